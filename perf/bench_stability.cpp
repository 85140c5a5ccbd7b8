// Stability sweeps (issue 8) that are too long for CI; perf/stability_sweep runs them and keeps
// the tables. Each mode prints a Markdown table on stdout.
//
//   bench_stability limits [STEPS]   computed stable step against the exact limit of the leap-frog
//                                    (2 / omega_max, eigenvalues of M^-1 K) and the factor at which
//                                    runs are first stopped (bisection, STEPS per run, default 5000)
//   bench_stability drift STEPS [mixed]  free vibration without damping: energy drift over STEPS
//                                    (mixed: the case key precision = "mixed")
//   bench_stability spin TURNS       free square spinning for TURNS turns: energy, angular
//                                    momentum, shape
//   bench_stability impact SPEED     block hitting a rigid wall at SPEED m/s, interfaces breaking:
//                                    energy balance, bounds, at several safety factors
// Eigen runs on the host only here: without EIGEN_NO_CUDA, nvcc (CUDA builds) makes Eigen mark its
// functions __host__ __device__, which CUDA 13 warns about (#20012-D, #20015-D) in Eigen 3.4.
#define EIGEN_NO_CUDA
#include <Eigen/Dense>
#include <Kokkos_Core.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "perf/bench_common.hpp"
#include "solver/simulation.hpp"
#include "tests/stability_fixtures.hpp"  // test helpers (exact stable step, fixtures)

namespace {

using namespace fdem;
using fdem_bench::seconds_since;
using fdem_test::host_view;
using fdem_test::mechanical;

constexpr double kE = 33e9, kNu = 0.25, kRho = 2700;

Case make_case(int dim, double kfac, double d) {
  auto c = fdem_test::basic_case(dim, kE, kNu, kRho);
  if (kfac > 0) {
    const double kn = kfac * kE / d;
    c.interface_materials = {fdem_test::strong_interface(kn, kn / 2.5)};
    c.fracture_material = 0;
  }
  return c;
}

// Node-sum (Gershgorin) bound on the spring part: omega^2 <= max_i 2 sum_{points at i} k A / m_i,
// combined with the bulk step `bulk` like the solver's estimate. Proposed in docs/robustness.md.
template <int D>
double node_sum_estimate(const Simulation<D>& sim, double kmax, double bulk) {
  if (sim.m.ni == 0) return bulk;
  const auto iface = host_view(sim.m.iface);
  const auto iarea = host_view(sim.m.iarea);
  const auto mass = host_view(sim.m.mass);
  std::vector<double> ksum(sim.m.nn, 0.0);
  for (int q = 0; q < sim.m.ni; ++q)
    for (int k = 0; k < 2 * D; ++k) ksum[iface(q, k)] += kmax * iarea(q);
  double w2 = 0;
  for (int i = 0; i < sim.m.nn; ++i) w2 = std::max(w2, 2 * ksum[i] / mass(i));
  const double s = 2 / std::sqrt(w2), b = bulk;
  return 1 / std::sqrt(1 / (b * b) + 1 / (s * s));
}

// Element-by-element bound on the bulk part (Irons: the largest eigenvalue of M^-1 K is at most
// the largest over elements of K_e / m_e, m_e the element's own lumped mass per node), K_e by
// central differences of the element force kernel. Proposed in docs/robustness.md.
template <int D>
double element_bound(const Simulation<D>& sim) {
  const auto X = host_view(sim.m.X);
  const auto elem = host_view(sim.m.elem);
  const auto grad = host_view(sim.m.grad);
  const auto vol0 = host_view(sim.m.vol0);
  const auto emat = host_view(sim.m.emat);
  const auto mat = host_view(sim.m.mat);
  constexpr int N = (D + 1) * D;
  double lmax = 0;
  for (int e = 0; e < sim.m.ne; ++e) {
    double xe[D + 1][D], G[D][D], fe[D + 1][D], h = 0;
    for (int a = 0; a < D + 1; ++a)
      for (int i = 0; i < D; ++i) xe[a][i] = X(elem(e, a), i);
    for (int i = 0; i < D; ++i) h = std::max(h, std::fabs(xe[1][i] - xe[0][i]));
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j) G[b][j] = grad(e, b, j);
    const int mt = emat(e);
    const double eps = 1e-7 * h;
    Eigen::Matrix<double, N, N> K;
    for (int j = 0; j < N; ++j) {
      double fp[N];
      for (int sgn = 1; sgn >= -1; sgn -= 2) {
        xe[j / D][j % D] += sgn * eps;
        element_forces<D>(xe, G, vol0(e), mat(mt, 0), mat(mt, 1), fe);
        xe[j / D][j % D] -= sgn * eps;
        for (int i = 0; i < N; ++i) {
          if (sgn > 0) fp[i] = fe[i / D][i % D];
          else K(i, j) = -(fp[i] - fe[i / D][i % D]) / (2 * eps);
        }
      }
    }
    const double me = mat(mt, 2) * vol0(e) / (D + 1);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(0.5 * (K + K.transpose()),
                                                                  Eigen::EigenvaluesOnly);
    lmax = std::max(lmax, es.eigenvalues().maxCoeff() / me);
  }
  return 2 / std::sqrt(lmax);
}

// Is a free run with random velocities (1e-3 m/s) at dt = factor * dt_crit stopped by the
// solver's check within `steps` steps?
template <int D>
bool stopped(const Case& c, const HostMesh& mesh, double factor, long steps) {
  Simulation<D> sim(c, mesh);
  sim.dt = factor * sim.stable.critical;
  fdem_test::random_velocities(sim, 7, 1e-3);
  try {
    for (long s = 1; s <= steps; ++s) {
      sim.step(s % 10 == 0);
      if (s % 10 == 0) sim.check_stability();
    }
  } catch (const NumericalError&) {
    return true;
  }
  return false;
}

template <int D>
void limits_row(const char* name, const Case& c, const HostMesh& mesh, long steps) {
  const auto t0 = std::chrono::steady_clock::now();
  double asym = 0;
  const double exact = fdem_test::exact_stable_step<D>(c, mesh, &asym);
  Simulation<D> sim(c, mesh);
  const auto st = sim.stable;
  const double kmax = sim.m.ni ? std::max(sim.m.coh.kn, sim.m.coh.ks) : 0;
  const double ns = node_sum_estimate<D>(sim, kmax, st.bulk);
  const double bound = node_sum_estimate<D>(sim, kmax, element_bound<D>(sim));
  double lo = 0.3, hi = 2.0;  // bisection on the factor where runs are first stopped
  if (!stopped<D>(c, mesh, hi, steps)) {
    hi = -1;
  } else {
    while (hi - lo > 0.002) {
      const double mid = 0.5 * (lo + hi);
      (stopped<D>(c, mesh, mid, steps) ? hi : lo) = mid;
    }
  }
  const auto q = mesh_quality(mesh);
  std::printf("| %s | %d | %.1f | %.3e | %.3e | %.3e | %.3f | %.3f | %.3f | %s | %.0e | %.0f |\n",
              name, sim.m.nn * D, q.min_angle_deg, st.bulk,
              std::isfinite(st.springs) ? st.springs : 0.0, st.critical, exact / st.critical,
              ns / st.critical, bound / st.critical,
              hi > 0 ? (std::to_string(hi).substr(0, 5)).c_str() : "> 2", asym, seconds_since(t0));
  std::fflush(stdout);
}

void limits(long steps) {
  std::printf("Stable time step: computed (solver) against exact (2/omega_max from the eigenvalues of "
              "M^-1 K, K assembled through the force kernel) and observed (smallest factor of "
              "dt_crit at which a free run with random velocities is stopped by the solver's check "
              "within %ld steps, bisection to 0.002). E = 33 GPa, nu = 0.25, rho = 2700, plane "
              "strain, k_s = k_n / 2.5, interfaces never fail; d = cell size. Candidate estimates: "
              "'node-sum springs' = the solver's bulk step combined with the spring bound "
              "omega^2 <= max_i 2 sum k A / m_i over the interface points at node i; 'element + "
              "node-sum' = the same with the bulk step from the largest element eigenvalue "
              "(K_e / m_e). A candidate is conservative when it is <= exact.\n\n", steps);
  std::printf("| configuration | dofs | min angle (deg) | dt_bulk (s) | dt_springs (s) | dt_crit (s) "
              "| exact / dt_crit | node-sum springs / dt_crit | element + node-sum bound / dt_crit "
              "| stopped from (x dt_crit) | K asymmetry | time (s) |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  {
    const double d = 0.01;
    auto mesh = fdem_test::block_bar(10, d, d);
    limits_row<2>("bar of 10 blocks, k_n = 10 E/d", make_case(2, 10, d), mesh, steps);
  }
  const int n = 3;
  const double d = 0.1 / n;
  {
    auto mesh = generate_crossed_rectangle(0, 0, 0.1, 0.1, n, n);
    limits_row<2>("crossed 3x3, no interfaces", make_case(2, 0, d), mesh, steps);
  }
  for (double kfac : {1.0, 10.0, 100.0, 1e3, 1e4}) {
    auto mesh = generate_crossed_rectangle(0, 0, 0.1, 0.1, n, n);
    insert_interfaces(mesh, {true});
    char name[96];
    std::snprintf(name, sizeof name, "crossed 3x3, k_n = %g E/d", kfac);
    limits_row<2>(name, make_case(2, kfac, d), mesh, steps);
  }
  {
    auto mesh = fdem_test::distorted_rectangle(0.1, 0.1, 4, 4, 5.0);
    limits_row<2>("5-degree slivers 4x4, no interfaces", make_case(2, 0, 0.025), mesh, steps);
    insert_interfaces(mesh, {true});
    limits_row<2>("5-degree slivers 4x4, k_n = 10 E/d", make_case(2, 10, 0.025), mesh, steps);
  }
  {
    auto mesh = generate_box({0, 0, 0}, {0.1, 0.1, 0.1}, 2, 2, 2);
    limits_row<3>("box 2x2x2 (Kuhn tets), no interfaces", make_case(3, 0, 0.05), mesh, steps);
    insert_interfaces(mesh, {true});
    for (double kfac : {10.0, 1e4}) {
      char name[96];
      std::snprintf(name, sizeof name, "box 2x2x2, k_n = %g E/d", kfac);
      limits_row<3>(name, make_case(3, kfac, 0.05), mesh, steps);
    }
  }
}

// Free vibration without damping at the default safety factor 0.5: largest |E/E0 - 1| up to each
// decade of steps.
template <int D>
void drift_row(const char* name, Case c, const HostMesh& mesh, long steps, bool mixed) {
  const auto t0 = std::chrono::steady_clock::now();
  c.mixed_precision = mixed;
  Simulation<D> sim(c, mesh);
  fdem_test::random_velocities(sim, 7, 1.0);
  sim.step(true);
  const double e0 = mechanical(sim.energies());
  double worst = 0, sum = 0;
  long count = 0;
  std::string cols;
  long next = 1000;
  for (long s = 1; s <= steps; ++s) {
    const bool sample = s % 100 == 0;
    sim.step(sample);
    if (sample) {
      sim.check_stability();
      const double dev = mechanical(sim.energies()) / e0 - 1;
      worst = std::max(worst, std::fabs(dev));
      if (s > next / 10) {  // mean over the last decade window (next/10, next]
        sum += dev;
        ++count;
      }
      if (s == next) {
        char buf[48];
        std::snprintf(buf, sizeof buf, " %.1e (%+.1e) |", worst, sum / count);
        cols += buf;
        next *= 10;
        sum = 0;
        count = 0;
      }
    }
  }
  std::printf("| %s | %.3e | %s %.0f |\n", name, sim.dt, cols.c_str(), seconds_since(t0));
  std::fflush(stdout);
}

void drift(long steps, bool mixed) {
  if (mixed) std::printf("precision \"mixed\". ");
  std::printf("Free vibration, no damping, no loads, random nodal velocities of up to 1 m/s, "
              "dt = 0.5 dt_crit (the default). Each column: largest |E/E0 - 1| of kinetic + elastic "
              "energy E (sampled every 100 steps) up to that number of steps, and in brackets the "
              "mean of E/E0 - 1 over the last tenth of those steps (a secular drift shows as a "
              "growing mean; the largest deviation also grows slowly as more extreme phases of the "
              "modes are sampled).\n\n| body | dt (s) |");
  for (long n = 1000; n <= steps; n *= 10) std::printf(" %ld steps |", n);
  std::printf(" time (s) |\n|---|---|");
  for (long n = 1000; n <= steps; n *= 10) std::printf("---|");
  std::printf("---|\n");
  {
    auto mesh = generate_crossed_rectangle(0, 0, 0.1, 0.1, 3, 3);
    drift_row<2>("2D crossed 3x3, no interfaces", make_case(2, 0, 0.1 / 3), mesh, steps, mixed);
    insert_interfaces(mesh, {true});
    drift_row<2>("2D crossed 3x3, k_n = 10 E/d", make_case(2, 10, 0.1 / 3), mesh, steps, mixed);
  }
  {
    auto mesh = generate_box({0, 0, 0}, {0.1, 0.1, 0.1}, 1, 1, 1);
    insert_interfaces(mesh, {true});
    drift_row<3>("3D box 1x1x1 (6 tets), k_n = 10 E/d", make_case(3, 10, 0.1), mesh, steps, mixed);
  }
}

// Free square (one crossed cell with interfaces) spinning about its centre.
void spin_row(double rim_fraction, double turns) {
  const auto t0 = std::chrono::steady_clock::now();
  const double L = 0.1;
  auto mesh = generate_crossed_rectangle(0, 0, L, L, 1, 1);
  insert_interfaces(mesh, {true});
  Simulation<2> sim(make_case(2, 10, L), mesh);
  const double cp = std::sqrt(kE * (1 - kNu) / ((1 + kNu) * (1 - 2 * kNu) * kRho));
  const double R = L / std::sqrt(2.0), omega = rim_fraction * cp / R;
  fdem_test::rigid_rotation(sim, omega, L / 2);
  sim.step(true);
  const double e0 = mechanical(sim.energies());
  const double L0 = fdem_test::angular_momentum(sim)[2];
  const long steps = std::lround(turns * 2 * M_PI / omega / sim.dt);
  fdem_test::Diagonal diagonal(sim, L);
  double worst = 0;
  const int every = std::max(1, static_cast<int>(0.5 / (omega * sim.dt)));  // < 0.5 rad apart
  for (long s = 1; s <= steps; ++s) {
    const bool sample = s % every == 0 || s == steps;
    sim.step(sample);
    if (sample) {
      sim.check_stability();
      worst = std::max(worst, std::fabs(mechanical(sim.energies()) / e0 - 1));
      diagonal.track();
    }
  }
  const double angle = diagonal.turned;
  const double Lz = fdem_test::angular_momentum(sim)[2];
  const double stretch = fdem_test::max_pair_stretch(sim, L);
  std::printf("| %.2f | %.0f | %.1f | %ld | %.2f | %.1e | %.1e | %.1e | %.1e | %.0f |\n",
              rim_fraction, omega * R, omega * sim.dt * 180 / M_PI, steps, angle / (2 * M_PI),
              worst, std::fabs(Lz / L0 - 1), stretch, rim_fraction * rim_fraction,
              seconds_since(t0));
  std::fflush(stdout);
}

void spin(double turns) {
  std::printf("Free square (0.1 m, one crossed cell, 4 triangles, interfaces k_n = 10 E/d) spinning "
              "about its centre from a rigid rotation, dt = 0.5 dt_crit. Energy: largest relative "
              "change of kinetic + elastic energy; angular momentum: relative change at the end; "
              "stretch: largest relative change of a distance between two nodes at the end "
              "(centrifugal strain ~ (v/c_p)^2).\n\n"
              "| rim speed / c_p | rim speed (m/s) | rotation per step (deg) | steps | turns "
              "| energy | angular momentum | stretch | (v/c_p)^2 | time (s) |\n"
              "|---|---|---|---|---|---|---|---|---|---|\n");
  for (double f : {0.01, 0.05, 0.2}) spin_row(f, turns);
}

// A block with interfaces everywhere (realistic strength) hits a fixed rigid wall.
void impact_row(double speed, double safety) {
  const auto t0 = std::chrono::steady_clock::now();
  const double w = 0.1, h = 0.05, d = 0.0125;
  auto mesh = generate_crossed_rectangle(0, 1e-4, w, h, 8, 4);
  insert_interfaces(mesh, {true});
  auto c = fdem_test::basic_case(2, kE, kNu, kRho);
  InterfaceMaterial im;
  im.name = "rock";
  im.kn = 10 * kE / d;
  im.ks = im.kn / 2.5;
  im.ft = 5e6;
  im.c = 10e6;
  im.phi = 30 * M_PI / 180;
  im.Gnc = 50;
  im.Gsc = 500;
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.initial_velocities = {InitialVelocity{"all", {0, -speed, 0}}};
  PlatenSpec wall;
  wall.name = "wall";
  wall.normal = {0, 1, 0};
  wall.friction = 0.3;
  c.platens = {wall};
  c.safety_factor = safety;
  Simulation<2> sim(c, mesh);
  const double cp = std::sqrt(kE * (1 - kNu) / ((1 + kNu) * (1 - 2 * kNu) * kRho));
  const double t_end = 1e-4 / speed + 10 * h / cp;  // contact plus ~5 round trips of a wave
  double worst = 0, vmax = 0, e0 = 0;
  std::string status = "ran to the end";
  Energies e;
  try {
    for (long s = 0; sim.t < t_end; ++s) {
      const bool sample = s % 100 == 0;
      sim.step(sample);
      if (sample) {
        sim.check_stability();
        e = sim.energies();
        if (s == 0) e0 = e.kinetic;
        worst = std::max(worst, std::fabs(e.balance_error) / e0);
        vmax = std::max(vmax, fdem_test::max_speed(sim));
      }
    }
  } catch (const NumericalError& err) {
    status = std::string("stopped: ") + std::string(err.what()).substr(0, 60) + "...";
  }
  std::printf("| %.0f | %.2f | %.2e | %ld | %.1e | %.2f | %ld / %d | %.2f | %.2f | %s | %.0f |\n",
              speed, safety, sim.dt, sim.step_count, worst, vmax / speed, e.failed, sim.m.ni,
              e.fracture / e0, e.kinetic / e0, status.c_str(), seconds_since(t0));
  std::fflush(stdout);
}

void impact(double speed) {
  std::printf("Block 0.1 x 0.05 m (crossed 8x4, interfaces everywhere: k_n = 10 E/d, f_t = 5 MPa, "
              "c = 10 MPa, phi = 30 deg, G_nc = 50 N/m, G_sc = 500 N/m) moving at SPEED into a "
              "fixed rigid wall (penalty = k_n, friction 0.3), no damping, for the contact time "
              "plus 10 h / c_p. Balance: largest |balance error| / initial kinetic energy. "
              "Fragments do not yet touch each other (contact module pending).\n\n"
              "| speed (m/s) | safety factor | dt (s) | steps | balance | max speed / speed "
              "| failed interfaces | fracture / E0 | kinetic / E0 at end | status | time (s) |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double sf : {0.5, 0.2, 0.1}) impact_row(speed, sf);
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  const std::string mode = argc > 1 ? argv[1] : "";
  const double arg = argc > 2 ? std::atof(argv[2]) : 0;
  try {
    if (mode == "limits") {
      limits(arg > 0 ? static_cast<long>(arg) : 5000);
    } else if (mode == "drift") {
      drift(arg > 0 ? static_cast<long>(arg) : 1000000, argc > 3 && std::string(argv[3]) == "mixed");
    } else if (mode == "spin") {
      spin(arg > 0 ? arg : 100);
    } else if (mode == "impact") {
      impact(arg > 0 ? arg : 200);
    } else {
      std::fprintf(stderr, "usage: bench_stability limits [STEPS] | drift [STEPS [mixed]] | spin [TURNS] | "
                           "impact [SPEED]\n");
      return 2;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_stability: %s\n", e.what());
    return 1;
  }
  return 0;
}
