// The force pass's two shapes (kernels/forces.hpp): on host backends one fused kernel over element
// chunks with their interfaces, on GPUs (and wherever Model::ichunk is absent) a bulk kernel and an
// interface kernel. Both must give the same nodal forces (to round-off: the scatter adds in
// another order) and exactly the same interface histories, with and without residual friction.
// Host backends run both shapes, so the GPU's shape is checked here without a GPU. The host's
// fused pass takes its items kLanes at a time (Lanes, kernels/lanes.hpp): that must give the same
// forces and histories to the bit as one at a time, whatever mix of intact, initiating, softening
// and failed interfaces a batch holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "scenes.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

// A cracked block whose interfaces initiate and soften under the displacement field below.
template <int D>
Case weak_case(bool friction, bool scatter = false) {
  auto c = fdem_test::basic_case(D);
  auto im = fdem_test::strong_interface(33e9 / (0.1 * 0.01), 13e9 / (0.1 * 0.01));
  im.ft = 2e6;
  im.c = 4e6;
  im.phi = 0.6;
  im.Gnc = 5;
  im.Gsc = 50;
  im.residual_friction = friction;
  im.phi_r = 0.5;
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.contact.enabled = 0;
  if (scatter) {  // per-interface strengths: the force kernel's PerIface shape
    c.scatter.distribution = "weibull";
    c.scatter.modulus = 3;
  }
  return c;
}

// x = X + u with u a smooth stretch plus a pseudo-random part of amplitude amp, on the device;
// turned by rot radians about the z axis after that
template <int D>
void displace(Simulation<D>& sim, double amp, double rot = 0) {
  auto X = Kokkos::create_mirror_view(sim.m.X);
  auto x = Kokkos::create_mirror_view(sim.m.x);
  Kokkos::deep_copy(X, sim.m.X);
  unsigned seed = 777;
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) x(i, k) = X(i, k) * (1 + 2e-4 * (k + 1)) + amp * fdem_test::prand(seed);
  const double c = std::cos(rot), s = std::sin(rot);
  for (int i = 0; i < sim.m.nn; ++i) {
    const double x0 = x(i, 0), x1 = x(i, 1);
    x(i, 0) = c * x0 - s * x1;
    x(i, 1) = s * x0 + c * x1;
  }
  Kokkos::deep_copy(sim.m.x, x);
}

struct Pass {
  std::vector<double> f, hist;
  double fmax = 0;
  int softening = 0, failed = 0;
};

enum class Shape { split, fused, fused_one_at_a_time, fused_mixed };

// unload: one more call at half the last amplitude, so that initiated points are below their
// largest separation (their damage stays: the lanes' own path for them).
template <int D>
Pass force_pass(Shape shape, bool friction, int calls, bool scatter = false, double amp = 4e-6, bool unload = false,
                double rot = 0) {
  Simulation<D> sim(weak_case<D>(friction, scatter), fdem_test::cracked_block<D>(D == 2 ? 8 : 4));
  EXPECT_GT(sim.m.ni, 0);
  EXPECT_EQ(sim.m.has_slip(), friction);
  EXPECT_EQ(sim.m.per_interface(), scatter);
  Model<D> m = sim.m;  // a shallow copy (the same Views)
  m.mixed_precision = shape == Shape::fused_mixed;
  if (shape == Shape::split) m.ichunk = Kokkos::View<int*>();
  else EXPECT_EQ(static_cast<int>(m.ichunk.extent(0)), (m.ne + kChunk - 1) / kChunk + 1) << "not the fused shape";
  Pass p;
  for (int c = 0; c < calls + (unload ? 1 : 0); ++c) {  // the history evolves from call to call
    displace(sim, c < calls ? amp * (c + 1) : 0.5 * amp * calls, rot);
    Kokkos::deep_copy(sim.m.f, 0.0);
    ForceScatter<D> sf(sim.m.f);
    compute_forces<D>(m, sf, true, shape != Shape::fused_one_at_a_time);
  }
  auto f = Kokkos::create_mirror_view(sim.m.f);
  Kokkos::deep_copy(f, sim.m.f);
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  Kokkos::deep_copy(h, sim.m.ihist);
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) {
      p.f.push_back(f(i, k));
      p.fmax = std::max(p.fmax, std::fabs(f(i, k)));
    }
  for (int q = 0; q < sim.m.ni; ++q)
    for (int k = 0; k < D; ++k) {
      for (int j = 0; j < kPointHistory; ++j) p.hist.push_back(h(q, k, j));
      p.softening += h(q, k, 1) > 0;  // dm0 > 0: initiated
      p.failed += h(q, k, 0) >= h(q, k, 2) && h(q, k, 1) > 0;  // dmax >= dmf: failed
    }
  return p;
}

template <int D>
void same_forces(bool friction) {
  const Pass fused = force_pass<D>(Shape::fused, friction, 3), split = force_pass<D>(Shape::split, friction, 3);
  ASSERT_EQ(fused.f.size(), split.f.size());
  ASSERT_GT(fused.fmax, 0.0);
  EXPECT_GT(fused.softening, 10) << "the scene should soften interfaces";
  double worst = 0;
  for (size_t i = 0; i < fused.f.size(); ++i) worst = std::max(worst, std::fabs(fused.f[i] - split.f[i]));
  EXPECT_LE(worst, 1e-12 * fused.fmax) << "largest force " << fused.fmax;
  ASSERT_EQ(fused.hist.size(), split.hist.size());
  int differ = 0;
  for (size_t i = 0; i < fused.hist.size(); ++i) differ += fused.hist[i] != split.hist[i];
  EXPECT_EQ(differ, 0);
}

TEST(ForceKernels, SplitEqualsFused2D) { same_forces<2>(false); }
TEST(ForceKernels, SplitEqualsFused3D) { same_forces<3>(false); }
TEST(ForceKernels, SplitEqualsFusedWithFriction3D) { same_forces<3>(true); }

// The fused pass in lanes against one item at a time: every force and history value the same bits,
// on a scene whose batches mix intact interfaces with initiating, softening and failed ones, and
// then, unloaded, initiated interfaces whose damage stays.
template <int D>
void lanes_same_bits(bool friction, bool scatter) {
  const double amp = 1.2e-5;  // enough for some points to fail within the three calls
  const Pass a = force_pass<D>(Shape::fused, friction, 3, scatter, amp, true);
  const Pass b = force_pass<D>(Shape::fused_one_at_a_time, friction, 3, scatter, amp, true);
  ASSERT_EQ(a.f.size(), b.f.size());
  ASSERT_GT(a.fmax, 0.0);
  const int points = static_cast<int>(a.hist.size()) / kPointHistory;
  EXPECT_GT(a.softening, points / 10) << "the scene should soften interfaces";
  EXPECT_GT(points - a.softening, points / 10) << "some points should stay intact (the lanes' own path)";
  EXPECT_GT(a.failed, 0) << "some points should fail";
  int fdiff = 0, hdiff = 0;
  for (size_t i = 0; i < a.f.size(); ++i) fdiff += a.f[i] != b.f[i];
  ASSERT_EQ(a.hist.size(), b.hist.size());
  for (size_t i = 0; i < a.hist.size(); ++i) hdiff += a.hist[i] != b.hist[i];
  EXPECT_EQ(fdiff, 0) << "of " << a.f.size() << " force components";
  EXPECT_EQ(hdiff, 0) << "of " << a.hist.size() << " history values";
}

TEST(ForceKernels, LanesGiveTheSameBits2D) { lanes_same_bits<2>(false, false); }
TEST(ForceKernels, LanesGiveTheSameBits3D) { lanes_same_bits<3>(false, false); }
TEST(ForceKernels, LanesGiveTheSameBitsWithFrictionAndScatter3D) { lanes_same_bits<3>(true, true); }
TEST(ForceKernels, LanesGiveTheSameBitsWithScatter2D) { lanes_same_bits<2>(false, true); }

}  // namespace

// precision "mixed" (Model::mixed_precision): the lanes in floats. Against the double pass on the
// same scene (batches of intact, initiating, softening, failed and unloading interfaces), straight
// and turned by a whole radian (the bulk's strain from H = F - I: rounding of order 6e-8 |H|, |H| of
// order the rotation): every force component within 1e-5 of the largest force (measured: 1.2e-7
// in 2D, 1.5e-7 in 3D, 1.5e-6 turned), and the histories (computed in double from the same
// decisions) the same but for a decision taken at its threshold.
template <int D>
void mixed_close(double rot) {
  const double amp = 1.2e-5;
  const Pass a = force_pass<D>(Shape::fused, false, 3, false, amp, true, rot);
  const Pass b = force_pass<D>(Shape::fused_mixed, false, 3, false, amp, true, rot);
  ASSERT_EQ(a.f.size(), b.f.size());
  ASSERT_GT(a.fmax, 0.0);
  EXPECT_GT(a.softening, 10) << "the scene should soften interfaces";
  double worst = 0;
  int fdiff = 0;
  for (size_t i = 0; i < a.f.size(); ++i) {
    worst = std::max(worst, std::fabs(a.f[i] - b.f[i]));
    fdiff += a.f[i] != b.f[i];
  }
  EXPECT_LE(worst, 1e-5 * a.fmax) << "largest force " << a.fmax;
  EXPECT_GT(fdiff, static_cast<int>(a.f.size()) / 2) << "the mixed pass should compute in floats";
  ASSERT_EQ(a.hist.size(), b.hist.size());
  int hdiff = 0;
  for (size_t i = 0; i < a.hist.size(); ++i) hdiff += std::fabs(a.hist[i] - b.hist[i]) > 1e-9 * std::fabs(a.hist[i]);
  EXPECT_LE(hdiff, static_cast<int>(a.hist.size()) / 100) << "of " << a.hist.size() << " history values";
}

TEST(ForceKernels, MixedPrecisionIsCloseToDouble2D) { mixed_close<2>(0.0); }
TEST(ForceKernels, MixedPrecisionIsCloseToDouble3D) { mixed_close<3>(0.0); }
TEST(ForceKernels, MixedPrecisionIsCloseToDoubleTurned3D) { mixed_close<3>(1.0); }
