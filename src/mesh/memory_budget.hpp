#pragma once
// How many elements this machine can hold: the memory a process may still use (physical memory,
// cgroup limit, RLIMIT_AS) against the bytes one element costs over a whole run (mesh, model,
// interfaces, contact, outputs; measured, see memory_budget.cpp). Meshes that cannot fit are
// refused before they are generated, meshed or allocated.
#include <string>

namespace fdem {

struct MemoryBudget {
  double bytes = 0;    // memory still available to this process; <= 0: unknown (no check)
  std::string source;  // where the figure comes from ("MemAvailable in /proc/meminfo", ...)
};

// The smallest of: MemAvailable (/proc/meminfo, else sysconf), the cgroup's memory limit less its
// usage (v2 memory.max - memory.current, v1 memory.limit_in_bytes - memory.usage_in_bytes) and
// RLIMIT_AS less the address space in use. FDEM_MEMORY_LIMIT_GB=<x> replaces it by x GiB;
// FDEM_MEMORY_CHECK=off turns every check off (experts: the estimates are upper bounds).
MemoryBudget available_memory();

// Bytes per element (peak resident memory over a run with interfaces on every face and contact,
// per element): 2D triangles, 3D tetrahedra. Also covers Gmsh's peak while it meshes.
double bytes_per_element(int dim);

// Elements Gmsh makes (Delaunay, as set up in gmsh_io.cpp) in an area (2D) or volume (3D) of
// `measure` at element size h: about c * measure / h^dim, with c counted on discs and spheres.
double estimate_gmsh_elements(int dim, double measure, double h);

// Largest element count the budget allows (infinity when unknown or checks are off).
double max_elements(int dim);

// Throws InputError when `elements` elements (dimension dim) cannot fit in the available memory.
// `request` names what asked for them (e.g. "mesh.element_size = 1e-05 m (4 x 5000 x 10000
// cells)"); `size` > 0: the element size that gives them, so that the message can state the
// smallest size that fits, under the name `size_key`; where a tiny size makes `elements` overflow
// (it said "give mesh.element_size >= inf m"), from `at_unit_size` if given: the count at size 1
// (elements times size^dim); the message says when no size fits.
void check_fits_in_memory(double elements, int dim, const std::string& request, double size = 0,
                          const std::string& size_key = "mesh.element_size", double at_unit_size = 0);

}  // namespace fdem
