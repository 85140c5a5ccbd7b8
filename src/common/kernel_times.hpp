#pragma once
// Time spent in each named Kokkos kernel of a run (`fdem run --kernel-times`): Kokkos' profiling
// hooks, registered in-process, time every parallel_for / parallel_reduce / parallel_scan from
// its begin to its end, by kernel name. On host backends a kernel has finished when its launch
// returns, so the times are the kernels' own; on GPUs launches return at once (set
// CUDA_LAUNCH_BLOCKING=1 for kernel times there). The hooks cost a clock read per launch; off by
// default.
#include <nlohmann/json.hpp>

namespace fdem::kernel_times {

// Registers the hooks (after Kokkos is initialised; replaces any other in-process hooks).
void enable();
bool enabled();
// Per kernel: name, calls, seconds, share of the timed total; largest first.
nlohmann::json report();
// The report as a table on stdout (the `top` largest kernels).
void print(int top = 25);

}  // namespace fdem::kernel_times
