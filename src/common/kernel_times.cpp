#include "common/kernel_times.hpp"

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <unordered_map>
#include <vector>

namespace fdem::kernel_times {

namespace {

using Clock = std::chrono::steady_clock;

struct Entry {
  long calls = 0;
  double seconds = 0;
};

struct Open {
  std::string name;
  Clock::time_point start;
};

// The hooks are called from the thread that launches (the host thread of the run).
bool g_enabled = false;
std::unordered_map<std::string, Entry> g_entries;
std::vector<Open> g_open;  // indexed by the kernel id the begin hook hands out

void begin(const char* name, uint32_t, uint64_t* kid) {
  size_t slot = 0;
  while (slot < g_open.size() && !g_open[slot].name.empty()) ++slot;
  if (slot == g_open.size()) g_open.emplace_back();
  g_open[slot].name = name ? name : "(unnamed)";
  g_open[slot].start = Clock::now();
  *kid = slot;
}

void end(uint64_t kid) {
  if (kid >= g_open.size() || g_open[kid].name.empty()) return;
  Entry& e = g_entries[g_open[kid].name];
  e.calls += 1;
  e.seconds += std::chrono::duration<double>(Clock::now() - g_open[kid].start).count();
  g_open[kid].name.clear();
}

}  // namespace

void enable() {
  namespace T = Kokkos::Tools::Experimental;
  T::set_begin_parallel_for_callback(begin);
  T::set_end_parallel_for_callback(end);
  T::set_begin_parallel_reduce_callback(begin);
  T::set_end_parallel_reduce_callback(end);
  T::set_begin_parallel_scan_callback(begin);
  T::set_end_parallel_scan_callback(end);
  g_enabled = true;
}

bool enabled() { return g_enabled; }

nlohmann::json report() {
  std::vector<std::pair<std::string, Entry>> v(g_entries.begin(), g_entries.end());
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.second.seconds > b.second.seconds; });
  double total = 0;
  for (const auto& [n, e] : v) total += e.seconds;
  nlohmann::json out = nlohmann::json::array();
  for (const auto& [n, e] : v)
    out.push_back({{"name", n}, {"calls", e.calls}, {"seconds", e.seconds},
                   {"share", total > 0 ? e.seconds / total : 0.0}});
  return out;
}

void print(int top) {
  const nlohmann::json r = report();
  double total = 0;
  for (const auto& k : r) total += k["seconds"].get<double>();
  std::printf("kernel times (%.3f s in %zu kernels):\n  %-48s %10s %12s %10s %7s\n", total, r.size(), "kernel",
              "calls", "seconds", "us/call", "share");
  int shown = 0;
  for (const auto& k : r) {
    if (shown++ >= top) break;
    const double s = k["seconds"].get<double>();
    const long c = k["calls"].get<long>();
    std::printf("  %-48s %10ld %12.3f %10.1f %6.1f%%\n", k["name"].get<std::string>().c_str(), c, s,
                c > 0 ? 1e6 * s / c : 0.0, 100.0 * k["share"].get<double>());
  }
  std::fflush(stdout);
}

}  // namespace fdem::kernel_times
