// Bulk elements: patch test (uniform stress under a linear displacement field, on irregular meshes,
// 2D and 3D) and objectivity (rigid rotation by 90 degrees: no stress; a pre-stressed block rotated
// by 90 degrees has its stress rotated with it).
#include <gtest/gtest.h>

#include <cmath>

#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

// Moves interior nodes of a generated mesh by up to `amp` times the cell size, deterministically.
void perturb_interior(HostMesh& mesh, const double* lo, const double* hi, double amp) {
  unsigned seed = 12345;
  const int D = mesh.dim;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    bool interior = true;
    for (int k = 0; k < D; ++k) {
      const double x = mesh.X[i * D + k];
      interior = interior && x > lo[k] + 1e-9 && x < hi[k] - 1e-9;
    }
    for (int k = 0; k < D; ++k) {
      const double r = fdem_test::prand(seed);
      if (interior) mesh.X[i * D + k] += amp * r;
    }
  }
}

// Sets x = map(X) on the device, computes forces and stresses.
template <int D, class Map>
void deform(Simulation<D>& sim, Map map, Kokkos::View<double* [6]>& stress) {
  auto X = Kokkos::create_mirror_view(sim.m.X);
  auto x = Kokkos::create_mirror_view(sim.m.x);
  Kokkos::deep_copy(X, sim.m.X);
  for (int i = 0; i < sim.m.nn; ++i) {
    double p[D], q[D];
    for (int k = 0; k < D; ++k) p[k] = X(i, k);
    map(p, q);
    for (int k = 0; k < D; ++k) x(i, k) = q[k];
  }
  Kokkos::deep_copy(sim.m.x, x);
  Kokkos::deep_copy(sim.m.f, 0.0);
  ForceScatter<D> sf(sim.m.f);
  compute_forces<D>(sim.m, sf);
  stress = Kokkos::View<double* [6]>("stress", sim.m.ne);
  element_stress<D>(sim.m, stress);
}

template <int D>
void expected_cauchy(const double (&F)[D][D], const Case& c, double (&s6)[6]) {
  const double E = c.materials[0].E, nu = c.materials[0].nu;
  double lam = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = E / (2 * (1 + nu));
  if (D == 2 && c.plane_stress) lam = 2 * lam * mu / (lam + 2 * mu);
  cauchy_stress<D>(F, lam, mu, c.plane_stress, s6);
}

template <int D>
void patch_test(HostMesh mesh, const double* lo, const double* hi, double h) {
  perturb_interior(mesh, lo, hi, (D == 2 ? 0.15 : 0.1) * h);
  auto c = fdem_test::basic_case(D);
  Simulation<D> sim(c, mesh);
  const double A[3][3] = {{1.0e-3, 2.0e-4, -3.0e-4}, {5.0e-4, -7.0e-4, 1.0e-4}, {2.0e-4, 3.0e-4, 6.0e-4}};
  Kokkos::View<double* [6]> stress;
  deform<D>(sim, [&](const double* p, double* q) {
    for (int i = 0; i < D; ++i) {
      q[i] = p[i];
      for (int j = 0; j < D; ++j) q[i] += A[i][j] * p[j];
    }
  }, stress);
  double F[D][D], s6[6];
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) F[i][j] = (i == j) + A[i][j];
  expected_cauchy<D>(F, c, s6);
  double smax = 0;
  for (double s : s6) smax = std::max(smax, std::fabs(s));
  auto s_h = Kokkos::create_mirror_view(stress);
  Kokkos::deep_copy(s_h, stress);
  double worst = 0;
  for (int e = 0; e < sim.m.ne; ++e)
    for (int k = 0; k < 6; ++k) worst = std::max(worst, std::fabs(s_h(e, k) - s6[k]));
  EXPECT_LT(worst / smax, 1e-11) << "stress not uniform";
  // Interior nodes are in equilibrium: their force vanishes to round-off.
  auto f = Kokkos::create_mirror_view(sim.m.f);
  Kokkos::deep_copy(f, sim.m.f);
  double fint = 0, fbnd = 0;
  for (int i = 0; i < sim.m.nn; ++i) {
    bool interior = true;
    for (int k = 0; k < D; ++k) {
      const double x = mesh.X[i * D + k];
      interior = interior && x > lo[k] + 0.3 * h && x < hi[k] - 0.3 * h;
    }
    for (int k = 0; k < D; ++k) (interior ? fint : fbnd) = std::max(interior ? fint : fbnd, std::fabs(f(i, k)));
  }
  EXPECT_GT(fbnd, 0.0);
  EXPECT_LT(fint / fbnd, 1e-10) << "interior nodes not in equilibrium";
}

TEST(Bulk, PatchTest2DIrregularMesh) {
  const double lo[2] = {0, 0}, hi[2] = {1, 1};
  patch_test<2>(generate_crossed_rectangle(0, 0, 1, 1, 5, 5), lo, hi, 0.2);
}

TEST(Bulk, PatchTest3DIrregularMesh) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  patch_test<3>(generate_box({0, 0, 0}, {1, 1, 1}, 4, 4, 4), lo, hi, 0.25);
}

template <int D>
void objectivity(HostMesh mesh) {
  auto c = fdem_test::basic_case(D);
  Simulation<D> sim(c, mesh);
  // rotation by 90 degrees about z (3D) / in the plane (2D)
  const double R[3][3] = {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}};
  Kokkos::View<double* [6]> stress;
  // 1. unstressed block, rigid rotation
  deform<D>(sim, [&](const double* p, double* q) {
    for (int i = 0; i < D; ++i) {
      q[i] = 0.3;  // plus a translation
      for (int j = 0; j < D; ++j) q[i] += R[i][j] * p[j];
    }
  }, stress);
  auto s_h = Kokkos::create_mirror_view(stress);
  Kokkos::deep_copy(s_h, stress);
  double worst = 0;
  for (int e = 0; e < sim.m.ne; ++e)
    for (int k = 0; k < 6; ++k) worst = std::max(worst, std::fabs(s_h(e, k)));
  EXPECT_LT(worst / c.materials[0].E, 1e-10);
  auto f = Kokkos::create_mirror_view(sim.m.f);
  Kokkos::deep_copy(f, sim.m.f);
  double fmax = 0;
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) fmax = std::max(fmax, std::fabs(f(i, k)));
  EXPECT_LT(fmax / c.materials[0].E, 1e-10);

  // 2. pre-stressed block (stretch A), then rotated: sigma' = R sigma R^T
  const double A[3][3] = {{2.0e-3, 1.0e-3, 0}, {1.0e-3, -1.0e-3, 5e-4}, {0, 5e-4, 1e-3}};
  double F[D][D], FR[D][D], s0[6], s1[6];
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) F[i][j] = (i == j) + A[i][j];
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      FR[i][j] = 0;
      for (int k = 0; k < D; ++k) FR[i][j] += R[i][k] * F[k][j];
    }
  expected_cauchy<D>(F, c, s0);
  deform<D>(sim, [&](const double* p, double* q) {
    for (int i = 0; i < D; ++i) {
      q[i] = 0;
      for (int j = 0; j < D; ++j) q[i] += FR[i][j] * p[j];
    }
  }, stress);
  Kokkos::deep_copy(s_h, stress);
  // rotate s0 by R: the rotation maps x->y, y->-x
  auto T = [](const double* s, int i, int j) {
    const int idx[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
    return s[idx[i][j]];
  };
  double rot[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      rot[i][j] = 0;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) rot[i][j] += R[i][k] * T(s0, k, l) * R[j][l];
    }
  const double want[6] = {rot[0][0], rot[1][1], rot[2][2], rot[0][1], rot[1][2], rot[0][2]};
  double smax = 0;
  for (double s : s0) smax = std::max(smax, std::fabs(s));
  worst = 0;
  for (int e = 0; e < sim.m.ne; ++e) {
    for (int k = 0; k < 6; ++k) s1[k] = s_h(e, k);
    for (int k = 0; k < 6; ++k) worst = std::max(worst, std::fabs(s1[k] - want[k]));
  }
  EXPECT_LT(worst / smax, 1e-10);
  EXPECT_GT(smax, 1e6);  // the block really is stressed
}

TEST(Bulk, RigidRotationIsStressFree2D) { objectivity<2>(generate_crossed_rectangle(0, 0, 1, 0.5, 4, 2)); }
TEST(Bulk, RigidRotationIsStressFree3D) { objectivity<3>(generate_box({0, 0, 0}, {1, 0.5, 0.5}, 3, 2, 2)); }

}  // namespace
