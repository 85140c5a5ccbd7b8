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

// Interfaces q with pick(q) failed (damage 1 at all points, no fracture energy), not handed over:
// the force kernel flags them and the contact system hands them over at its next check.
template <int D, class Pick>
void fail_interfaces(fdem::Simulation<D>& sim, Pick pick) {
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  Kokkos::deep_copy(h, sim.m.ihist);
  for (int q = 0; q < sim.m.ni; ++q)
    if (pick(q))
      for (int k = 0; k < D; ++k) fdem::store_point(h, q, k, fdem::CohesivePoint{1.0, 0.5, 1.0, 0.0});
  Kokkos::deep_copy(sim.m.ihist, h);
}

// Every interface failed (the scene starts from cracked pieces), then handed over to contact; the
// next step is the energy reference.
template <int D>
void fail_all_interfaces(fdem::Simulation<D>& sim) {
  fail_interfaces(sim, [](int) { return true; });
  sim.contact()->check_failures(sim.m);
  sim.reset_energy_reference();
}

// A 40 mm square or cube of n x n (x n) cells with interfaces everywhere.
template <int D>
fdem::HostMesh cracked_block(int n) {
  fdem::HostMesh m = D == 2 ? fdem::generate_crossed_rectangle(0, 0, 0.04, 0.04, n, n, "body")
                            : fdem::generate_box({0, 0, 0}, {0.04, 0.04, 0.04}, n, n, n, "body");
  fdem::insert_interfaces(m, {true});
  return m;
}

// The cracked block (strong interfaces: none fails by itself) on a fixed base under gravity, pressed
// by a friction platen from above, contact with friction; skin: the Verlet skin (0: derived).
template <int D>
fdem::Case pressed_case(double skin = 0) {
  auto c = basic_case(D, 1e7, 0.25, 2000);
  c.interface_materials = {strong_interface(2e7 / 0.01, 0.8e7 / 0.01)};
  c.fracture_material = 0;
  c.contact.enabled = 1;
  c.contact.friction = 0.5;
  c.contact.skin = skin;
  fdem::VelocityBC fix;
  fix.set = D == 2 ? "ymin" : "zmin";
  fix.active = {true, true, true};
  c.velocity_bcs = {fix};
  c.gravity = {0, 0, 0};
  c.gravity[D - 1] = -9.81;
  fdem::PlatenSpec p;
  p.name = "top";
  p.point[D - 1] = 0.0401;
  p.normal[D - 1] = -1.0;
  p.velocity[D - 1] = -0.05;
  p.friction = 0.3;
  c.platens = {p};
  return c;
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
