#pragma once
// Host-parallel loops for the set-up: building the model's host arrays before they are uploaded
// (solver/model_builder.cpp), and checks of them. The host execution space's threads run f(i) for i in [0, n); f
// runs on the host only (it may use std:: containers), writes nothing another i writes, and
// throws nothing. Launches live in kernels/ (docs/developing.md).
#include <Kokkos_Core.hpp>

namespace fdem {

template <class F>
void host_for(const char* name, int n, const F& f) {
  Kokkos::parallel_for(name, Kokkos::RangePolicy<Kokkos::DefaultHostExecutionSpace>(0, n), f);
}

// The sum over i in [0, n) of what f(i, sum) adds to sum (a long: counts), on the host's threads.
template <class F>
void host_reduce_sum(const char* name, int n, const F& f, long& sum) {
  Kokkos::parallel_reduce(name, Kokkos::RangePolicy<Kokkos::DefaultHostExecutionSpace>(0, n), f, sum);
}

}  // namespace fdem
