// Particle impact physics on small meshes, from the shipped case files (cases/particle_impact_2d,
// cases/particle_impact_3d) with coarse element sizes and short end times:
// - momentum is conserved before the plate is reached and while fragments fly freely, and
//   changes through the impact by exactly the plate's impulse (its force integrated over time);
// - the total mass of the fragments equals the particle's mass;
// - below a threshold speed the particle rebounds intact, above it it breaks;
// - the largest fragment's mass fraction falls as the speed rises.
#include <gtest/gtest.h>

#include <sys/types.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "solver/fragment_analysis.hpp"
#include "solver/run.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;
namespace fs = std::filesystem;

const std::string kCase2D = std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_2d/case.json";
const std::string kCase3D = std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_3d/case.json";

// The solver's mesh of a case: built, renumbered for locality, interfaces inserted (as `fdem run`).
HostMesh case_mesh(const Case& c) {
  HostMesh mesh = build_mesh(c.mesh, c.dim);
  reorder_for_locality(mesh);
  std::vector<bool> frac(mesh.region_names.size(), false);
  for (const auto& r : c.fracturable_regions) frac[mesh.region_index(r)] = true;
  insert_interfaces(mesh, frac);
  return mesh;
}

template <int D>
double mesh_mass(const HostMesh& m, double rho, double thickness) {
  double total = 0;
  for (int e = 0; e < m.num_elems(); ++e) {
    double x[D + 1][D];
    for (int a = 0; a < D + 1; ++a)
      for (int k = 0; k < D; ++k) x[a][k] = m.X[static_cast<size_t>(m.elems[e * (D + 1) + a]) * D + k];
    if constexpr (D == 2) {
      total += rho * thickness * 0.5 *
               std::fabs((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]));
    } else {
      double a[3], b[3], c[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = x[1][k] - x[0][k];
        b[k] = x[2][k] - x[0][k];
        c[k] = x[3][k] - x[0][k];
      }
      total += rho * std::fabs(a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                               a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
  }
  return total;
}

// Runs a case through the same path as `fdem run` (quietly, into a temporary folder) and returns
// its summary.
nlohmann::json run_quiet(const std::string& path, const std::vector<std::string>& overrides,
                         const std::string& tag) {
  RunOptions opt;
  opt.overrides = overrides;
  opt.progress = false;
  opt.out_dir = (fs::temp_directory_path() / ("fdem_impact_" + tag + "_" + std::to_string(::getpid()))).string();
  auto s = run_case(path, opt);
  fs::remove_all(opt.out_dir);
  return s;
}

// Momentum through an impact, step by step: constant before contact and after the fragments
// have left the plate, and P(N) - P(0) = plate impulse = sum of dt (F_n + F_{n+1}) / 2 (the
// leap-frog's momentum at x(n) is sum m (v(n-1/2) + v(n+1/2)) / 2; dt of each F_n: its velocity
// step, which differs from the step before and after on the step where contact's stable step
// applies).
template <int D>
void momentum_through_impact(const std::string& path, const std::vector<std::string>& overrides,
                             int min_fragments, int max_fragments) {
  const Case c = load_case(path, overrides);
  const HostMesh mesh = case_mesh(c);
  Simulation<D> sim(c, mesh);
  const int up = D - 1;  // the plate's normal
  std::vector<double> force;  // platen force along each axis, per step
  std::vector<std::array<double, 3>> F;
  std::vector<std::array<double, 3>> P;
  std::vector<long> sampled;
  std::vector<double> DT;  // each step's velocity step (the step shortens once interfaces fail)
  auto sample = [&]() {
    sim.step(true);
    F.push_back(sim.platen_force(0));
    DT.push_back(sim.last_velocity_step());
    P.push_back({sim.energies().momentum[0], sim.energies().momentum[1], sim.energies().momentum[2]});
    sampled.push_back(sim.step_count - 1);
  };
  sample();
  const double p0 = P[0][up];
  ASSERT_LT(p0, 0.0);
  // before the plate: no force, momentum constant
  long first_contact = -1, last_contact = -1;
  for (long n = 1; sim.t < c.end_time * (1 - 1e-12); ++n) {
    if (n % 50 == 0) {
      sample();
    } else {
      sim.step(false);
      F.push_back(sim.platen_force(0));
      DT.push_back(sim.last_velocity_step());
    }
    const bool touching = F.back()[0] != 0 || F.back()[1] != 0 || F.back()[2] != 0;
    if (touching && first_contact < 0) first_contact = n;
    if (touching) last_contact = n;
  }
  sample();
  ASSERT_GT(first_contact, 0) << "the particle never reached the plate";
  // pre-contact samples: momentum unchanged to round-off
  const double scale = std::fabs(p0);
  for (size_t s = 0; s < sampled.size(); ++s) {
    if (sampled[s] >= first_contact) break;
    for (int k = 0; k < D; ++k) EXPECT_NEAR(P[s][k], P[0][k], 1e-12 * scale) << "step " << sampled[s];
  }
  // every sample: momentum change = trapezoidal impulse of the plate since step 0
  double worst = 0, impulse_max = 0;
  for (size_t s = 1; s < sampled.size(); ++s) {
    const long N = sampled[s];
    for (int k = 0; k < D; ++k) {
      double J = 0.5 * (F[0][k] * DT[0] + F[N][k] * DT[N]);
      for (long n = 1; n < N; ++n) J += F[n][k] * DT[n];
      impulse_max = std::max(impulse_max, std::fabs(J));
      worst = std::max(worst, std::fabs(P[s][k] - P[0][k] - J));
    }
  }
  EXPECT_GT(impulse_max, 0.5 * scale) << "the plate hardly stopped the particle";
  EXPECT_LT(worst, 0.01 * impulse_max) << "momentum change differs from the plate impulse";
  EXPECT_LT(worst, 1e-9 * scale) << "(expected to round-off)";
  // after the last contact: free flight of the fragments, momentum constant
  int free_samples = 0;
  for (size_t s = 0; s + 1 < sampled.size(); ++s) {
    if (sampled[s] <= last_contact) continue;
    ++free_samples;
    for (int k = 0; k < D; ++k) EXPECT_NEAR(P.back()[k], P[s][k], 1e-12 * scale) << "step " << sampled[s];
  }
  EXPECT_GE(free_samples, 3) << "the fragments did not leave the plate before the end";
  EXPECT_GT(P.back()[up], 0.0) << "no rebound";
  // the fragments: broken as asked, their masses sum to the particle's mass
  FragmentAnalysis<D> fa(sim.m);
  const FragmentStats st = fa.compute(sim.m);
  EXPECT_GE(st.count, min_fragments);
  EXPECT_LE(st.count, max_fragments);
  const double mass = mesh_mass<D>(mesh, c.materials[0].density, D == 2 ? c.thickness : 1.0);
  EXPECT_NEAR(st.total_mass, mass, 1e-12 * mass);
  std::printf("  %dD: p0 %.6g N s, final %.6g N s, largest plate impulse %.6g N s, worst |dP - J| %.3g N s;"
              " contact steps %ld-%ld, %d free-flight samples; %d fragments, total mass %.12g (mesh %.12g) kg\n",
              D, p0, P.back()[up], impulse_max, worst, first_contact, last_contact, free_samples, st.count,
              st.total_mass, mass);
  double sum = 0;
  for (double m : fa.masses()) sum += m;
  EXPECT_NEAR(sum, mass, 1e-12 * mass);
}

// The speeds sit where the test's premises hold: the particle reaches the plate, every piece
// leaves it again and flies freely for a while before the end, and the total momentum ends
// upward. Faster, pieces are still on or moving down onto the plate at the end (the split disc's
// pieces at 6 m/s in 2D, measured without contact after main's Delaunay generator (dc1f07c) and
// initiation on the envelope (be6b5df) moved the breakage threshold).

TEST(Impact, MomentumChangesOnlyByPlateImpulse2D) {
  // 5 m/s: the disc cracks from the contact, pieces break off and all of them rebound by 0.5 ms.
  // (Close to the threshold the fragment count follows the time step chaotically: 4 m/s gave 1 or
  // 2 fragments for steps from 4e-8 to 6e-8 s, 5 m/s 2 to 5; this test passes with both the
  // step that shortens when the first interface fails and the contact step from the start.)
  momentum_through_impact<2>(kCase2D, {"parameters.speed=5", "parameters.h=0.006",
                                       "parameters.duration=500e-6"},
                             2, 10);
}

TEST(Impact, MomentumChangesOnlyByPlateImpulse3D) {
  // 3 m/s on a coarse sphere (about 700 tetrahedra): an elastic rebound, no interface fails (at
  // 4 m/s 2 interfaces fail, at 5 m/s the contact zone breaks off)
  momentum_through_impact<3>(kCase3D, {"parameters.speed=3", "parameters.h=0.008",
                                       "parameters.duration=200e-6"},
                             1, 1);
}

// Free flight without a plate: a particle moving at (3, -5(, 2)) m/s that also expands at a rate
// of 2000 1/s (50 m/s at 25 mm from the centre), with +-2 m/s of random velocity on top, tears
// apart; its momentum stays the same to round-off while the fragments fly apart.
template <int D>
void free_flight(const std::string& path, const std::vector<std::string>& overrides) {
  Case c = load_case(path, overrides);
  c.platens.clear();
  const HostMesh mesh = case_mesh(c);
  Simulation<D> sim(c, mesh);
  auto v = Kokkos::create_mirror_view(sim.m.v);
  Kokkos::deep_copy(v, sim.m.v);
  auto X = Kokkos::create_mirror_view(sim.m.X);
  Kokkos::deep_copy(X, sim.m.X);
  unsigned seed = 5;
  const double v0[3] = {3.0, -5.0, 2.0};
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) v(i, k) = v0[k] + 2000.0 * X(i, k) + 2.0 * fdem_test::prand(seed);
  Kokkos::deep_copy(sim.m.v, v);
  sim.reset_energy_reference();
  sim.step(true);
  const Energies e0 = sim.energies();
  double scale = 0;
  for (int k = 0; k < D; ++k) scale += e0.momentum[k] * e0.momentum[k];
  scale = std::sqrt(scale);
  ASSERT_GT(scale, 0.0);
  for (int n = 1; n < 3000; ++n) sim.step(false);
  sim.step(true);
  for (int k = 0; k < D; ++k) EXPECT_NEAR(sim.energies().momentum[k], e0.momentum[k], 1e-12 * scale);
  FragmentAnalysis<D> fa(sim.m);
  const FragmentStats st = fa.compute(sim.m);
  EXPECT_GT(st.count, 10) << "the velocity field did not break the particle";
  const double mass = mesh_mass<D>(mesh, c.materials[0].density, D == 2 ? c.thickness : 1.0);
  EXPECT_NEAR(st.total_mass, mass, 1e-12 * mass);
  double dmax = 0;
  for (int k = 0; k < D; ++k) dmax = std::max(dmax, std::fabs(sim.energies().momentum[k] - e0.momentum[k]));
  std::printf("  %dD: |P| %.6g N s, largest change over 3000 steps %.3g N s; %d fragments\n", D, scale,
              dmax, st.count);
}

TEST(Impact, MomentumConservedInFreeFlightOfFragments2D) {
  free_flight<2>(kCase2D, {"parameters.h=0.006"});
}

TEST(Impact, MomentumConservedInFreeFlightOfFragments3D) {
  free_flight<3>(kCase3D, {"parameters.h=0.008"});
}

// A fragmenting impact with contact on, step by step: it runs to the end without blowing up, the
// energy balance closes within 2 % of the particle's kinetic energy, and the plate holds every
// surface node, crack faces included: at every sample no surface node is deeper below the plate
// than its allowance (the depth it had when it became a surface node,
// Platens::follow_surfaces) plus 0.5 % of the element size. Nodes that are not surface nodes
// yet (copies of a vertex that slid along failed interfaces not handed over to contact yet) can
// be below the plate; every node stays within 10 % of h. Before the contact rules of contact_pair
// the 2D run (15 m/s, h = 8 mm) blew up at step 481 with 3.4 kJ appearing at a corner where
// several cracks meet, and the 3D run (20 m/s) blew up too; with the platen acting on the original
// outer boundary only, nodes sank 8 % of h into the plate (both runs), 2.5 % and 5 % with it.
template <int D>
void fragmenting_impact_with_contact(const std::string& path, const std::vector<std::string>& overrides,
                                     double h, int min_fragments) {
  const Case c = load_case(path, overrides);
  const HostMesh mesh = case_mesh(c);
  Simulation<D> sim(c, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  sim.step(true);
  const double e0 = sim.energies().kinetic;
  const double plate = c.platens[0].point[D - 1];
  double worst_err = 0, deepest = 0, beyond = 0;
  auto x = Kokkos::create_mirror_view(sim.m.x);
  for (long n = 1; sim.t < c.end_time * (1 - 1e-12); ++n) {
    const bool sample = n % 100 == 0;
    sim.step(sample);
    if (!sample) continue;
    sim.check_stability();
    worst_err = std::max(worst_err, std::fabs(sim.energies().balance_error));
    Kokkos::deep_copy(x, sim.m.x);
    // (the platens' rows: one per node they act on, bnode; they change with the surfaces)
    auto g0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.m.platen_g0);
    auto area = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.m.barea);
    auto bnode = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.m.bnode);
    for (int i = 0; i < sim.m.nn; ++i) deepest = std::max(deepest, plate - x(i, D - 1));
    for (int b = 0; b < sim.m.nb; ++b)
      if (area(b) > 0) beyond = std::max(beyond, plate - x(bnode(b), D - 1) + g0(0, b));
  }
  FragmentAnalysis<D> fa(sim.m);
  const FragmentStats st = fa.compute(sim.m);
  std::printf("  %dD: %ld steps, kinetic energy %.4g J, worst balance error %.3g J (%.2g %%), deepest node "
              "below the plate %.3g h (surface nodes: %.3g h beyond their allowance), %ld interfaces failed, %d "
              "fragments, %d "
              "contacts at the end\n",
              D, sim.step_count, e0, worst_err, 100 * worst_err / e0, deepest / h, beyond / h, sim.energies().failed,
              st.count, sim.contact()->active_contacts());
  // 3D at 20 m/s: 0.97 % at the case's safety factor 0.3 (2026-12-05); 1.0 to 1.9 % measured
  // earlier over safety factors 0.19 to 0.21, with the step that
  // shortens at the first handover and with the contact step from the start (the fragmentation
  // is chaotic: 70 to 86 fragments); the contact weights' position derivatives are not in the
  // force (docs/theory.md). 2D: 2.1 % at the case's safety factor 0.45 (0.3 % at 0.2).
  EXPECT_LT(worst_err, 0.03 * e0) << "energy balance";
  EXPECT_LT(beyond, 0.005 * h) << "a node went through the plate";
  EXPECT_LT(deepest, 0.1 * h);
  EXPECT_GE(st.count, min_fragments) << "the particle did not break";
}

TEST(Impact, FragmentingImpactWithContactStaysStable2D) {
  fragmenting_impact_with_contact<2>(kCase2D, {"parameters.speed=15", "parameters.h=0.008"},
                                     0.008, 10);
}

TEST(Impact, FragmentingImpactWithContactStaysStable3D) {
  fragmenting_impact_with_contact<3>(kCase3D, {"parameters.speed=20", "parameters.h=0.008", "parameters.duration=200e-6"},
                                     0.008, 5);
}

// A failed interface between two blocks: pressed together by 1 um it pushes them apart (the
// penalty); once a pair is farther apart than half the face (here: the right block turned over by
// 180 degrees about the interface's centre, which makes the mid-surface degenerate) it carries
// no force and stores no energy, where it used to give non-finite forces, and it stays so when
// the faces come back (switching on again would release the overlap reached meanwhile).
TEST(Impact, PartedFailedInterfaceCarriesNothing) {
  auto c = fdem_test::basic_case(2);
  c.interface_materials = {fdem_test::strong_interface(1e13, 4e12)};
  c.fracture_material = 0;
  c.contact.enabled = 0;  // the stop-gap without contact (with contact, contact takes over)
  const double d = 0.01;
  Simulation<2> sim(c, fdem_test::block_bar(2, d, d));
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  for (int k = 0; k < 2; ++k) {
    h(0, k, 0) = 3e-6;
    h(0, k, 1) = 1e-6;
    h(0, k, 2) = 2e-6;
    h(0, k, 3) = 0;
  }
  Kokkos::deep_copy(sim.m.ihist, h);
  auto x = Kokkos::create_mirror_view(sim.m.x);
  auto forces = [&](double (&fB)[2], double& stored) {
    Kokkos::deep_copy(sim.m.x, x);
    Kokkos::deep_copy(sim.m.f, 0.0);
    ForceScatter<2> sf(sim.m.f);
    compute_forces<2>(sim.m, sf);
    auto f = Kokkos::create_mirror_view(sim.m.f);
    Kokkos::deep_copy(f, sim.m.f);
    fB[0] = fB[1] = 0;
    for (int i = 4; i < 8; ++i)
      for (int k = 0; k < 2; ++k) fB[k] += f(i, k);  // total force on the right block
    stored = interface_state<2>(sim.m).elastic;
  };
  Kokkos::deep_copy(x, sim.m.X);
  for (int i = 4; i < 8; ++i) x(i, 0) -= 1e-6;  // right block pressed 1 um into the left one
  double f[2], e;
  forces(f, e);
  EXPECT_NEAR(f[0], 1e13 * 1e-6 * d, 1e-9 * 1e13 * 1e-6 * d);  // kn * overlap * face area (t = 1)
  EXPECT_NEAR(f[1], 0.0, 1e-6 * f[0]);
  EXPECT_NEAR(e, 0.5 * 1e13 * 1e-12 * d, 1e-9 * e);
  // turned over by 180 degrees about the interface centre (d, d/2): x -> 2 c - x
  Kokkos::deep_copy(x, sim.m.X);
  for (int i = 4; i < 8; ++i) {
    x(i, 0) = 2 * d - x(i, 0);
    x(i, 1) = d - x(i, 1);
  }
  forces(f, e);
  EXPECT_EQ(f[0], 0.0);
  EXPECT_EQ(f[1], 0.0);
  EXPECT_EQ(e, 0.0);
  Kokkos::deep_copy(x, sim.m.X);
  for (int i = 4; i < 8; ++i) x(i, 0) -= 1e-6;  // pressed again: parted for good
  forces(f, e);
  EXPECT_EQ(f[0], 0.0);
  EXPECT_EQ(e, 0.0);
  // half a face apart with an intact interface: it pulls the block back (no switch-off)
  for (int k = 0; k < 2; ++k) h(0, k, 0) = h(0, k, 1) = h(0, k, 2) = 0;
  Kokkos::deep_copy(sim.m.ihist, h);
  Kokkos::deep_copy(sim.m.icontact, 0);
  Kokkos::deep_copy(x, sim.m.X);
  for (int i = 4; i < 8; ++i) x(i, 0) += 0.5 * d;
  forces(f, e);
  EXPECT_LT(f[0], 0.0);
  EXPECT_GT(e, 0.0);
}

// 2D disc (h = 6 mm, about 500 triangles): at 2 m/s no interface fails and the disc rebounds in
// one piece; at 12 m/s it breaks.
TEST(Impact, ReboundsIntactBelowThresholdAndBreaksAbove) {
  const auto slow = run_quiet(kCase2D, {"parameters.speed=2", "parameters.h=0.006",
                                        "parameters.duration=300e-6", "output.snapshot_count=0"},
                              "slow");
  EXPECT_EQ(slow["interfaces_failed"].get<long>(), 0);
  EXPECT_EQ(slow["fragments"]["count"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(slow["fragments"]["largest_fraction"].get<double>(), 1.0);
  const double m = slow["fragments"]["total_mass_kg"].get<double>();
  const double py = slow["momentum_N_s"][1].get<double>();
  EXPECT_GT(py, 0.5 * m * 2.0) << "rebound speed below half the impact speed";
  EXPECT_LT(py, 1.0 * m * 2.0 * (1 + 1e-9)) << "rebound faster than the impact";
  // the disc's mass: rho pi R^2 t within the polygonal approximation
  EXPECT_NEAR(m, 2700 * M_PI * 0.05 * 0.05 * 1.0, 0.01 * m);

  const auto fast = run_quiet(kCase2D, {"parameters.speed=12", "parameters.h=0.006",
                                        "parameters.duration=300e-6", "output.snapshot_count=0"},
                              "fast");
  EXPECT_GT(fast["interfaces_failed"].get<long>(), 10);
  EXPECT_GE(fast["fragments"]["count"].get<int>(), 5);
  EXPECT_LT(fast["fragments"]["largest_fraction"].get<double>(), 0.9);
  EXPECT_NEAR(fast["fragments"]["total_mass_kg"].get<double>(), m, 1e-12 * m);
}

// Largest fragment fraction against speed (2, 5, 12, 40 m/s), each the mean over three meshes
// (h = 5.5, 6, 6.5 mm): one mesh's value scatters by about +-0.15 with the path the main cracks
// happen to take, the mean falls with speed (with contact: 1.00, 0.86, 0.42, 0.068; without, when
// the fragments passed through each other and the plate held only the original surface: 1.00,
// 0.81, 0.50, 0.37).
TEST(Impact, LargestFragmentFractionFallsWithSpeed) {
  const std::vector<double> speeds = {2, 5, 12, 40};
  const std::vector<double> sizes = {0.0055, 0.006, 0.0065};
  std::vector<double> mean;
  std::string table;
  for (double v : speeds) {
    double sum = 0;
    for (double h : sizes) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%g", v);
      const std::string vs = buf;
      std::snprintf(buf, sizeof buf, "%g", h);
      const auto s = run_quiet(kCase2D, {"parameters.speed=" + vs, "parameters.h=" + std::string(buf),
                                         "parameters.duration=300e-6", "output.snapshot_count=0",
                                         "output.history_rows=20"},
                               "sweep");
      const double lf = s["fragments"]["largest_fraction"].get<double>();
      sum += lf;
      table += "  v " + vs + " h " + buf + ": largest " + std::to_string(lf) + ", fragments " +
               std::to_string(s["fragments"]["count"].get<int>()) + "\n";
    }
    mean.push_back(sum / sizes.size());
  }
  for (size_t i = 0; i < mean.size(); ++i) table += "  mean at " + std::to_string(speeds[i]) + ": " + std::to_string(mean[i]) + "\n";
  EXPECT_DOUBLE_EQ(mean[0], 1.0) << table;
  for (size_t i = 1; i < mean.size(); ++i) EXPECT_LE(mean[i], mean[i - 1]) << table;
  EXPECT_LT(mean.back(), 0.6 * mean[0]) << table;
  std::printf("%s", table.c_str());
}

}  // namespace
