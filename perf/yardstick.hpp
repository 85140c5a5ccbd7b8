#pragma once
// The yardstick of the step benchmarks: a minimal fused explicit step on the same mesh and in the
// same memory order as the full step, so that a full-step figure can be quoted as a ratio to what
// the simplest physics of the method costs on the same machine, in the same run.
//
// Physics, the least that still does the method's work per element and per interface:
//   - bulk: small-strain constant-strain simplex, isotropic (lambda, mu of material 0),
//     displacements u, reference gradients of the model (ElementData::grad), f_a = -V sigma g_a;
//   - interfaces: one point per node pair (D per interface, as the full step), normal fixed at
//     the reference configuration, opening d_n = (u_B - u_A) . n, a mode-I linear-softening
//     damage law with one history value per point (written only when it grows), penalty in
//     compression, no shear;
//   - nodes: local damping alpha |f| sign(v), leap-frog, no boundary conditions;
//   - no branch on a sign that changes at random from item to item (damping, the penalty in
//     compression): selects, as the full step makes them (fdem::kselect);
//   - the scatter as the full step does it (fdem::ForceScatter: a copy per thread but the first on
//     host backends, atomics on GPUs), one access() per chunk of kChunk elements done with the
//     interfaces whose side A lies in it (Model::ichunk), then one contribute and a node pass that
//     zeroes the forces.
// Memory per element-step it must move: u, v, f, 1/m of the nodes, connectivity, gradients and
// volume of the elements, node pairs, normal, area and damage of the interfaces.
#include <Kokkos_Core.hpp>

#include "kernels/forces.hpp"
#include "kernels/model.hpp"

namespace fdem_bench {

// Inverse masses and the interfaces' reference normals of the yardstick (a free function: CUDA
// does not allow a device lambda in a constructor).
template <int D>
void yardstick_setup(const fdem::Model<D>& m, const Kokkos::View<double*>& minv,
                     const Kokkos::View<double* [D]>& nrm) {
  const int nn = m.nn, ni = m.ni;
  const auto mass = m.mass;
  const auto mi = minv;
  Kokkos::parallel_for(
      "ys::minv", Kokkos::RangePolicy<fdem::ExecSpace>(0, nn),
      KOKKOS_LAMBDA(const int i) { mi(i) = mass(i) > 0 ? 1.0 / mass(i) : 0.0; });
  const auto X = m.X;
  const auto ifc = m.iface;
  const auto n = nrm;
  Kokkos::parallel_for(
      "ys::normals", Kokkos::RangePolicy<fdem::ExecSpace>(0, ni), KOKKOS_LAMBDA(const int q) {
        double t[D], s[D], nq[D];
        for (int i = 0; i < D; ++i) t[i] = X(ifc(q, 1), i) - X(ifc(q, 0), i);
        if constexpr (D == 2) {
          nq[0] = t[1];
          nq[1] = -t[0];
        } else {
          for (int i = 0; i < D; ++i) s[i] = X(ifc(q, 2), i) - X(ifc(q, 0), i);
          nq[0] = t[1] * s[2] - t[2] * s[1];
          nq[1] = t[2] * s[0] - t[0] * s[2];
          nq[2] = t[0] * s[1] - t[1] * s[0];
        }
        double l = 0;
        for (int i = 0; i < D; ++i) l += nq[i] * nq[i];
        l = l > 0 ? 1.0 / fdem::kmath::sqrt(l) : 0.0;
        for (int i = 0; i < D; ++i) n(q, i) = nq[i] * l;
      });
}

template <int D>
struct Yardstick {
  using View2 = Kokkos::View<double* [D]>;
  int nn = 0, ne = 0, ni = 0, nbc = 0;
  bool fused = false;
  View2 u, v, f;
  Kokkos::View<double*> minv;
  Kokkos::View<int* [D + 1]> elem;
  Kokkos::View<double* [D][D]> grad;
  Kokkos::View<double*> vol;
  Kokkos::View<int* [2 * D]> iface;
  Kokkos::View<int*> ichunk;
  View2 nrm;
  Kokkos::View<double*> area;
  View2 dmg;
  fdem::ForceScatter<D> sf;
  double lam = 0, mu = 0, kn = 0, d0 = 0, df = 0, alpha = 0.7, dt = 0;

  // From a model built by the solver on the same mesh: its connectivity, gradients, volumes,
  // interface node pairs, areas and chunk index are shared (same memory order); u, v, damage and
  // the normals are the yardstick's own. v starts as the model's velocities.
  explicit Yardstick(const fdem::Model<D>& m, double dt_)
      : nn(m.nn), ne(m.ne), ni(m.ni), u("ys::u", m.nn), v("ys::v", m.nn), f("ys::f", m.nn),
        minv("ys::minv", m.nn), elem(m.elem), grad(m.grad), vol(m.vol0), iface(m.iface),
        ichunk(m.ichunk), nrm("ys::n", m.ni), area(m.iarea), dmg("ys::d", m.ni), sf(f), dt(dt_) {
    auto mh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.mat);
    lam = mh(0, 0);
    mu = mh(0, 1);
    kn = m.coh.kn;
    const double ft = m.coh.ft > 0 ? m.coh.ft : 1e6;
    const double G = m.coh.Gnc > 0 ? m.coh.Gnc : 100.0;
    d0 = ft / kn;
    df = 2.0 * G / ft > d0 ? 2.0 * G / ft : 2.0 * d0;
    nbc = (ne + fdem::kChunk - 1) / fdem::kChunk;
    fused = fdem::kChunk > 1 && static_cast<int>(ichunk.extent(0)) == nbc + 1;
    Kokkos::deep_copy(v, m.v);
    yardstick_setup<D>(m, minv, nrm);
    Kokkos::fence();
  }

  template <class Acc>
  KOKKOS_INLINE_FUNCTION void bulk(const int e, Acc& acc) const {
    double g[D + 1][D], ue[D + 1][D];
    for (int j = 0; j < D; ++j) g[0][j] = 0;
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j) {
        g[b + 1][j] = grad(e, b, j);
        g[0][j] -= g[b + 1][j];
      }
    for (int a = 0; a < D + 1; ++a)
      for (int i = 0; i < D; ++i) ue[a][i] = u(elem(e, a), i);
    double eps[D][D], tr = 0;
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) {
        double s = 0;
        for (int a = 0; a < D + 1; ++a) s += 0.5 * (ue[a][i] * g[a][j] + ue[a][j] * g[a][i]);
        eps[i][j] = s;
      }
    for (int i = 0; i < D; ++i) tr += eps[i][i];
    const double V = vol(e);
    for (int a = 0; a < D + 1; ++a) {
      const int node = elem(e, a);
      for (int i = 0; i < D; ++i) {
        double s = lam * tr * g[a][i];
        for (int j = 0; j < D; ++j) s += 2.0 * mu * eps[i][j] * g[a][j];
        acc(node, i) += -V * s;
      }
    }
  }

  template <class Acc>
  KOKKOS_INLINE_FUNCTION void interface(const int q, Acc& acc) const {
    double n[D];
    for (int i = 0; i < D; ++i) n[i] = nrm(q, i);
    const double A = area(q);
    for (int k = 0; k < D; ++k) {
      const int a = iface(q, k), b = iface(q, D + k);
      double dn = 0;
      for (int i = 0; i < D; ++i) dn += (u(b, i) - u(a, i)) * n[i];
      double d = dmg(q, k);
      if (dn > d0) {
        const double t = dn < df ? kn * d0 * (df - dn) / (df - d0) : 0.0;
        const double dnew = 1.0 - t / (kn * dn);
        if (dnew > d) {
          d = dnew;
          dmg(q, k) = d;
        }
      }
      const double t = fdem::kselect(dn > 0, 1.0 - d, 1.0) * kn * dn;  // no branch on the sign
      for (int i = 0; i < D; ++i) {
        acc(a, i) += t * A * n[i];
        acc(b, i) -= t * A * n[i];
      }
    }
  }

  KOKKOS_INLINE_FUNCTION void operator()(const int c) const {
    auto acc = sf.access();
    if (fused) {
      const int e1 = c * fdem::kChunk + fdem::kChunk < ne ? c * fdem::kChunk + fdem::kChunk : ne;
      for (int e = c * fdem::kChunk; e < e1; ++e) bulk(e, acc);
      for (int q = ichunk(c); q < ichunk(c + 1); ++q) interface(q, acc);
    } else if (c < nbc) {
      const int e1 = c * fdem::kChunk + fdem::kChunk < ne ? c * fdem::kChunk + fdem::kChunk : ne;
      for (int e = c * fdem::kChunk; e < e1; ++e) bulk(e, acc);
    } else {
      const int i0 = (c - nbc) * fdem::kChunk, i1 = i0 + fdem::kChunk < ni ? i0 + fdem::kChunk : ni;
      for (int q = i0; q < i1; ++q) interface(q, acc);
    }
  }

  // One step: forces (fused pass, scatter), contribute, node update (which zeroes f).
  void step() {
    const int nic = (ni + fdem::kChunk - 1) / fdem::kChunk;
    sf.reset();
    Kokkos::parallel_for("ys::forces", Kokkos::RangePolicy<fdem::ExecSpace>(0, fused ? nbc : nbc + nic), *this);
    fdem::contribute_forces<D>(f, sf);
    const auto uu = u, vv = v, ff = f;
    const auto mi = minv;
    const double h = dt, al = alpha;
    Kokkos::parallel_for(
        "ys::nodes", Kokkos::RangePolicy<fdem::ExecSpace>(0, nn), KOKKOS_LAMBDA(const int i) {
          for (int k = 0; k < D; ++k) {
            double fk = ff(i, k);
            const double vk = vv(i, k);
            fk -= al * fdem::kmath::fabs(fk) * static_cast<double>((vk > 0) - (vk < 0));  // no branches
            const double vn = vk + h * fk * mi(i);
            vv(i, k) = vn;
            uu(i, k) += h * vn;
            ff(i, k) = 0.0;
          }
        });
  }

  // Bytes per step it must move (the benchmarks' counting rule: every array element a pass touches
  // once per pass; node data gathered once per pass). T: scatter copies (threads - 1 on host
  // backends: the first thread adds into f itself; 0 on GPUs).
  double bytes(int T) const {
    const double nd = 8.0 * D;
    const double forces = nn * nd                                 // u gathered
                          + ne * (4.0 * (D + 1) + 8.0 * D * D + 8)  // connectivity, gradients, volume
                          + ni * (4.0 * 2 * D + nd + 8 + 2 * 8.0 * D);  // pairs, normal, area, damage
    const double scatter = (T > 0 ? T * nn * nd + T * nn * nd + T * nn * nd + 2 * nn * nd : 0.0);
    const double nodes = nn * (2 * nd + 2 * nd + 2 * nd + 8);  // u, v read+write, f read+zero, 1/m
    return forces + scatter + nodes;
  }
};

}  // namespace fdem_bench
