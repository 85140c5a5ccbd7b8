#pragma once
// Transparent huge pages for the heap (docs/performance-impact.md, section 4, "Huge pages"): the
// set-up of a large mesh is mostly first touches of freshly allocated memory, each a page fault;
// with glibc's malloc tunable glibc.malloc.hugetlb=1 (glibc 2.35 and later) malloc asks the kernel
// for transparent huge pages on its memory (madvise), and where the kernel gives them on request
// (/sys/kernel/mm/transparent_hugepage/enabled "madvise") a fault maps 2 MiB instead of 4 KiB.
// glibc reads its tunables when a program loads, so fdem sets it and starts itself again once
// (src/app/main.cpp). Host only.
#include <string>

namespace fdem {

// The kernel's transparent huge page mode: "always", "madvise", "never", or "" where it cannot be
// read (not Linux, no such file).
std::string transparent_huge_pages_mode();

// Whether this process's malloc asks for huge pages (GLIBC_TUNABLES holds glibc.malloc.hugetlb=1).
bool malloc_asks_huge_pages();

// For `fdem info` and summary.json: "on (glibc.malloc.hugetlb=1, kernel mode madvise)", "on (kernel
// mode always)", or "off (...)" with why.
std::string huge_pages_state();

// Before the program's own work: sets GLIBC_TUNABLES to ask for huge pages where it helps (the
// kernel's mode is madvise, glibc is 2.35 or later, not an address-sanitized build, the user has
// not set glibc.malloc.hugetlb nor FDEM_HUGE_PAGES=0); true when it did, so that the program must
// start again for glibc to read it.
bool ask_for_huge_pages();

// Gives the heap's free memory back to the kernel (glibc's malloc_trim; elsewhere nothing): after
// the set-up frees its host mesh, whose pages malloc would otherwise keep (resident) for the
// run's later small allocations, while the large ones (the Views, the contact lists as they grow)
// take fresh pages. Returns the resident bytes it gave back (-1 where unknown).
double release_free_heap();

}  // namespace fdem
