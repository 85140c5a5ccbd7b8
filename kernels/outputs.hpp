#pragma once
// Reductions and fields for output and checks, run on sampled steps only (not every step): bulk
// strain energy, the interfaces' energies and counts, sums over node lists (reactions,
// displacements), element stresses and interface damage for snapshots.
#include "kernels/cohesive.hpp"
#include "kernels/elastic.hpp"
#include "kernels/interface.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Bulk strain energy.
template <int D>
double strain_energy(const Model<D>& m) {
  const auto x = m.x;
  const ElementData<D> el = m;
  double w = 0;
  Kokkos::parallel_reduce(
      "fdem::strain_energy", Kokkos::RangePolicy<ExecSpace>(0, m.owned_elems()),
      KOKKOS_LAMBDA(const int e, double& s) {
        double xe[D + 1][D], G[D][D], F[D][D], S[D][D];
        gather_element<D>(x, el, e, xe, G);
        deformation_gradient<D>(xe, G, F);
        const int mt = el.emat(e);
        s += el.vol0(e) * svk_stress<D>(F, el.mat(mt, 0), el.mat(mt, 1), S);
      },
      w);
  return w;
}

// Sums over the interfaces: stored elastic energy, dissipated fracture energy, energy dissipated by
// the residual friction of softening points (kernels/cohesive.hpp, SlipPoint), number damaged
// (some point with damage > 0) and failed (every point at damage 1). A parallel_reduce result
// type in Kokkos 3.4.1 (volatile join) and 4.x (plain join).
struct InterfaceSums {
  double elastic = 0, fracture = 0, friction = 0, damaged = 0, failed = 0;
  KOKKOS_INLINE_FUNCTION InterfaceSums() {}
  KOKKOS_INLINE_FUNCTION InterfaceSums& operator+=(const InterfaceSums& o) {
    elastic += o.elastic;
    fracture += o.fracture;
    friction += o.friction;
    damaged += o.damaged;
    failed += o.failed;
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile InterfaceSums& o) volatile {
    elastic += o.elastic;
    fracture += o.fracture;
    friction += o.friction;
    damaged += o.damaged;
    failed += o.failed;
  }
#endif
};

// The interfaces' energies and counts (InterfaceSums).
template <int D>
InterfaceSums interface_state(const Model<D>& m) {
  const auto x = m.x;
  const InterfaceData<D> in = m;
  InterfaceSums out;
  Kokkos::parallel_reduce(
      "fdem::interface_state", Kokkos::RangePolicy<ExecSpace>(0, m.owned_ifaces()),
      KOKKOS_LAMBDA(const int q, InterfaceSums& s) {
        double xa[D][D], xb[D][D], n[D], ap;
        gather_interface<D>(x, in.iface, q, xa, xb);
        interface_frame<D>(xa, xb, 1.0, n, ap);
        ap = in.iarea(q);
        const bool handed = in.icontact(q);  // carries nothing, stores nothing
        bool any = false, all = true;
        for (int k = 0; k < D; ++k) {
          const CohesivePoint h = load_point(in.ihist, q, k);
          double d[D], dn = 0, ds2 = 0;
          for (int i = 0; i < D; ++i) {
            d[i] = xb[k][i] - xa[k][i];
            dn += d[i] * n[i];
          }
          for (int i = 0; i < D; ++i) ds2 += (d[i] - dn * n[i]) * (d[i] - dn * n[i]);
          const double dmg = cohesive_damage(h);
          const CohesiveParams p = in.params(q);
          if (!handed) s.elastic += ap * cohesive_stored(p, dn, kmath::sqrt(ds2), dmg);
          s.fracture += ap * cohesive_dissipation(h);
          if (in.has_slip() && h.dm0 > 0.0 && p.tanphir >= 0.0) {  // the residual friction
            const SlipPoint<D> sl = load_slip<D>(in.islip, q, k);
            double e[D];
            if (!handed) s.elastic += ap * 0.5 * p.ks * elastic_slip<D>(n, d, sl, e);
            s.friction += ap * sl.wf;
          }
          any = any || dmg > 0.0;
          all = all && dmg >= 1.0;
        }
        s.damaged += any ? 1.0 : 0.0;
        s.failed += all ? 1.0 : 0.0;
      },
      out);
  return out;
}

// Sum of the internal force over a node list (reaction of a velocity BC = minus this sum).
template <int D>
void node_list_force(const Model<D>& m, const Kokkos::View<int*>& nodes, double (&out)[3]) {
  auto f = m.f;
  SumN<3> s;
  Kokkos::parallel_reduce(
      "fdem::node_list_force", Kokkos::RangePolicy<ExecSpace>(0, nodes.extent(0)),
      KOKKOS_LAMBDA(const int j, SumN<3>& a) {
        for (int k = 0; k < D; ++k) a.v[k] += f(nodes(j), k);
      },
      s);
  for (int k = 0; k < 3; ++k) out[k] = s.v[k];
}

// Mean displacement of a node list (monitors: crack mouth opening, deflections).
template <int D>
void node_list_displacement(const Model<D>& m, const Kokkos::View<int*>& nodes, double (&out)[3]) {
  auto x = m.x;
  auto X = m.X;
  SumN<3> s;
  Kokkos::parallel_reduce(
      "fdem::node_list_displacement", Kokkos::RangePolicy<ExecSpace>(0, nodes.extent(0)),
      KOKKOS_LAMBDA(const int j, SumN<3>& a) {
        for (int k = 0; k < D; ++k) a.v[k] += x(nodes(j), k) - X(nodes(j), k);
      },
      s);
  const double n = nodes.extent(0) > 0 ? static_cast<double>(nodes.extent(0)) : 1.0;
  for (int k = 0; k < 3; ++k) out[k] = s.v[k] / n;
}

// Per-element Cauchy stress (6 components) and per-interface mean damage, for snapshots.
template <int D>
void element_stress(const Model<D>& m, const Kokkos::View<double* [6]>& out) {
  const auto x = m.x;
  const ElementData<D> el = m;
  Kokkos::parallel_for(
      "fdem::element_stress", Kokkos::RangePolicy<ExecSpace>(0, m.ne), KOKKOS_LAMBDA(const int e) {
        double xe[D + 1][D], G[D][D], F[D][D], s6[6];
        gather_element<D>(x, el, e, xe, G);
        deformation_gradient<D>(xe, G, F);
        const int mt = el.emat(e);
        cauchy_stress<D>(F, el.mat(mt, 0), el.mat(mt, 1), el.plane_stress, s6);
        for (int c = 0; c < 6; ++c) out(e, c) = s6[c];
      });
}

template <int D>
void interface_damage(const Model<D>& m, const Kokkos::View<double*>& out) {
  auto ihist = m.ihist;
  Kokkos::parallel_for(
      "fdem::interface_damage", Kokkos::RangePolicy<ExecSpace>(0, m.ni), KOKKOS_LAMBDA(const int q) {
        double s = 0;
        for (int k = 0; k < D; ++k)
          s += cohesive_damage(load_point(ihist, q, k));
        out(q) = s / D;
      });
}

}  // namespace fdem

namespace Kokkos {
template <>
struct reduction_identity<fdem::InterfaceSums> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::InterfaceSums sum() { return fdem::InterfaceSums(); }
};
}  // namespace Kokkos
