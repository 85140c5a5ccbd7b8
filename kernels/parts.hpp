#pragma once
// Device loops of a decomposed run that are not the exchange itself (kernels/halo.hpp): the
// contact pass's ghost forces, the contact zones' check and the checks of a cut of the parts
// (src/solver/simulation_parallel.cpp, src/solver/summary.cpp). Each reads its views by value and
// returns a few host values.
#include "kernels/model.hpp"

namespace fdem {

// The forces on the ghost nodes (nodes n0..nn-1) set to zero: before the contact pass of a part,
// whose contacts then put their forces on ghosts there to be sent back to the owners.
template <int D>
void zero_ghost_forces(const NodeData<D>& n) {
  const auto f = n.f;
  Kokkos::parallel_for(
      "fdem::halo::zero_ghost_forces", Kokkos::RangePolicy<ExecSpace>(n.owned_nodes(), n.nn),
      KOKKOS_LAMBDA(const int i) {
        for (int k = 0; k < D; ++k) f(i, k) = 0.0;
      });
}

// Over the own nodes: the largest squared displacement from xref (the positions where the parts
// were cut) and the largest squared speed, in one pass.
template <int D>
void largest_drift(const NodeData<D>& n, const Kokkos::View<double* [D]>& xref, double& d2, double& v2) {
  const auto x = n.x, v = n.v;
  const auto X = xref;
  d2 = v2 = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::zone_drift", Kokkos::RangePolicy<ExecSpace>(0, n.owned_nodes()),
      KOKKOS_LAMBDA(const int i, double& dm, double& vm) {
        double a = 0, b = 0;
        for (int k = 0; k < D; ++k) {
          a += (x(i, k) - X(i, k)) * (x(i, k) - X(i, k));
          b += v(i, k) * v(i, k);
        }
        dm = a > dm ? a : dm;
        vm = b > vm ? b : vm;
      },
      Kokkos::Max<double>(d2), Kokkos::Max<double>(v2));
}

// Over the own nodes: the mass, the momentum (3 components; the third 0 in 2D) and the sum of
// m |v_k| (the scale of the momentum's round-off), into s[0..4].
template <int D>
void mass_momentum(const NodeData<D>& n, double (&s)[5]) {
  const auto mass = n.mass;
  const auto v = n.v;
  for (double& x : s) x = 0;
  Kokkos::parallel_reduce(
      "fdem::recut::mass_momentum", Kokkos::RangePolicy<ExecSpace>(0, n.owned_nodes()),
      KOKKOS_LAMBDA(const int i, double& a, double& b, double& c, double& d, double& e) {
        a += mass(i);
        b += mass(i) * v(i, 0);
        c += mass(i) * v(i, 1);
        if (D == 3) d += mass(i) * v(i, D - 1);
        for (int k = 0; k < D; ++k) e += mass(i) * (v(i, k) < 0 ? -v(i, k) : v(i, k));
      },
      s[0], s[1], s[2], s[3], s[4]);
}

// The narrow phase's work of the points points(0..np) in its units: `point_units` per point plus
// its candidates (CSR offsets `off` by node); with a non-empty `w` also added per node,
// w(node) += units * scale. Returns the sum (the balance of a run over processes, Simulation).
inline double point_work(const Kokkos::View<int*>& off, const Kokkos::View<int*>& points, int np, int point_units,
                         const Kokkos::View<double*>& w, double scale) {
  const bool per_node = w.extent(0) > 0;
  double total = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::point_work", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const int i, double& sum) {
        const int s = points(i);
        const double units = static_cast<double>(point_units + off(s + 1) - off(s));
        if (per_node) w(s) += units * scale;  // (each surface node once in the list)
        sum += units;
      },
      total);
  return total;
}

// The interfaces among the first `count` whose handover flag is set (handed over to contact).
inline long count_handed(const Kokkos::View<int*>& icontact, int count) {
  const auto ic = icontact;
  long handed = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::count_handed", Kokkos::RangePolicy<ExecSpace>(0, count),
      KOKKOS_LAMBDA(const int q, long& n) { n += ic(q) != 0 ? 1 : 0; }, handed);
  return handed;
}

}  // namespace fdem
