#pragma once
// The memory of a run's Kokkos Views (the data a GPU run holds on the device): Kokkos' allocation
// hooks, registered in-process, tally every allocation by its label's kind, and keep the kinds'
// sizes at the moment the total peaked. On host backends the same Views are allocated, except
// the scatter's per-thread copies (kind `scatter`; a GPU adds with atomics instead), so a run
// on OpenMP measures what the device would hold (docs/performance.md, "Device memory").
#include <nlohmann/json.hpp>

#include <string>

namespace fdem::view_memory {

// Registers the hooks (after Kokkos is initialised; replaces any other in-process allocation hooks).
void enable();
bool enabled();
// The kind of a View's label: model, contact, fragments, halo, scatter or other.
std::string kind_of(const std::string& label);
// {peak_bytes, current_bytes, peak_by_kind: {kind: bytes}, largest: [{label, bytes}] at the peak}.
nlohmann::json report(int largest = 12);

}  // namespace fdem::view_memory
