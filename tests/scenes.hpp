#pragma once
// Scene set-up shared by the tests and the benchmarks (perf/ includes this file too): changes to a
// built Simulation that put it into a state worth testing or timing.
#include <Kokkos_Core.hpp>

#include "kernels/model.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace fdem_test {

// A host copy of a View's current contents (the View itself where it is host memory already).
template <class V>
typename V::HostMirror host_view(const V& v) {
  auto h = Kokkos::create_mirror_view(v);
  Kokkos::deep_copy(h, v);
  return h;
}

// The first time a monitored value `a` (at time t) reaches `level`, interpolated linearly from
// `prev` (at time tprev): sets t_cross once (while it is < 0).
inline void front_crossing(double a, double prev, double t, double tprev, double level, double& t_cross) {
  if (t_cross < 0 && a >= level) t_cross = tprev + (t - tprev) * (level - prev) / (a - prev);
}

// Every interface failed (damage 1 at all points, no fracture energy: the scene starts from cracked
// pieces), then handed over to contact; the next step is the energy reference.
template <int D>
void fail_all_interfaces(fdem::Simulation<D>& sim) {
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  for (int q = 0; q < sim.m.ni; ++q)
    for (int k = 0; k < D; ++k) fdem::store_point(h, q, k, fdem::CohesivePoint{1.0, 0.5, 1.0, 0.0});
  Kokkos::deep_copy(sim.m.ihist, h);
  sim.contact()->check_failures(sim.m);
  sim.reset_energy_reference();
}

// Adds amp * (pseudo-random in [-1, 1]) to every velocity component (the same sequence for the same
// seed); the next step is the energy reference.
template <int D>
void shake(fdem::Simulation<D>& sim, double amp, unsigned seed = 12345) {
  auto v = Kokkos::create_mirror_view(sim.m.v);
  Kokkos::deep_copy(v, sim.m.v);
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) v(i, k) += amp * prand(seed);
  Kokkos::deep_copy(sim.m.v, v);
  sim.reset_energy_reference();
}

}  // namespace fdem_test
