#pragma once
// The internal forces of one explicit step (docs/theory.md sections 2 to 4): bulk elements
// (kernels/elastic.hpp) and cohesive interfaces (kernels/interface.hpp), scattered into the nodal
// forces: on host backends in one fused pass over element chunks, elsewhere in two kernels.
#include "kernels/cohesive.hpp"
#include "kernels/elastic.hpp"
#include "kernels/interface.hpp"
#include "kernels/lanes.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Chunk of items per work item for the scatter: 256 on host backends (one access() per chunk),
// 1 on GPUs (one thread per item, atomics).
constexpr int kChunk =
    Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible ? kScatterChunk : 1;

// Arguments and results by value of the interface kernel's out-of-line branches
// (LeanInterfaceForces::fail and friction_step).
template <int D>
struct VecArg {
  double v[D];
};
template <int D>
struct FrictionStep {
  double f[D], dg[D];  // the increments of fa (and -fb) and of dU/dn
  double wd;           // the fracture dissipation after the step
};

// The bulk part of the force pass: element e's forces into the scatter accessor.
template <int D>
struct BulkForces {
  Kokkos::View<double* [D]> x;
  ElementData<D> el;

  template <class Acc>
  KOKKOS_INLINE_FUNCTION void operator()(const int e, Acc& acc) const {
    double xe[D + 1][D], G[D][D], fe[D + 1][D];
    gather_element<D>(x, el, e, xe, G);
    const int mt = el.emat(e);
    element_forces<D>(xe, G, el.vol0(e), el.mat(mt, 0), el.mat(mt, 1), fe);
    for (int a = 0; a < D + 1; ++a)
      for (int i = 0; i < D; ++i) acc(el.elem(e, a), i) += fe[a][i];
  }

#if FDEM_HOST_LANES
  // Elements e0 .. e0 + W - 1 at once (W: the lanes M's width), scattered element after element
  // as operator() would. M = HostLanes: the same forces as operator() gives each, to the bit.
  // M = MixedLanes (FusedForceKernel::mixed): positions and the deformation gradient in double,
  // the displacement gradient H = F - I rounded to floats, the strain, stress and forces in floats
  // (element_forces_h), the forces added to the double sums.
  template <class M, class Acc>
  void batch(const int e0, Acc& acc) const {
    constexpr int W = M::kWidth;
    using L = Lanes<W>;  // the gather's doubles
    L xe[D + 1][D], G[D][D];
    M fe[D + 1][D];
    for (int a = 0; a < D + 1; ++a)
      for (int i = 0; i < D; ++i) xe[a][i] = L::gather([&](int w) { return x(el.elem(e0 + w, a), i); });
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j) G[b][j] = L::gather([&](int w) { return el.grad(e0 + w, b, j); });
    const M vol = M::gather([&](int w) { return el.vol0(e0 + w); });
    const M lam = M::gather([&](int w) { return el.mat(el.emat(e0 + w), 0); });
    const M mu = M::gather([&](int w) { return el.mat(el.emat(e0 + w), 1); });
    if constexpr (std::is_same_v<M, L>) {
      element_forces<D, L>(xe, G, vol, lam, mu, fe);
    } else {
      L F[D][D];
      M H[D][D], Gm[D][D];
      deformation_gradient<D, L>(xe, G, F);
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
          H[i][j] = lanes_as<M>(i == j ? F[i][j] - L(1.0) : F[i][j]);
          Gm[i][j] = lanes_as<M>(G[i][j]);
        }
      element_forces_h<D, M>(H, Gm, vol, lam, mu, fe);
    }
    for (int w = 0; w < W; ++w)
      for (int a = 0; a < D + 1; ++a)
        for (int i = 0; i < D; ++i) acc(el.elem(e0 + w, a), i) += fe[a][i][w];
  }
#endif
};

// The interface part: interface q's history and, while it carries, its forces. PerIface: the
// interfaces take their own parameters (InterfaceData::params); else all take InterfaceData::coh.
// Fric: the model has slip states (InterfaceData::islip): a point that has begun to soften reads
// and writes its slip state too (the others never touch it).
template <int D, bool PerIface, bool Fric>
struct InterfaceForces {
  Kokkos::View<double* [D]> x;
  Kokkos::View<double* [D]> v;  // v(n - 1/2): the step's motion of a softening point's node pair (Fric)
  InterfaceData<D> in;

  template <class Acc>
  KOKKOS_INLINE_FUNCTION void operator()(const int q, Acc& acc) const {
    // Model::icontact: nonzero once the interface carries nothing (handed over to contact: its
    // faces are in contact instead; or, without contact, come apart for good: interface_apart).
    if (in.icontact(q)) return;
    const bool handover = in.contact_handover;
    double xa[D][D], xb[D][D], fa[D][D], fb[D][D];
    CohesivePoint h[D];
    SlipPoint<D> sl[D];
    gather_interface<D>(x, in.iface, q, xa, xb);
    for (int k = 0; k < D; ++k) h[k] = load_point(in.ihist, q, k);
    const CohesiveParams p = PerIface ? in.params(q) : in.coh;
    // the slip state and the step's motion of a softening point with a residual friction only
    // (a point that has not begun to soften, or under the paper's law, reads neither)
    const bool slips = Fric && p.tanphir >= 0.0;
    for (int k = 0; k < D; ++k) sl[k] = slips && h[k].dm0 > 0.0 ? load_slip<D>(in.islip, q, k) : zero_slip<D>();
    if (interface_apart<D>(xa, xb, h)) {
      interface_fail_all<D, Fric>(xa, xb, p, h, sl);
      for (int k = 0; k < D; ++k) {
        store_point(in.ihist, q, k, h[k]);
        if (slips) store_slip<D>(in.islip, q, k, sl[k]);
      }
      if (handover) Kokkos::atomic_exchange(&in.icontact_pending(), 1);
      else in.icontact(q) = 1;
      return;
    }
    CohesivePoint h0[D];
    for (int k = 0; k < D; ++k) h0[k] = h[k];
    double du[D][D];  // x(n) - x(n-1) of each node pair: v(n - 1/2) dt (softening points, Fric)
    for (int k = 0; k < D; ++k)
      for (int i = 0; i < D; ++i)
        du[k][i] = slips && h[k].dm0 > 0.0 ? (v(in.iface(q, D + k), i) - v(in.iface(q, k), i)) * in.step_dt : 0.0;
    const double dmean = interface_forces<D, Fric>(xa, xb, in.iarea(q), p, h, sl, fa, fb, du);
    if (handover && dmean >= 1.0 && interface_parted<D>(xa, xb, in.handover_slip))
      Kokkos::atomic_exchange(&in.icontact_pending(), 1);
    for (int k = 0; k < D; ++k) {
      // the history is written only when the step changed it (most points of a run stay
      // undamaged or unload: no write traffic for them); the slip state of a softening point
      // (its slip follows the faces' every move)
      if (!same_point(h[k], h0[k])) store_point(in.ihist, q, k, h[k]);
      if (slips && h[k].dm0 > 0.0) store_slip<D>(in.islip, q, k, sl[k]);
      for (int i = 0; i < D; ++i) {
        acc(in.iface(q, k), i) += fa[k][i];
        acc(in.iface(q, D + k), i) += fb[k][i];
      }
    }
  }

#if FDEM_HOST_LANES
  // Whether interface q can take the lanes' path in this step, as far as its history tells (batch:
  // its separations and damage decide the rest): not handed over, and each point either intact
  // (dm0 <= 0) or initiated with no strength change (rescale 1) and no residual friction to step.
  // h: its points' histories.
  KOKKOS_INLINE_FUNCTION bool lane_ready(const int q, const CohesiveParams& p, CohesivePoint (&h)[D]) const {
    for (int k = 0; k < D; ++k) h[k] = load_point(in.ihist, q, k);
    if (in.icontact(q)) return false;
    bool ok = true;
    for (int k = 0; k < D; ++k) {
      if (h[k].dm0 > 0.0)
        ok = ok && p.rescale == 1.0 && !(Fric && p.tanphir >= 0.0);
      else
        ok = ok && h[k].dm0 <= 0.0;  // (a NaN takes the scalar code)
    }
    return ok;
  }

  // The damage D of point k of the lanes' interfaces (cohesive_damage, its quotient in the lanes).
  template <class L = HostLanes>
  static L lane_damage(const CohesivePoint (&h)[L::kWidth][D], int k) {
    const L dmax = L::gather([&](int w) { return h[w][k].dmax; });
    const L dm0 = L::gather([&](int w) { return h[w][k].dm0; });
    const L dmf = L::gather([&](int w) { return h[w][k].dmf; });
    const L part = dmf * (dmax - dm0) / (dmax * (dmf - dm0));
    return L::gather([&](int w) {
      const CohesivePoint& s = h[w][k];
      return s.dm0 <= 0.0 || s.dmax <= s.dm0 ? 0.0 : (s.dmax >= s.dmf ? 1.0 : part[w]);
    });
  }

  // The tractions of point k of the lanes' interfaces as cohesive_update gives them while the
  // history stays, tn = (dn > 0 ? 1 - D : 1) kn dn and kss = (1 - D) ks, and whether each lane's
  // point keeps its history (fast; ds: |the tangential separation|). Where no lane's point k has
  // initiated (D = 0), tn = kn dn and kss = ks: the same bits, without the damage's quotient.
  template <class L = HostLanes>
  static void lane_tractions(const CohesiveParams (&pw)[L::kWidth], const CohesivePoint (&h)[L::kWidth][D],
                             const int k, const L& kn, const L& ks, const L& dn, const L& ds,
                             bool (&fast)[L::kWidth], L& tn, L& kss) {
    bool intact = true;
    for (int w = 0; w < L::kWidth; ++w) intact = intact && !(fast[w] && h[w][k].dm0 > 0.0);
    if (intact) {
      for (int w = 0; w < L::kWidth; ++w)
        if (fast[w]) fast[w] = keeps_history(pw[w], h[w][k], dn[w], ds[w], 0.0);
      tn = kn * dn;
      kss = ks;
      return;
    }
    const L dnp = L::gather([&](int w) { return kselect(dn[w] > 0.0, dn[w], 0.0); });
    const L dm = lane_sqrt(dnp * dnp + ds * ds);  // equivalent_separation
    const L dmg = lane_damage<L>(h, k);
    for (int w = 0; w < L::kWidth; ++w)  // (failed: the scalar code sees whether it has come apart)
      if (fast[w]) fast[w] = dmg[w] < 1.0 && keeps_history(pw[w], h[w][k], dn[w], ds[w], dm[w]);
    const L gl = 1.0 - dmg;
    const L sel = L::gather([&](int w) { return kselect(dn[w] > 0.0, gl[w], 1.0); });
    tn = sel * kn * dn;
    kss = gl * ks;
  }

  // Interfaces q0 .. q0 + W - 1 at once (W: the lanes M's width). Those whose every point keeps
  // its history in this step take the lanes' forces: an intact point that does not meet its
  // initiation test, or an initiated one below its largest separation (unloading or reloading: its
  // damage D stays), with cohesive_update's tractions tn = (dn > 0 ? 1 - D : 1) kn dn and
  // kss = (1 - D) ks, and no history written. The others (initiating, damage growing, failed,
  // handed over, residual friction) go through operator() in their turn, so that the scatter keeps
  // the interfaces' order.
  // M = HostLanes: the same operations as operator() in the same order, so the same bits.
  // M = MixedLanes (FusedForceKernel::mixed): the lanes in floats, from the separations and the
  // positions relative to each interface's first A node formed in double (a separation far below
  // the coordinates' rounding keeps its relative precision); the decisions from the float
  // separations; the forces added to the double sums.
  template <class M, class Acc>
  void batch(const int q0, Acc& acc) const {
    constexpr int W = M::kWidth;
    using L = Lanes<W>;  // the gather's doubles
    constexpr bool same = std::is_same_v<M, L>;
    bool fast[W], any = false;
    CohesiveParams pw[W];
    CohesivePoint h[W][D];
    for (int w = 0; w < W; ++w) {
      pw[w] = PerIface ? in.params(q0 + w) : in.coh;
      fast[w] = lane_ready(q0 + w, pw[w], h[w]);
      any = any || fast[w];
    }
    if (!any) {
      for (int w = 0; w < W; ++w) (*this)(q0 + w, acc);
      return;
    }
    const M kn = M::gather([&](int w) { return pw[w].kn; });
    const M ks = M::gather([&](int w) { return pw[w].ks; });
    const M ap = M::gather([&](int w) { return in.iarea(q0 + w); });
    M xa[D][D], xb[D][D], d[D][D];
    {
      L da[D][D], db[D][D];
      for (int k = 0; k < D; ++k)
        for (int i = 0; i < D; ++i) {
          da[k][i] = L::gather([&](int w) { return x(in.iface(q0 + w, k), i); });
          db[k][i] = L::gather([&](int w) { return x(in.iface(q0 + w, D + k), i); });
        }
      for (int k = 0; k < D; ++k)
        for (int i = 0; i < D; ++i) {
          d[k][i] = lanes_as<M>(db[k][i] - da[k][i]);
          xa[k][i] = lanes_as<M>(same ? da[k][i] : da[k][i] - da[0][i]);
          xb[k][i] = lanes_as<M>(same ? db[k][i] : db[k][i] - da[0][i]);
        }
    }
    M n[D], ap_cur, g[D], fa[D][D], fb[D][D];
    interface_frame<D, M>(xa, xb, M(1.0), n, ap_cur);
    for (int i = 0; i < D; ++i) g[i] = 0.0;
    for (int k = 0; k < D; ++k) {
      M dn, ds[D], ds2;
      point_separation<D, M>(d[k], n, dn, ds, ds2);
      M tn, kss;
      lane_tractions<M>(pw, h, k, kn, ks, dn, lane_sqrt(ds2), fast, tn, kss);
      point_forces<D, M>(d[k], n, ap, tn, kss, dn, ds, fa[k], fb[k], g);
    }
    M e[D - 1][D], dm[D][D];
    mid_edges<D, M>(xa, xb, e);
    interface_normal_forces<D, M>(e, n, g, dm);
    const typename M::Scalar half = 0.5;  // (the forces' last difference in the lanes' precision)
    for (int w = 0; w < W; ++w) {
      if (!fast[w]) {
        (*this)(q0 + w, acc);
        continue;
      }
      const int q = q0 + w;
      for (int k = 0; k < D; ++k)
        for (int i = 0; i < D; ++i) {
          acc(in.iface(q, k), i) += fa[k][i][w] - half * dm[k][i][w];
          acc(in.iface(q, D + k), i) += fb[k][i][w] - half * dm[k][i][w];
        }
    }
  }
#endif
};

// The interface part point by point, for the GPU (the split path of run_force_kernels): the
// same forces and histories as InterfaceForces (to round-off: each node pair takes its point's
// forces and the normal's share in two adds), with only one point's history, slip state and forces
// live at a time, the forces scattered as soon as they are known, and the positions and the
// parameters read again where they are needed rather than held: on CUDA the 3D kernel of one
// interface material takes 127 registers without spills where the fused kernel took 208-220
// (docs/cuda.md, "Kernel resources").
template <int D, bool PerIface, bool Fric>
struct LeanInterfaceForces {
  Kokkos::View<double* [D]> x;
  Kokkos::View<double* [D]> v;
  InterfaceData<D> in;

  // separation of point k: its B node's position less its A node's (read again where needed
  // rather than held: the positions do not change in the force pass)
  KOKKOS_INLINE_FUNCTION void separation(int q, int k, double (&d)[D]) const {
    const int na = in.iface(q, k), nb = in.iface(q, D + k);
    for (int i = 0; i < D; ++i) d[i] = x(nb, i) - x(na, i);
  }

  // The residual friction of point k of interface q (interface_point_forces' Friction policy),
  // out of line with its arguments and results by value (a softening point's branch: on CUDA its
  // registers do not add to the common path's, and no array of the caller needs an address, which
  // would put it in local memory; docs/cuda.md, "Kernel resources"). It reads what the fused
  // kernel holds in arrays: the slip state (zero for a point fresh in this step), the separation
  // and the step's motion of the node pair, and stores the slip state; it returns the increments
  // of the forces and of dU/dn (the same arithmetic: the caller adds f to fa, takes it from fb
  // and adds dg to g) and the fracture dissipation.
  KOKKOS_FUNCTION FDEM_NOINLINE FrictionStep<D> friction_step(const int q, const int k, const VecArg<D> n,
                                                              const double dn, const double ap, const double tc,
                                                              const double dD, const bool fresh,
                                                              const double wd) const {
    const CohesiveParams p = PerIface ? in.params(q) : in.coh;
    const int na = in.iface(q, k), nb = in.iface(q, D + k);
    SlipPoint<D> sl = fresh ? zero_slip<D>() : load_slip<D>(in.islip, q, k);
    double d[D], ds[D], du[D], fb[D];
    separation(q, k, d);
    for (int i = 0; i < D; ++i) {
      ds[i] = d[i] - dn * n.v[i];  // (as interface_point_forces has it)
      du[i] = fresh ? 0.0 : (v(nb, i) - v(na, i)) * in.step_dt;
    }
    FrictionStep<D> r;
    for (int i = 0; i < D; ++i) r.f[i] = fb[i] = r.dg[i] = 0.0;
    CohesivePoint h{};
    h.wd = wd;
    residual_friction<D>(p, n.v, d, dn, ds, ap, tc, dD, du, fresh, h, sl, r.f, fb, r.dg);
    store_slip<D>(in.islip, q, k, sl);
    r.wd = h.wd;
    return r;
  }
  struct PointSlip {
    const LeanInterfaceForces& f;
    int q, k;
    bool stored = false;  // the friction step ran (and stored the slip state)
    KOKKOS_INLINE_FUNCTION void friction(const CohesiveParams&, const double (&n)[D], const double (&)[D], double dn,
                                         const double (&)[D], double ap, double tc, double dD, bool fresh,
                                         CohesivePoint& h, double (&fa)[D], double (&fb)[D], double (&g)[D]) {
      VecArg<D> nv;
      for (int i = 0; i < D; ++i) nv.v[i] = n[i];
      const FrictionStep<D> r = f.friction_step(q, k, nv, dn, ap, tc, dD, fresh, h.wd);
      for (int i = 0; i < D; ++i) {
        fa[i] += r.f[i];
        fb[i] -= r.f[i];
        g[i] += r.dg[i];
      }
      h.wd = r.wd;
      stored = true;
    }
  };

  // Interface q has come apart (normal n): its points fail, and it is handed over (or, without
  // contact, carries nothing from now on). Not inlined: a rare branch, so that on CUDA the
  // registers of its points' updates do not add to those of the common path (docs/cuda.md,
  // "Kernel resources").
  KOKKOS_FUNCTION FDEM_NOINLINE void fail(const int q, const VecArg<D> n) const {
    for (int k = 0; k < D; ++k) {
      const CohesiveParams p = PerIface ? in.params(q) : in.coh;
      const bool slips = Fric && p.tanphir >= 0.0;
      CohesivePoint h = load_point(in.ihist, q, k);
      SlipPoint<D> sl = slips && h.dm0 > 0.0 ? load_slip<D>(in.islip, q, k) : zero_slip<D>();
      double d[D];
      separation(q, k, d);
      interface_fail_point<D, Fric>(d, n.v, p, h, sl);
      store_point(in.ihist, q, k, h);
      if (slips) store_slip<D>(in.islip, q, k, sl);
    }
    if (in.contact_handover) Kokkos::atomic_exchange(&in.icontact_pending(), 1);
    else in.icontact(q) = 1;
  }

  template <class Acc>
  KOKKOS_INLINE_FUNCTION void operator()(const int q, Acc& acc) const {
    if (in.icontact(q)) return;
    double n[D];  // the unit normal: all the points need of the positions but their own
    bool apart;
    {
      double xa[D][D], xb[D][D], dmg[D], ap_cur;
      gather_interface<D>(x, in.iface, q, xa, xb);
      interface_frame<D>(xa, xb, 1.0, n, ap_cur);
      for (int k = 0; k < D; ++k) dmg[k] = cohesive_damage(load_point(in.ihist, q, k));
      apart = interface_apart<D>(xa, xb, dmg);
    }
    if (apart) {
      VecArg<D> nv;
      for (int i = 0; i < D; ++i) nv.v[i] = n[i];
      fail(q, nv);
      return;
    }
    double g[D], dsum = 0;  // dU/dn
    for (int i = 0; i < D; ++i) g[i] = 0;
    for (int k = 0; k < D; ++k) {
      // the parameters again for each point (PerIface: from the table; held through the points,
      // they cost 20 registers)
      const CohesiveParams p = PerIface ? in.params(q) : in.coh;
      const bool slips = Fric && p.tanphir >= 0.0;
      const double ap = in.iarea(q);  // (read again for each point, as the parameters)
      const int na = in.iface(q, k), nb = in.iface(q, D + k);
      CohesivePoint h = load_point(in.ihist, q, k);
      const bool soft = slips && h.dm0 > 0.0;
      double d[D], fa[D], fb[D];
      separation(q, k, d);
      PointSlip fr{*this, q, k};
      dsum += interface_point_forces<D, Fric>(d, n, ap, p, h, fr, fa, fb, g);
      // the history as read (again: held through the update, it costs registers) decides the write
      if (!same_point(h, load_point(in.ihist, q, k))) store_point(in.ihist, q, k, h);
      // a point that began to soften in this step with no damage yet: its slip state starts at
      // zero (the friction step stores the others'; a softening point's state stays otherwise)
      if (slips && h.dm0 > 0.0 && !soft && !fr.stored) store_slip<D>(in.islip, q, k, zero_slip<D>());
      // fb is -fa, bit for bit (negation is exact and rounding symmetric: the friction's
      // fa + f and -fa - f agree); not held through the point's update
      for (int i = 0; i < D; ++i) {
        acc(na, i) += fa[i];
        acc(nb, i) += -fa[i];
      }
    }
    double dm[D][D];
    {
      double xa[D][D], xb[D][D], e[D - 1][D];  // read again: held through the points, they cost registers
      gather_interface<D>(x, in.iface, q, xa, xb);
      mid_edges<D>(xa, xb, e);
      interface_normal_forces<D>(e, n, g, dm);
    }
    for (int k = 0; k < D; ++k)
      for (int i = 0; i < D; ++i) {
        acc(in.iface(q, k), i) += -0.5 * dm[k][i];
        acc(in.iface(q, D + k), i) += -0.5 * dm[k][i];
      }
    if (in.contact_handover && dsum / D >= 1.0) {
      double xa[D][D], xb[D][D];
      gather_interface<D>(x, in.iface, q, xa, xb);
      if (interface_parted<D>(xa, xb, in.handover_slip)) Kokkos::atomic_exchange(&in.icontact_pending(), 1);
    }
  }
};

// Host backends: work item c is element chunk c with the interfaces whose side A lies in it
// (Model::ichunk: one pass over the nodes, side A's positions and forces are still in cache).
// lanes: kLanes items at a time (BulkForces::batch, InterfaceForces::batch), the same results to
// the bit as one at a time (false: the benchmarks' and tests' reference). mixed (with lanes; case
// key precision = "mixed", Model::mixed_precision): kMixedLanes items at a time in floats first
// (batch<MixedLanes>), what a chunk leaves over as with lanes alone.
template <int D, bool PerIface, bool Fric>
struct FusedForceKernel {
  BulkForces<D> bulk;
  InterfaceForces<D, PerIface, Fric> iface;
  ForceScatter<D> sf;
  bool lanes = true;
  bool mixed = false;

  KOKKOS_INLINE_FUNCTION void operator()(const int c) const {
    auto acc = sf.access();
    const int e1 = kmin((c + 1) * kChunk, bulk.el.bulk_elems());
    int e = c * kChunk;
    const int q1 = iface.in.ichunk(c + 1);
    int q = iface.in.ichunk(c);
#if FDEM_HOST_LANES
    if (lanes && mixed)
      for (; e + kMixedLanes <= e1; e += kMixedLanes) bulk.template batch<MixedLanes>(e, acc);
    if (lanes)
      for (; e + kLanes <= e1; e += kLanes) bulk.template batch<HostLanes>(e, acc);
#endif
    for (; e < e1; ++e) bulk(e, acc);
#if FDEM_HOST_LANES
    if (lanes && mixed)
      for (; q + kMixedLanes <= q1; q += kMixedLanes) iface.template batch<MixedLanes>(q, acc);
    if (lanes)
      for (; q + kLanes <= q1; q += kLanes) iface.template batch<HostLanes>(q, acc);
#endif
    for (; q < q1; ++q) iface(q, acc);
  }
};

// Elsewhere (GPUs: one thread per item; a model without Model::ichunk) the bulk elements and the
// interfaces are two kernels: each holds only the registers its own part needs (on CUDA, one
// kernel with both took the interface part's registers for every bulk element too). Work item c:
// chunk c of kChunk items, 0 <= item < n.
template <class Part, int D>
struct ChunkForceKernel {
  Part part;
  ForceScatter<D> sf;
  int n;

  KOKKOS_INLINE_FUNCTION void operator()(const int c) const {
    auto acc = sf.access();
    const int i1 = kmin((c + 1) * kChunk, n);
    for (int i = c * kChunk; i < i1; ++i) part(i, acc);
  }
};

// The bulk kernel's launch bounds: none in the default (25 %) build, where the interface kernel's
// bound would let the compiler spend 94 registers (3D) on what takes 79 without it; the 50 %
// variant's bound (64) in that build (docs/cuda.md, "Kernel resources").
#if FDEM_CUDA_OCCUPANCY >= 50
using BulkLaunchBounds = ForceLaunchBounds;
#else
using BulkLaunchBounds = Kokkos::LaunchBounds<>;
#endif

// Internal forces of bulk elements and interfaces scattered into m.f (which the node update left
// at zero). contribute = false: the sums stay in sf (the caller adds the contact forces to it and
// contributes). The interface kernel of the split runs under ForceLaunchBounds
// (kernels/fdem_kokkos.hpp), the bulk kernel under BulkLaunchBounds.
template <int D, bool PerIface, bool Fric>
void run_force_kernels(const Model<D>& m, ForceScatter<D>& sf, bool fused, int nbc, bool lanes) {
  const BulkForces<D> bulk{m.x, m.elements()};
  if constexpr (kChunk > 1) {  // host backends (a device build compiles no fused kernel)
    if (fused) {
      const InterfaceForces<D, PerIface, Fric> iface{m.x, m.v, m.interfaces()};
      Kokkos::parallel_for("fdem::forces", Kokkos::RangePolicy<ExecSpace>(0, nbc),
                           FusedForceKernel<D, PerIface, Fric>{bulk, iface, sf, lanes, m.mixed_precision});
      return;
    }
  }
  const int nb = m.elements().bulk_elems(), ni = m.ni;
  if (nb > 0)
    Kokkos::parallel_for("fdem::forces_bulk",
                         Kokkos::RangePolicy<ExecSpace, BulkLaunchBounds>(0, (nb + kChunk - 1) / kChunk),
                         ChunkForceKernel<BulkForces<D>, D>{bulk, sf, nb});
  if (ni > 0)
    Kokkos::parallel_for("fdem::forces_interfaces",
                         Kokkos::RangePolicy<ExecSpace, ForceLaunchBounds>(0, (ni + kChunk - 1) / kChunk),
                         ChunkForceKernel<LeanInterfaceForces<D, PerIface, Fric>, D>{
                             LeanInterfaceForces<D, PerIface, Fric>{m.x, m.v, m.interfaces()}, sf, ni});
}

// lanes = false: the host's fused pass one item at a time (FusedForceKernel::lanes; the same
// results).
template <int D>
void compute_forces(const Model<D>& m, ForceScatter<D>& sf, bool contribute = true, bool lanes = true) {
  const int nbc = (m.ne + kChunk - 1) / kChunk;
  const bool fused = kChunk > 1 && static_cast<int>(m.ichunk.extent(0)) == nbc + 1;
  sf.reset();
  if (m.per_interface()) {
    if (m.has_slip()) run_force_kernels<D, true, true>(m, sf, fused, nbc, lanes);
    else run_force_kernels<D, true, false>(m, sf, fused, nbc, lanes);
  } else {
    if (m.has_slip()) run_force_kernels<D, false, true>(m, sf, fused, nbc, lanes);
    else run_force_kernels<D, false, false>(m, sf, fused, nbc, lanes);
  }
  if (!contribute) return;  // the caller adds more (contact) and contributes
  auto f = m.f;
  contribute_forces<D>(f, sf);
}

}  // namespace fdem
