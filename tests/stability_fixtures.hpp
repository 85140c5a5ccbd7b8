#pragma once
// Helpers for the stability stress tests (tests/test_stability.cpp) and the larger sweeps
// (perf/bench_stability.cpp): random velocity fields, energy sums, angular momentum, the
// distorted mesh, and the exact stability limit of the leap-frog from the largest eigenvalue of
// M^-1 K (K assembled through the solver's own force kernel, power iteration).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "mesh/mesh.hpp"
#include "solver/simulation.hpp"
#include "scenes.hpp"
#include "solver_fixtures.hpp"

namespace fdem_test {

// Elastic energy plus kinetic energy (what an undamped, unloaded body conserves).
inline double mechanical(const fdem::Energies& e) {
  return e.kinetic + e.strain + e.interface_elastic + e.contact_elastic;
}

// Every node gets a velocity with components uniform in [-amp, amp] (deterministic).
template <int D>
void random_velocities(fdem::Simulation<D>& sim, unsigned seed, double amp) {
  auto v = Kokkos::create_mirror_view(sim.m.v);
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) v(i, k) = amp * prand(seed);
  Kokkos::deep_copy(sim.m.v, v);
  sim.reset_energy_reference();
}

// Largest nodal speed.
template <int D>
double max_speed(const fdem::Simulation<D>& sim) {
  const auto v = host_view(sim.m.v);
  double s = 0;
  for (int i = 0; i < sim.m.nn; ++i) {
    double q = 0;
    for (int k = 0; k < D; ++k) q += v(i, k) * v(i, k);
    s = std::max(s, q);
  }
  return std::sqrt(s);
}

// Angular momentum about the origin (z component in 2D), sum of m x(n+1) x v(n+1/2): the
// leap-frog conserves it exactly when the internal forces exert no net torque (objectivity).
template <int D>
std::array<double, 3> angular_momentum(const fdem::Simulation<D>& sim) {
  const auto x = host_view(sim.m.x);
  const auto v = host_view(sim.m.v);
  const auto m = host_view(sim.m.mass);
  std::array<double, 3> L{0, 0, 0};
  for (int i = 0; i < sim.m.nn; ++i) {
    if constexpr (D == 2) {
      L[2] += m(i) * (x(i, 0) * v(i, 1) - x(i, 1) * v(i, 0));
    } else {
      L[0] += m(i) * (x(i, 1) * v(i, 2) - x(i, 2) * v(i, 1));
      L[1] += m(i) * (x(i, 2) * v(i, 0) - x(i, 0) * v(i, 2));
      L[2] += m(i) * (x(i, 0) * v(i, 1) - x(i, 1) * v(i, 0));
    }
  }
  return L;
}

// A 2D body set in rigid rotation at angular velocity omega about (c, c); the next step is the
// energy reference.
inline void rigid_rotation(fdem::Simulation<2>& sim, double omega, double c) {
  const auto X = host_view(sim.m.X);
  auto v = Kokkos::create_mirror_view(sim.m.v);
  for (int i = 0; i < sim.m.nn; ++i) {
    v(i, 0) = -omega * (X(i, 1) - c);
    v(i, 1) = omega * (X(i, 0) - c);
  }
  Kokkos::deep_copy(sim.m.v, v);
  sim.reset_energy_reference();
}

// The diagonal of a 2D square of side L with a corner at the origin, from the first node at (0, 0)
// to the first node at (L, L) (reference positions), followed as the body turns: track() adds the
// turn since the last call (less than half a turn apart) to `turned`.
class Diagonal {
 public:
  Diagonal(const fdem::Simulation<2>& sim, double L) : sim_(sim), x_(Kokkos::create_mirror_view(sim.m.x)) {
    const auto X = host_view(sim.m.X);
    for (int i = 0; i < sim.m.nn; ++i) {
      if (X(i, 0) == 0 && X(i, 1) == 0 && a_ < 0) a_ = i;
      if (X(i, 0) == L && X(i, 1) == L && b_ < 0) b_ = i;
    }
    prev_ = angle();
  }
  // Its angle now.
  double angle() {
    Kokkos::deep_copy(x_, sim_.m.x);
    return std::atan2(x_(b_, 1) - x_(a_, 1), x_(b_, 0) - x_(a_, 0));
  }
  void track() {
    const double a = angle();
    turned += std::remainder(a - prev_, 2 * M_PI);
    prev_ = a;
  }
  double turned = 0;  // radians

 private:
  const fdem::Simulation<2>& sim_;
  typename decltype(fdem::Model<2>::x)::HostMirror x_;
  int a_ = -1, b_ = -1;
  double prev_ = 0;
};

// Largest relative change of the distance between two nodes of a 2D body (reference against
// current positions; pairs closer than 1e-9 L, copies of one node, left out).
inline double max_pair_stretch(const fdem::Simulation<2>& sim, double L) {
  const auto X = host_view(sim.m.X);
  const auto x = host_view(sim.m.x);
  double worst = 0;
  for (int i = 0; i < sim.m.nn; ++i)
    for (int j = i + 1; j < sim.m.nn; ++j) {
      const double d0 = std::hypot(X(i, 0) - X(j, 0), X(i, 1) - X(j, 1));
      if (d0 < 1e-9 * L) continue;
      const double d1 = std::hypot(x(i, 0) - x(j, 0), x(i, 1) - x(j, 1));
      worst = std::max(worst, std::fabs(d1 / d0 - 1));
    }
  return worst;
}

// Crossed-diagonal rectangle (w x h, nx x ny cells) whose cell centres are moved down to
// (x_left + 0.7 dx, y_bottom + 0.7 dx tan(min_angle)) in every other cell (checkerboard): the bottom
// triangle of such a cell is a sliver whose smallest angle is min_angle_deg (and whose largest
// is near 180 - 2.5 min_angle). Interfaces are not inserted.
inline fdem::HostMesh distorted_rectangle(double w, double h, int nx, int ny, double min_angle_deg) {
  auto mesh = fdem::generate_crossed_rectangle(0, 0, w, h, nx, ny);
  const double dx = w / nx, dy = h / ny;
  const double tanv = std::tan(min_angle_deg * M_PI / 180.0);
  const int ncorner = (nx + 1) * (ny + 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if ((i + j) % 2) continue;
      const int c = ncorner + j * nx + i;
      mesh.X[2 * c] = (i + 0.7) * dx;  // 0.7 dx from the left corner, 0.3 dx from the right
      mesh.X[2 * c + 1] = j * dy + 0.7 * dx * tanv;  // so the left base angle is min_angle
    }
  return mesh;
}

// Exact stable step of the undamped leap-frog for small motions about the reference state:
// 2 / omega_max with omega_max^2 the largest eigenvalue of M^-1 K. K is assembled column by
// column from the solver's own force kernel (one step from x = X +- eps e_j with v = 0 gives
// v = -+ dt eps M^-1 K e_j); the largest eigenvalue of M^-1/2 K M^-1/2 comes from power iteration
// with the Rayleigh quotient (converged to ~1e-6 relative for these meshes; small meshes only: a
// few thousand degrees of freedom). Only for cases without velocity BCs, loads, damping or
// platens, and with interfaces that stay undamaged. `asymmetry` (optional) receives
// max |K - K^T| / max |K| (0 for forces that derive from an energy, up to round-off).
template <int D>
double exact_stable_step(const fdem::Case& c, const fdem::HostMesh& mesh,
                         double* asymmetry = nullptr, int max_iter = 20000) {
  fdem::Simulation<D> sim(c, mesh);
  const int nn = sim.m.nn, nd = nn * D;
  auto X = Kokkos::create_mirror(sim.m.X);  // copies (a mirror view may be m.X itself)
  auto x = Kokkos::create_mirror_view(sim.m.x);
  auto v = Kokkos::create_mirror_view(sim.m.v);
  auto mass = Kokkos::create_mirror_view(sim.m.mass);
  Kokkos::deep_copy(X, sim.m.X);
  Kokkos::deep_copy(mass, sim.m.mass);
  double size = 0;
  for (int k = 0; k < D; ++k) {
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < nn; ++i) {
      lo = std::min(lo, X(i, k));
      hi = std::max(hi, X(i, k));
    }
    size = std::max(size, hi - lo);
  }
  const double eps = 1e-7 * size;  // far in the linear range, far above round-off
  const double dt = sim.dt;
  const size_t n = static_cast<size_t>(nd);
  std::vector<double> K(n * n);  // K(i, j) = K[i * n + j]
  for (int j = 0; j < nd; ++j) {
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Kokkos::deep_copy(x, X);
      Kokkos::deep_copy(v, 0.0);
      x(j / D, j % D) += sgn * eps;
      Kokkos::deep_copy(sim.m.x, x);
      Kokkos::deep_copy(sim.m.v, v);
      sim.step(false);
      Kokkos::deep_copy(v, sim.m.v);
      for (int i = 0; i < nd; ++i) {
        const double fi = mass(i / D) * v(i / D, i % D) / dt;  // = -K (sgn eps e_j)
        double& k = K[i * n + j];
        k = sgn < 0 ? fi : (k - fi) / (2 * eps);
      }
    }
  }
  double kmax = 0, amax = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j) {
      kmax = std::max(kmax, std::fabs(K[i * n + j]));
      amax = std::max(amax, std::fabs(K[i * n + j] - K[j * n + i]));
    }
  if (asymmetry) *asymmetry = amax / kmax;
  // A = S (K + K^T)/2 S with S = M^-1/2: symmetric, eigenvalues omega^2
  std::vector<double> A(n * n), s(n);
  for (size_t i = 0; i < n; ++i) s[i] = 1.0 / std::sqrt(mass(i / D));
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j) A[i * n + j] = 0.5 * (K[i * n + j] + K[j * n + i]) * s[i] * s[j];
  std::vector<double> u(n), w(n);
  unsigned seed = 12345;
  for (auto& q : u) q = prand(seed);
  double lambda = 0;
  for (int it = 0; it < max_iter; ++it) {
    double uu = 0, uw = 0, ww = 0;
    for (size_t i = 0; i < n; ++i) {
      double acc = 0;
      for (size_t j = 0; j < n; ++j) acc += A[i * n + j] * u[j];
      w[i] = acc;
      uu += u[i] * u[i];
      uw += u[i] * acc;
      ww += acc * acc;
    }
    const double next = uw / uu;  // Rayleigh quotient: rises monotonically to omega_max^2
    const double norm = std::sqrt(ww);
    for (size_t i = 0; i < n; ++i) u[i] = w[i] / norm;
    if (it > 50 && next - lambda <= 1e-13 * next) {
      lambda = next;
      break;
    }
    lambda = std::max(lambda, next);
  }
  return 2.0 / std::sqrt(lambda);
}

}  // namespace fdem_test
