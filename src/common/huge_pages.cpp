// Transparent huge pages for the heap (huge_pages.hpp): the kernel's mode, glibc's tunable; and
// the heap's free pages given back.
#include "common/huge_pages.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdlib>
#include <fstream>
#include <string>

#include "common/setup_times.hpp"

namespace fdem {

namespace {

constexpr const char* kTunable = "glibc.malloc.hugetlb";

// glibc 2.35 added the tunable; an address sanitizer replaces malloc (the tunable would do nothing).
constexpr bool kGlibcHasTunable =
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 35)) && \
    !defined(__SANITIZE_ADDRESS__)
    true;
#else
    false;
#endif

std::string tunables() {
  const char* t = std::getenv("GLIBC_TUNABLES");
  return t ? t : "";
}

}  // namespace

std::string transparent_huge_pages_mode() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!f || !std::getline(f, line)) return "";
  // e.g. "always [madvise] never": the mode in brackets
  const size_t a = line.find('['), b = line.find(']');
  return a == std::string::npos || b == std::string::npos || b < a ? "" : line.substr(a + 1, b - a - 1);
}

bool malloc_asks_huge_pages() {
  const std::string t = tunables();
  const size_t at = t.find(std::string(kTunable) + "=");
  return at != std::string::npos && t.compare(at + std::string(kTunable).size() + 1, 1, "1") == 0;
}

std::string huge_pages_state() {
  const std::string mode = transparent_huge_pages_mode();
  if (mode == "always") return "on (kernel mode always)";
  if (mode == "madvise" && malloc_asks_huge_pages()) return "on (glibc.malloc.hugetlb=1, kernel mode madvise)";
  if (mode == "madvise") return "off (kernel mode madvise; malloc does not ask: FDEM_HUGE_PAGES=0, or glibc)";
  return "off (kernel mode " + (mode.empty() ? std::string("unknown") : mode) + ")";
}

bool ask_for_huge_pages() {
  if (!kGlibcHasTunable) return false;
  const char* off = std::getenv("FDEM_HUGE_PAGES");
  if (off && std::string(off) == "0") return false;
  if (transparent_huge_pages_mode() != "madvise") return false;  // (always: every process has them)
  std::string t = tunables();
  if (t.find(kTunable) != std::string::npos) return false;  // (the user's choice)
  t += (t.empty() ? "" : ":") + std::string(kTunable) + "=1";
  return setenv("GLIBC_TUNABLES", t.c_str(), 1) == 0;
}

double release_free_heap() {
  const double before = setup_times::rss_bytes();
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
  const double after = setup_times::rss_bytes();
  return before >= 0 && after >= 0 ? before - after : -1.0;
}

}  // namespace fdem
