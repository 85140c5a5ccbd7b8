#include "common/view_memory.hpp"

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cstdint>
#include <map>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace fdem::view_memory {

namespace {

struct Alloc {
  std::string label;
  uint64_t bytes = 0;
};

// Views are made on the host thread of the run, but Kokkos' host backends allocate their own
// per-thread buffers from inside parallel regions: the hooks take a lock.
std::mutex g_lock;
bool g_enabled = false;
std::unordered_map<const void*, Alloc> g_live;
std::map<std::string, uint64_t> g_by_label;  // live bytes per label
uint64_t g_current = 0, g_peak = 0;
std::map<std::string, uint64_t> g_peak_by_label;  // g_by_label when g_current last reached g_peak

void on_allocate(const Kokkos_Profiling_SpaceHandle, const char* label, const void* ptr, const uint64_t size) {
  const std::string l = label ? label : "";
  const std::lock_guard<std::mutex> hold(g_lock);
  g_live[ptr] = Alloc{l, size};
  g_by_label[l] += size;
  g_current += size;
  if (g_current > g_peak) {
    g_peak = g_current;
    g_peak_by_label = g_by_label;
  }
}

void on_deallocate(const Kokkos_Profiling_SpaceHandle, const char*, const void* ptr, const uint64_t) {
  const std::lock_guard<std::mutex> hold(g_lock);
  auto it = g_live.find(ptr);
  if (it == g_live.end()) return;  // allocated before the hooks
  auto lb = g_by_label.find(it->second.label);
  if (lb != g_by_label.end()) {
    lb->second -= it->second.bytes;
    if (lb->second == 0) g_by_label.erase(lb);
  }
  g_current -= it->second.bytes;
  g_live.erase(it);
}

bool starts(const std::string& s, const char* p) { return s.rfind(p, 0) == 0; }

}  // namespace

void enable() {
  namespace T = Kokkos::Tools::Experimental;
  T::set_allocate_data_callback(on_allocate);
  T::set_deallocate_data_callback(on_deallocate);
  g_enabled = true;
}

bool enabled() { return g_enabled; }

std::string kind_of(const std::string& label) {
  if (starts(label, "fdem::contact::")) return "contact";
  if (starts(label, "fdem::fragments::")) return "fragments";
  if (starts(label, "fdem::halo::")) return "halo";
  // ScatterView's per-thread copies (host backends only) carry the scatter's label plus Kokkos' own
  if (label.find("scatter") != std::string::npos || label.find("Scatter") != std::string::npos ||
      label.find("duplicated") != std::string::npos)
    return "scatter";
  if (starts(label, "fdem::")) return "model";
  return "other";
}

nlohmann::json report(int largest) {
  const std::lock_guard<std::mutex> hold(g_lock);
  std::map<std::string, uint64_t> kinds;
  for (const auto& [l, b] : g_peak_by_label) kinds[kind_of(l)] += b;
  std::vector<std::pair<std::string, uint64_t>> v(g_peak_by_label.begin(), g_peak_by_label.end());
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  nlohmann::json top = nlohmann::json::array();
  for (int i = 0; i < static_cast<int>(v.size()) && i < largest; ++i)
    top.push_back({{"label", v[i].first}, {"bytes", v[i].second}});
  return {{"peak_bytes", g_peak}, {"current_bytes", g_current}, {"peak_by_kind", kinds}, {"largest", top}};
}

}  // namespace fdem::view_memory
