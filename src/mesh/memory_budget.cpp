// Memory budget: what the machine (and the limits put on this process) leaves, and what an element
// costs. See memory_budget.hpp.
#include "mesh/memory_budget.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "common/error.hpp"

namespace fdem {

namespace {

// "Key:   1234 kB" lines of /proc/meminfo or /proc/self/status, in bytes; < 0 if absent.
double proc_kb_field(const char* file, const std::string& key) {
  std::ifstream f(file);
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream s(line.substr(key.size() + 1));
      double kb = -1;
      if (s >> kb) return kb * 1024.0;
    }
  return -1;
}

// A number in a cgroup file; < 0 if absent or "max" (no limit).
double cgroup_number(const std::string& file) {
  std::ifstream f(file);
  std::string text;
  if (!(f >> text) || text == "max") return -1;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !(v >= 0) || v > 1e18) return -1;  // v1 writes ~9.2e18 for "none"
  return v;
}

// The cgroup v2 folder of this process ("" if not on cgroup v2).
std::string cgroup2_dir() {
  std::ifstream f("/proc/self/cgroup");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("0::", 0) == 0) return "/sys/fs/cgroup" + line.substr(3);
  return "";
}

void lower(MemoryBudget& b, double bytes, const std::string& source) {
  if (bytes < 0) return;
  if (b.bytes <= 0 || bytes < b.bytes) {
    b.bytes = std::max(bytes, 1.0);
    b.source = source;
  }
}

std::string gib(double bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return buf;
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

bool checks_off() {
  const char* e = std::getenv("FDEM_MEMORY_CHECK");
  return e && (std::string(e) == "off" || std::string(e) == "0");
}

}  // namespace

MemoryBudget available_memory() {
  MemoryBudget b;
  if (const char* e = std::getenv("FDEM_MEMORY_LIMIT_GB")) {
    char* end = nullptr;
    const double g = std::strtod(e, &end);
    if (end != e && g > 0 && std::isfinite(g)) {
      b.bytes = g * 1024.0 * 1024.0 * 1024.0;
      b.source = "FDEM_MEMORY_LIMIT_GB=" + std::string(e);
      return b;
    }
  }
  double phys = proc_kb_field("/proc/meminfo", "MemAvailable");
  std::string phys_source = "MemAvailable in /proc/meminfo";
  if (phys < 0) {
    const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) phys = static_cast<double>(pages) * static_cast<double>(page);
    phys_source = "available physical memory (sysconf)";
  }
  lower(b, phys, phys_source);
  const std::string v2 = cgroup2_dir();
  if (!v2.empty()) {
    const double max = cgroup_number(v2 + "/memory.max");
    const double cur = cgroup_number(v2 + "/memory.current");
    if (max >= 0) lower(b, max - std::max(cur, 0.0), "cgroup limit " + v2 + "/memory.max less usage");
  }
  {
    const std::string v1 = "/sys/fs/cgroup/memory/";
    const double max = cgroup_number(v1 + "memory.limit_in_bytes");
    const double cur = cgroup_number(v1 + "memory.usage_in_bytes");
    if (max >= 0) lower(b, max - std::max(cur, 0.0), "cgroup limit memory.limit_in_bytes less usage");
  }
  rlimit rl{};
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
    const double used = std::max(proc_kb_field("/proc/self/status", "VmSize"), 0.0);
    lower(b, static_cast<double>(rl.rlim_cur) - used, "RLIMIT_AS (ulimit -v) less the address space in use");
  }
  return b;
}

// Peak resident memory of `fdem run` (300 steps, interfaces on every face, contact on, snapshots)
// less that of the smallest mesh, per element, measured with /usr/bin/time -v on
// cases/uniaxial_compression (2D: 3200 -> 51200 elements) and cases/particle_impact_3d (3D), and
// rounded up with 50 % headroom for contact pair lists that grow as a body fragments. Gmsh's own
// peak while meshing a disc or sphere is below it. Figures: docs/developing.md, "Refusals".
// Checked against the set-up measures of docs/performance-impact.md, section 4: the 3D impact at
// 1e5 and 1e6 tetrahedra peaks at 2.8 and 2.3 kB per tetrahedron (2.2 kB from one to the other),
// Gmsh's child process at 0.6 kB: 4300 B still covers them with the headroom for contact.
double bytes_per_element(int dim) { return dim == 2 ? 2700.0 : 4300.0; }

// Elements per (measure / h^dim) that Gmsh made with the generators' settings (gmsh_io.cpp), the
// largest counted: discs R / h = 17, 50, 100: 2.70, 2.67, 2.60; spheres R / h = 8.3, 10, 16.7:
// 5.19, 4.86, 4.65 (docs/developing.md, "Refusals").
double estimate_gmsh_elements(int dim, double measure, double h) {
  const double per_measure = dim == 2 ? 2.7 : 5.2;
  return per_measure * measure / std::pow(h, dim);
}

double max_elements(int dim) {
  if (checks_off()) return std::numeric_limits<double>::infinity();
  const MemoryBudget b = available_memory();
  if (!(b.bytes > 0)) return std::numeric_limits<double>::infinity();
  return b.bytes / bytes_per_element(dim);
}

void check_fits_in_memory(double elements, int dim, const std::string& request, double size,
                          const std::string& size_key, double at_unit_size) {
  if (checks_off()) return;
  const MemoryBudget b = available_memory();
  if (!(b.bytes > 0)) return;
  const double per = bytes_per_element(dim);
  const double need = elements * per;
  if (need <= b.bytes && std::isfinite(need)) return;
  const double cap = b.bytes / per;
  const std::string count = std::isfinite(elements)
                                ? "about " + num(elements) + " elements, which need about " + gib(need)
                                : std::string("more elements than a double counts");
  std::string msg = request + " would make " + count + " (" + num(per) + " bytes per element over a run); " +
                    gib(b.bytes) + " is available (" + b.source + "), enough for about " + num(cap) +
                    " elements";
  if (size > 0 && std::isfinite(size) && elements > 0) {
    double smallest = size * std::pow(elements / cap, 1.0 / dim);
    if (!std::isfinite(smallest) && at_unit_size > 0)  // elements overflowed at this size
      smallest = std::pow(at_unit_size / cap, 1.0 / dim);
    if (smallest > 0 && std::isfinite(smallest))
      msg += ": give " + size_key + " >= " + num(smallest) + " m";
    else if (at_unit_size > 0)  // the model's measure itself overflows
      msg += ": no " + size_key + " makes it fit: the model is beyond double precision";
    else
      msg += ": give a far larger " + size_key + " (this one's count overflows a double)";
  }
  msg += " (FDEM_MEMORY_CHECK=off skips this check)";
  throw InputError(msg);
}

}  // namespace fdem
