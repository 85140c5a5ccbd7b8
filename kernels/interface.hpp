#pragma once
// Kinematics and forces of one cohesive interface element (docs/theory.md sections 4 and 6b):
// its frame (normal and tributary area), whether it has come apart or parted (handover to
// contact), the failure of all its points, and its cohesive forces. Pointwise device functions;
// the force kernel (kernels/forces.hpp) and the contact handover call them.
#include "kernels/cohesive.hpp"
#include "kernels/fdem_kokkos.hpp"
#include "kernels/lanes.hpp"

namespace fdem {

// Geometry of an interface: unit normal n (from side A to side B) of the mid-surface and the
// tributary area of each integration point (nodal integration: one point per node pair) in the
// current configuration. The forces use the reference area (tractions per unit reference area,
// so that they derive from a stored energy); the current one serves the set-up. T: double, or
// Lanes<W> (kernels/lanes.hpp) for W interfaces at once (as the other functions with a T below).
template <int D, class T = double>
KOKKOS_FORCEINLINE_FUNCTION void interface_frame(const T (&xa)[D][D], const T (&xb)[D][D], const T& thickness,
                                                 T (&n)[D], T& area_pt) {
  T m[D][D];
  for (int k = 0; k < D; ++k)
    for (int i = 0; i < D; ++i) m[k][i] = 0.5 * (xa[k][i] + xb[k][i]);
  if constexpr (D == 2) {
    const T tx = m[1][0] - m[0][0], ty = m[1][1] - m[0][1];
    const T L = lane_sqrt(tx * tx + ty * ty);
    n[0] = ty / L;
    n[1] = -tx / L;
    area_pt = 0.5 * L * thickness;
  } else {
    const T a[3] = {m[1][0] - m[0][0], m[1][1] - m[0][1], m[1][2] - m[0][2]};
    const T b[3] = {m[2][0] - m[0][0], m[2][1] - m[0][1], m[2][2] - m[0][2]};
    T c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const T len = lane_sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int i = 0; i < D; ++i) n[i] = c[i] / len;
    area_pt = 0.5 * len / 3.0;
  }
}

// An interface has come apart when one of its failed points (D = 1) has its node pair farther
// apart than the A face's inradius (2D: half its length). Its mid-surface, and so the normal of
// its compressive penalty and of whatever cohesion its other points still have, is then no
// longer meaningful (it degenerates when one fragment has turned over against the other, and a
// penalty along a flipped normal pushes with the force of a millimetre-deep overlap: in the 3D
// multi-particle impact an interface whose one corner still held while the other two were 8 mm
// apart kicked a node to 3.5e4 m/s). From the step this is first seen on, every point of the
// interface is failed (interface_fail_all) and it carries nothing and stores nothing: without
// contact (case key contact.enabled = false) for good (Model::icontact; switching back on would
// release whatever overlap its faces reached meanwhile), with contact until the next handover
// check makes its faces contact surfaces. Faces that stay close (sliding or pressed together)
// keep the penalty; with contact, interface_parted below hands them over.
// dmg: the damage of each point (cohesive_damage).
template <int D>
KOKKOS_FORCEINLINE_FUNCTION bool interface_apart(const double (&xa)[D][D], const double (&xb)[D][D],
                                            const double (&dmg)[D]) {
  bool failed = false;
  for (int k = 0; k < D; ++k) failed = failed || dmg[k] >= 1.0;
  if (!failed) return false;
  double r2;
  if constexpr (D == 2) {
    const double tx = xa[1][0] - xa[0][0], ty = xa[1][1] - xa[0][1];
    r2 = 0.25 * (tx * tx + ty * ty);
  } else {
    double e[3][3], per = 0;
    for (int k = 0; k < 3; ++k) {
      double l2 = 0;
      for (int i = 0; i < 3; ++i) {
        e[k][i] = xa[(k + 1) % 3][i] - xa[k][i];
        l2 += e[k][i] * e[k][i];
      }
      per += kmath::sqrt(l2);
    }
    const double c[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                         e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    const double r = kmath::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / per;  // 2 area / perimeter
    r2 = r * r;
  }
  for (int k = 0; k < D; ++k) {
    if (dmg[k] < 1.0) continue;
    double d2 = 0;
    for (int i = 0; i < D; ++i) d2 += (xb[k][i] - xa[k][i]) * (xb[k][i] - xa[k][i]);
    if (d2 > r2) return true;
  }
  return false;
}
template <int D>
KOKKOS_FORCEINLINE_FUNCTION bool interface_apart(const double (&xa)[D][D], const double (&xb)[D][D],
                                            const CohesivePoint (&h)[D]) {
  double dmg[D];
  for (int k = 0; k < D; ++k) dmg[k] = cohesive_damage(h[k]);
  return interface_apart<D>(xa, xb, dmg);
}

// Fails every point of an interface that has come apart (interface_apart): a point that still
// holds releases the elastic energy it stores at its present separation, booked as fracture
// dissipation (its remaining fracture energy is never spent: the crack has run past it).
// Fric: a softening point's residual friction spring (interface_forces) releases its energy too,
// booked as friction (sl.wf).
// One point of a come-apart interface with unit normal n (interface_frame); d: its separation
// (its B node's position less its A node's).
template <int D, bool Fric = false>
KOKKOS_INLINE_FUNCTION void interface_fail_point(const double (&d)[D], const double (&n)[D], const CohesiveParams& p,
                                                 CohesivePoint& h, SlipPoint<D>& sl) {
  const double dmg = cohesive_damage(h);
  if (dmg >= 1.0) return;
  double dn = 0, ds2 = 0;
  for (int i = 0; i < D; ++i) dn += d[i] * n[i];
  for (int i = 0; i < D; ++i) ds2 += (d[i] - dn * n[i]) * (d[i] - dn * n[i]);
  h.wd += cohesive_stored(p, dn, kmath::sqrt(ds2), dmg);  // per unit area, as wd
  if constexpr (Fric) {
    if (p.tanphir >= 0.0 && dmg > 0.0) {
      double e[D];
      sl.wf += 0.5 * p.ks * elastic_slip<D>(n, d, sl, e);
    }
  }
  if (!(h.dm0 > 0.0)) h.dm0 = 1e-300;  // never initiated: initiated now
  if (!(h.dmf > h.dm0)) h.dmf = 2.0 * h.dm0;
  h.dmax = h.dmax > h.dmf ? h.dmax : h.dmf;
}
template <int D, bool Fric = false>
KOKKOS_INLINE_FUNCTION void interface_fail_all(const double (&xa)[D][D], const double (&xb)[D][D],
                                               const CohesiveParams& p, CohesivePoint (&h)[D],
                                               SlipPoint<D> (&sl)[D]) {
  double n[D], ap_cur;
  interface_frame<D>(xa, xb, 1.0, n, ap_cur);
  for (int k = 0; k < D; ++k) {
    double d[D];
    for (int i = 0; i < D; ++i) d[i] = xb[k][i] - xa[k][i];
    interface_fail_point<D, Fric>(d, n, p, h[k], sl[k]);
  }
}

// A failed interface is handed over to contact once its faces have parted: open (normal gap >= 0
// at every point), or slid by more than `slip` at some point. Until then the failed interface
// keeps its compression penalty (the cohesive law at D = 1), which holds the crack faces apart
// exactly where contact between them could not yet be trusted (faces still touching at a crack
// tip, copies of a vertex still joined through other interfaces).
template <int D>
KOKKOS_INLINE_FUNCTION bool interface_parted(const double (&xa)[D][D], const double (&xb)[D][D], double slip) {
  double n[D], ap;
  interface_frame<D>(xa, xb, 1.0, n, ap);
  bool open = true, slid = false;
  for (int k = 0; k < D; ++k) {
    double d[D], dn = 0, d2 = 0;
    for (int i = 0; i < D; ++i) {
      d[i] = xb[k][i] - xa[k][i];
      dn += d[i] * n[i];
      d2 += d[i] * d[i];
    }
    open = open && dn >= 0.0;
    slid = slid || d2 - dn * dn > slip * slip;
  }
  return open || slid;
}

// The residual friction of one softening point (interface_forces; friction_return, cohesive.hpp)
// beside its cohesive shear traction of magnitude tc, its damage risen by dD and its separation
// changed by du in the step (fresh: it began to soften in this step): the slip
// step and its dissipation (sl.wf), the energy the damage moved into the spring taken off the
// fracture dissipation (h.wd), and the forces of U_f = ap k_s |P (d - sp)|^2 / 2 added to the
// point's (fa, fb) and to dU/dn (g): dU_f/dd = ap k_s e, dU_f/dn = -ap k_s (r . n) r with
// r = d - sp = dn n + e.
template <int D>
KOKKOS_INLINE_FUNCTION void residual_friction(const CohesiveParams& p, const double (&n)[D], const double (&d)[D],
                                              double dn, const double (&ds)[D], double ap, double tc, double dD,
                                              const double (&du)[D], bool fresh, CohesivePoint& h,
                                              SlipPoint<D>& sl, double (&fa)[D], double (&fb)[D], double (&g)[D]) {
  if (fresh) {  // begun to soften in this step: the spring starts unstretched at x(n-1)
    double dun = 0;
    for (int i = 0; i < D; ++i) dun += du[i] * n[i];
    for (int i = 0; i < D; ++i) sl.sp[i] = ds[i] - (du[i] - dun * n[i]);
  }
  double e[D], moved;
  sl.wf += friction_return<D>(p, n, d, dn, ds, tc, dD, du, sl, e, moved);
  h.wd -= moved;
  const double kf = ap * p.ks;
  for (int i = 0; i < D; ++i) {
    fa[i] += kf * e[i];
    fb[i] -= kf * e[i];
    g[i] -= kf * dn * (dn * n[i] + e[i]);
  }
}

// What interface_point_forces does with a softening point's residual friction: `Friction`
// policy with friction(p, n, d, dn, ds, ap, tc, dD, fresh, h, fa, fb, g), given the point's
// parameters, normal, separation and its normal and tangential parts, area, cohesive shear
// traction, damage rise, whether it began to soften in this step, its history and forces. Here:
// the slip state and the step's motion in the caller's arrays (the fused kernel);
// LeanInterfaceForces (kernels/forces.hpp) has its own, which reads them where they are needed.
template <int D>
struct SlipInArrays {
  SlipPoint<D>& sl;
  const double (&du)[D];
  KOKKOS_INLINE_FUNCTION void friction(const CohesiveParams& p, const double (&n)[D], const double (&d)[D], double dn,
                                       const double (&ds)[D], double ap, double tc, double dD, bool fresh,
                                       CohesivePoint& h, double (&fa)[D], double (&fb)[D], double (&g)[D]) const {
    residual_friction<D>(p, n, d, dn, ds, ap, tc, dD, du, fresh, h, sl, fa, fb, g);
  }
};

// A point's separation d (B node less A node) split along the unit normal n: dn = d . n, the
// tangential part ds and its square ds2.
template <int D, class T = double>
KOKKOS_FORCEINLINE_FUNCTION void point_separation(const T (&d)[D], const T (&n)[D], T& dn, T (&ds)[D], T& ds2) {
  dn = 0.0;
  for (int i = 0; i < D; ++i) dn += d[i] * n[i];
  ds2 = 0.0;
  for (int i = 0; i < D; ++i) {
    ds[i] = d[i] - dn * n[i];
    ds2 += ds[i] * ds[i];
  }
}

// A point's forces from its tractions (normal tn, secant shear stiffness kss) on area ap: fa on its
// A node, fb on its B node (without the normal's change), and its share of g = dU/dn.
template <int D, class T = double>
KOKKOS_FORCEINLINE_FUNCTION void point_forces(const T (&d)[D], const T (&n)[D], const T& ap, const T& tn,
                                              const T& kss, const T& dn, const T (&ds)[D], T (&fa)[D], T (&fb)[D],
                                              T (&g)[D]) {
  for (int i = 0; i < D; ++i) {
    fa[i] = ap * (tn * n[i] + kss * ds[i]);
    fb[i] = -fa[i];
    g[i] += ap * (tn - kss * dn) * d[i];
  }
}

// One point's share of interface_forces: updates its history and returns its damage; d: its
// separation (B node less A node); fa, fb: the forces on its node pair without the normal's change
// (interface_normal_forces); g += dU/dn. Fric: a softening point's residual friction through the
// policy fr (SlipInArrays).
template <int D, bool Fric, class Friction>
KOKKOS_FORCEINLINE_FUNCTION double interface_point_forces(const double (&d)[D], const double (&n)[D], double ap,
                                                     const CohesiveParams& p, CohesivePoint& h, Friction& fr,
                                                     double (&fa)[D], double (&fb)[D], double (&g)[D]) {
  double ds[D], dn, ds2;
  point_separation<D>(d, n, dn, ds, ds2);
  double tn, kss, dmg;
  const double dmg0 = Fric ? cohesive_damage(h) : 0.0;
  const bool fresh = !(h.dm0 > 0.0);
  cohesive_update(p, dn, kmath::sqrt(ds2), h, tn, kss, dmg);
  point_forces<D>(d, n, ap, tn, kss, dn, ds, fa, fb, g);
  if constexpr (Fric) {
    if (p.tanphir >= 0.0 && dmg > 0.0)
      fr.friction(p, n, d, dn, ds, ap, kss * kmath::sqrt(ds2), dmg - dmg0, fresh, h, fa, fb, g);
  }
  return dmg;
}
template <int D, bool Fric = false>
KOKKOS_FORCEINLINE_FUNCTION double interface_point_forces(const double (&d)[D], const double (&n)[D], double ap,
                                                     const CohesiveParams& p, CohesivePoint& h, SlipPoint<D>& sl,
                                                     const double (&du)[D], double (&fa)[D], double (&fb)[D],
                                                     double (&g)[D]) {
  SlipInArrays<D> fr{sl, du};
  return interface_point_forces<D, Fric>(d, n, ap, p, h, fr, fa, fb, g);
}

// The mid-surface's edges from its first point, m_k - m_0 with m_k = (xa_k + xb_k) / 2 (k >= 1):
// what the normal's change needs of the positions (interface_normal_forces).
template <int D, class T = double>
KOKKOS_FORCEINLINE_FUNCTION void mid_edges(const T (&xa)[D][D], const T (&xb)[D][D], T (&e)[D - 1][D]) {
  for (int k = 1; k < D; ++k)
    for (int i = 0; i < D; ++i) e[k - 1][i] = 0.5 * (xa[k][i] + xb[k][i] - xa[0][i] - xb[0][i]);
}

// The forces of the normal's change: dm[k] = dU/dm_k through the mid-surface points
// m_k = (xa_k + xb_k) / 2 from g = dU/dn; each node of pair k takes -dm[k] / 2. e: mid_edges.
template <int D, class T = double>
KOKKOS_FORCEINLINE_FUNCTION void interface_normal_forces(const T (&e)[D - 1][D], const T (&n)[D], const T (&g)[D],
                                                         T (&dm)[D][D]) {
  T gp[D], gn = 0.0;  // projection (I - n n^T) g
  for (int i = 0; i < D; ++i) gn += g[i] * n[i];
  for (int i = 0; i < D; ++i) gp[i] = g[i] - gn * n[i];
  if constexpr (D == 2) {
    // n = (t_y, -t_x) / L with t = m1 - m0: dU/dt = (1/L) R^T gp, R^T (gx, gy) = (-gy, gx)
    const T tx = e[0][0];
    const T ty = e[0][1];
    const T L = lane_sqrt(tx * tx + ty * ty);
    const T Gt[2] = {-gp[1] / L, gp[0] / L};
    for (int i = 0; i < 2; ++i) {
      dm[1][i] = Gt[i];
      dm[0][i] = -Gt[i];
    }
  } else {
    // n = c / |c|, c = a x b, a = m1 - m0, b = m2 - m0: dU/dc = gp / |c|,
    // dU/da = b x hc, dU/db = hc x a
    const T(&a)[3] = e[0];
    const T(&b)[3] = e[1];
    const T c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const T cl = lane_sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    const T hc[3] = {gp[0] / cl, gp[1] / cl, gp[2] / cl};
    const T da[3] = {b[1] * hc[2] - b[2] * hc[1], b[2] * hc[0] - b[0] * hc[2], b[0] * hc[1] - b[1] * hc[0]};
    const T db[3] = {hc[1] * a[2] - hc[2] * a[1], hc[2] * a[0] - hc[0] * a[2], hc[0] * a[1] - hc[1] * a[0]};
    for (int i = 0; i < 3; ++i) {
      dm[1][i] = da[i];
      dm[2][i] = db[i];
      dm[0][i] = -da[i] - db[i];
    }
  }
}

// Cohesive forces of one interface: updates the history of its points and returns the forces on
// its A-side (fa) and B-side (fb) nodes, and the mean damage. ap: reference tributary area of a
// point. The forces are the exact gradient of the stored energy U = ap sum_k psi(delta_k . n,
// |delta_k - (delta_k . n) n|) at fixed damage, including the change of the normal n with the
// nodes (it matters once faces have slid or opened far), so that the interface neither creates
// nor loses energy.
// Fric (the model has slip states, Model::islip) and p.tanphir >= 0: a point that has begun to
// soften (D > 0) also has its residual friction (residual_friction; docs/theory.md section 4): a
// Coulomb spring k_s e that supplies what the softening cohesive traction (1 - D) k_s |delta_s|
// no longer carries, up to sigma_n tan(phi_r), so that the shear resistance goes from the
// Mohr-Coulomb peak down the paper's softening branch until it meets sigma_n tan(phi_r) and stays
// there; psi gains k_s |e|^2 / 2 and the slip dissipates into sl.wf. The damage and its fracture
// energy are the paper's law's. sl: the points' slip states (zero for a point that had not begun
// to soften). (The GPU's force kernel does the same point by point: LeanInterfaceForces,
// kernels/forces.hpp.)
template <int D, bool Fric = false>
KOKKOS_FORCEINLINE_FUNCTION double interface_forces(const double (&xa)[D][D], const double (&xb)[D][D],
                                               double ap, const CohesiveParams& p,
                                               CohesivePoint (&h)[D], SlipPoint<D> (&sl)[D],
                                               double (&fa)[D][D], double (&fb)[D][D],
                                               const double (&du)[D][D]) {
  double n[D], ap_cur;
  interface_frame<D>(xa, xb, 1.0, n, ap_cur);
  double dsum = 0;
  double g[D];  // dU/dn
  for (int i = 0; i < D; ++i) g[i] = 0;
  for (int k = 0; k < D; ++k) {
    double d[D];
    for (int i = 0; i < D; ++i) d[i] = xb[k][i] - xa[k][i];
    dsum += interface_point_forces<D, Fric>(d, n, ap, p, h[k], sl[k], du[k], fa[k], fb[k], g);
  }
  double e[D - 1][D], dm[D][D];  // mid-surface edges, dU/dm_k
  mid_edges<D>(xa, xb, e);
  interface_normal_forces<D>(e, n, g, dm);
  for (int k = 0; k < D; ++k)
    for (int i = 0; i < D; ++i) {
      fa[k][i] -= 0.5 * dm[k][i];
      fb[k][i] -= 0.5 * dm[k][i];
    }
  return dsum / D;
}

}  // namespace fdem
