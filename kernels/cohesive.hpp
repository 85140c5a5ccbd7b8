#pragma once
// Cohesive interface law at one integration point (docs/theory.md section 4): uncoupled penalty
// traction-separation with scalar damage, Mohr-Coulomb initiation with tension cut-off, and
// Benzeggagh-Kenane mixed-mode linear softening. Irreversible (damage follows the largest
// equivalent separation reached). Compression is never damaged (penalty).
#include <array>

#include "kernels/fdem_kokkos.hpp"

namespace fdem {

struct CohesiveParams {
  double kn, ks;     // Pa/m
  double ft, c;      // Pa
  double tanphi;     // -
  double Gnc, Gsc;   // N/m
  double eta;        // BK exponent
  // The residual friction of a softening point (docs/theory.md section 4): tan(phi_r); negative:
  // the paper's law (no friction while a point softens, none once it has failed).
  double tanphir = -1.0;
  // Strength change since the histories were last updated: the strength the histories were
  // written under divided by the strength now (strength reduction: SRF_old / SRF_new). 1: none.
  // cohesive_update moves the softening envelope of initiated points with it (below).
  double rescale = 1.0;
};

// The parameters as the 9 values of the checkpoint entry "model/cohesive" (kn, ks, ft, c, tanphi,
// Gnc, Gsc, eta, tanphir; rescale is not among them), and back (rescale = 1). Checkpoints written
// before the residual friction hold the first 8 (n = 8: the paper's law).
constexpr int kCohesiveArraySize = 9;
inline std::array<double, kCohesiveArraySize> to_array(const CohesiveParams& p) {
  return {p.kn, p.ks, p.ft, p.c, p.tanphi, p.Gnc, p.Gsc, p.eta, p.tanphir};
}
inline CohesiveParams cohesive_params_from_array(const double* a, int n = kCohesiveArraySize) {
  return CohesiveParams{a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], n > 8 ? a[8] : -1.0};
}

// History of one integration point. dm0 == 0: not initiated yet. After initiation:
// dm0 = equivalent separation at initiation, dmf = at complete failure (from the mixed-mode
// fracture energy fixed at initiation), dmax = largest reached, wd = energy dissipated per unit area.
struct CohesivePoint {
  double dmax, dm0, dmf, wd;
};
// Values of one point's history as stored: the last extent of Model::ihist (its columns in the
// order of load_point / store_point, kernels/model.hpp).
constexpr int kPointHistory = 4;
static_assert(sizeof(CohesivePoint) == kPointHistory * sizeof(double),
              "CohesivePoint is kPointHistory doubles");

// The history of a point that starts failed (a frictional joint's: src/solver/model_builder.cpp):
// damage 1 (cohesive_damage: dmax >= dmf > dm0 > 0), nothing dissipated.
KOKKOS_INLINE_FUNCTION CohesivePoint failed_point() { return CohesivePoint{2e-300, 1e-300, 2e-300, 0.0}; }

KOKKOS_FORCEINLINE_FUNCTION double cohesive_damage(const CohesivePoint& s) {
  if (s.dm0 <= 0.0 || s.dmax <= s.dm0) return 0.0;
  if (s.dmax >= s.dmf) return 1.0;
  return s.dmf * (s.dmax - s.dm0) / (s.dmax * (s.dmf - s.dm0));
}

// Energy dissipated per unit area so far.
KOKKOS_INLINE_FUNCTION double cohesive_dissipation(const CohesivePoint& s) { return s.wd; }

// The initiation test of an undamaged point at separation (dn normal, ds = |tangential|): its
// elastic tractions tn_e = kn dn and ts_e = ks ds against the tension cut-off (tensile: tn_e >= ft)
// and the Mohr-Coulomb envelope (shear: ts_e >= c + sigc tan(phi), sigc = <-tn_e>+ the compression).
struct Initiation {
  double tn_e, ts_e, sigc;
  bool tensile, shear;
};
KOKKOS_FORCEINLINE_FUNCTION Initiation initiation_test(const CohesiveParams& p, double dn, double ds) {
  Initiation t;
  t.tn_e = p.kn * dn;
  t.ts_e = p.ks * ds;
  t.sigc = kselect(t.tn_e < 0.0, -t.tn_e, 0.0);
  t.tensile = t.tn_e >= p.ft;
  t.shear = t.ts_e >= p.c + t.sigc * p.tanphi;
  return t;
}

// The equivalent separation of the damage law: the opening (not a closure) and the slip together.
KOKKOS_FORCEINLINE_FUNCTION double equivalent_separation(double dn, double ds) {
  const double dnp = kselect(dn > 0.0, dn, 0.0);
  return kmath::sqrt(dnp * dnp + ds * ds);
}

// Whether cohesive_update leaves the history h alone at separation (dn, ds) under p, given that
// the strength has not changed (p.rescale 1): an intact point that does not meet its initiation
// test, or an initiated one not beyond its largest separation (dm: equivalent_separation(dn, ds)).
KOKKOS_FORCEINLINE_FUNCTION bool keeps_history(const CohesiveParams& p, const CohesivePoint& h, double dn,
                                               double ds, double dm) {
  if (h.dm0 <= 0.0) {
    const Initiation t = initiation_test(p, dn, ds);
    return !(t.tensile || t.shear);
  }
  return !(dm > h.dmax);
}

// Updates the history with the separation (dn normal, ds = |tangential|) and returns the
// tractions: tn (tension positive) and the secant shear stiffness kss so that the shear traction
// vector is kss * delta_s_vector. Also returns the damage D.
KOKKOS_FORCEINLINE_FUNCTION void cohesive_update(const CohesiveParams& p, double dn, double ds,
                                            CohesivePoint& s, double& tn, double& kss, double& D) {
  // The signs of dn decide selects, not branches (kselect).
  const double dnp = kselect(dn > 0.0, dn, 0.0);
  const double dm = equivalent_separation(dn, ds);
  if (s.dm0 > 0.0 && p.rescale != 1.0) {
    // The strength (f_t, c, tan(phi)) has been divided by a factor since the last update
    // (strength reduction): the envelope of an initiated point follows the strength it has now.
    // The initiation separation scales with the strength (the criterion is linear in it), the
    // fracture energy G_c = K dm0 dmf / 2 stays, so dmf scales inversely. The damage rises at the
    // separation the point has, and the stored energy it releases, psi0 dD with psi0 the
    // undamaged energy of the present separation (exact: psi0 does not change while only the
    // strength does), is fracture dissipation. Damage never heals: where the new envelope would
    // give less damage (past the middle of the softening branch under a reduction, or under a
    // strength that rises), dmax moves to where the present secant meets the new envelope.
    const double D0 = cohesive_damage(s);
    s.dm0 *= p.rescale;
    s.dmf /= p.rescale;
    if (s.dmf < s.dm0 * (1.0 + 1e-12)) s.dmf = s.dm0 * (1.0 + 1e-12);
    const double D1 = cohesive_damage(s);
    if (D1 > D0) {
      s.wd += 0.5 * (p.kn * dnp * dnp + p.ks * ds * ds) * (D1 - D0);
    } else if (D1 < D0) {
      const double x = D0 >= 1.0 ? s.dmf : s.dmf * s.dm0 / (s.dmf - D0 * (s.dmf - s.dm0));
      s.dmax = kmax(s.dmax, x);
      if (D0 >= 1.0) s.dmax = kmax(s.dmax, s.dmf);
    }
  }
  if (s.dm0 <= 0.0) {
    // Undamaged: initiation check on the elastic tractions (tensile failure has priority).
    const Initiation t = initiation_test(p, dn, ds);
    const double tn_e = t.tn_e, ts_e = t.ts_e, sigc = t.sigc;
    const bool tensile = t.tensile, shear = t.shear;
    if ((tensile || shear) && dm > 0.0) {
      const double Gn = 0.5 * p.kn * dnp * dnp;
      const double GS = 0.5 * p.ks * ds * ds;
      const double GT = Gn + GS;
      const double ratio = GT > 0.0 ? GS / GT : 0.0;
      const double gc = p.Gnc + (p.Gsc - p.Gnc) * kmath::pow(ratio, p.eta);
      const double keff = 2.0 * GT / (dm * dm);
      // Initiation is placed on the envelope: the fraction r <= 1 of the present separation at
      // which the criterion is met with equality (along the present direction). A step that
      // overshoots the strength, or a strength reduced while the separation stays (slope
      // stability), then softens at once to the envelope instead of keeping the excess traction.
      double r = 1.0;
      if (tensile) r = kmin(r, p.ft / tn_e);
      if (shear) {
        const double den = ts_e - sigc * p.tanphi;
        r = kmin(r, den > 0.0 ? p.c / den : 1.0);
      }
      r = kmax(r, 1e-6);
      const double dm0 = r * dm;
      double dmf = 2.0 * gc / (keff * dm0);
      if (dmf < dm0 * (1.0 + 1e-12)) dmf = dm0 * (1.0 + 1e-12);  // brittle limit: fails at once
      s.dm0 = dm0;
      s.dmf = dmf;
      s.dmax = dm;
      s.wd = 0.5 * keff * dmf * dm0 / (dmf - dm0) * (kmin(dm, dmf) - dm0);
    }
  } else if (dm > s.dmax) {
    // Dissipation = integral of psi0 dD with psi0 = K dm^2 / 2 the undamaged energy of the
    // current mode (K = (kn <dn>+^2 + ks ds^2) / dm^2). While loading, dm^2 dD = dmf dm0 /
    // (dmf - dm0) d(dmax), so the increment is exact for any step along a proportional path.
    const double a = kmin(s.dmax, s.dmf), b = kmin(dm, s.dmf);
    if (b > a) {
      const double K = (p.kn * dnp * dnp + p.ks * ds * ds) / (dm * dm);
      s.wd += 0.5 * K * s.dmf * s.dm0 / (s.dmf - s.dm0) * (b - a);
    }
    s.dmax = dm;
  }
  D = cohesive_damage(s);
  const double g = 1.0 - D;
  tn = kselect(dn > 0.0, g, 1.0) * p.kn * dn;  // (1.0 * kn) * dn == kn * dn: the same bits
  kss = g * p.ks;
}

// Elastic energy stored per unit area at the current separation.
KOKKOS_INLINE_FUNCTION double cohesive_stored(const CohesiveParams& p, double dn, double ds, double D) {
  const double g = 1.0 - D;
  return kselect(dn > 0.0, 0.5 * (g * p.kn * dn * dn + g * p.ks * ds * ds),
                 0.5 * (p.kn * dn * dn + g * p.ks * ds * ds));  // both finite: a select, no branch
}

// The residual friction of a softening point (docs/theory.md section 4): a Coulomb spring that
// takes up what the softening cohesive traction no longer carries, up to the residual friction
// sigma_n tan(phi_r). Its state: the slip sp (global components, in the tangent plane of the step
// that wrote it) and the energy its sliding has dissipated per unit area, wf:
// slip_state_size<D>() values per point (Model::islip).
template <int D>
struct SlipPoint {
  double sp[D];
  double wf;
};
template <int D>
constexpr int slip_state_size() {
  return D + 1;
}
template <int D>
KOKKOS_INLINE_FUNCTION SlipPoint<D> zero_slip() {
  SlipPoint<D> s;
  for (int i = 0; i < D; ++i) s.sp[i] = 0.0;
  s.wf = 0.0;
  return s;
}

// The elastic slip e of the residual friction's shear spring: the part of d - sp in the plane
// normal to n (d: the separation, xb - xa). Returns |e|^2.
template <int D>
KOKKOS_INLINE_FUNCTION double elastic_slip(const double (&n)[D], const double (&d)[D], const SlipPoint<D>& s,
                                           double (&e)[D]) {
  double rn = 0, e2 = 0;
  for (int i = 0; i < D; ++i) rn += (d[i] - s.sp[i]) * n[i];
  for (int i = 0; i < D; ++i) {
    e[i] = d[i] - s.sp[i] - rn * n[i];
    e2 += e[i] * e[i];
  }
  return e2;
}

// One step of the residual friction's Coulomb spring at separation d (normal n, normal separation
// dn, tangential part ds) beside a cohesive shear traction of magnitude tc, whose damage rose by
// dD in the step; du: the change of d over the step (x(n) - x(n-1) of the node pair). The spring
// takes over what the cohesion lost: its trial elastic slip is e = P (d - sp) + dD ds (at fixed ds
// the damage moves dD k_s ds of the traction from the cohesive secant to the friction spring: the
// shear traction as a whole follows the elastic increment, so the friction comes in as fast as
// the cohesion goes, however brittle the softening), cut back to |k_s e| <= max(0, tan(phi_r)
// k_n <-dn> - tc): it supplies what the softening cohesion no longer carries, up to the residual
// friction (open, it carries nothing and sp follows d). Updates sp (= ds - e, in this step's
// tangent plane); returns e, in `moved` the energy the damage moved into the spring (the caller
// books it against the fracture dissipation, which counts the whole secant energy psi0 dD as
// released), and the energy the step dissipated per unit area: the spring's energy before, plus
// the work of the mean of its old and new tractions over the step's tangential motion P du, plus
// moved, less its energy after (the old elastic slip: e_trial - P du before the transfer). In a
// steady slide that is the traction times the slip; where the limit falls (the faces open, the
// compression eases) it releases what the spring held. (psi_trial - psi_after, the energy the
// return releases at fixed positions, counts the elastic predictor's overshoot, k_s |slip|^2 / 2
// a step, as well: the balance drifted by 0.4 % of a slide's work in the 3D direct shear of
// tests/test_joints.cpp; the traction times the slip alone missed the release: 3.4 % of the
// energy in the 2D impact.)
template <int D>
KOKKOS_INLINE_FUNCTION double friction_return(const CohesiveParams& p, const double (&n)[D], const double (&d)[D],
                                              double dn, const double (&ds)[D], double tc, double dD,
                                              const double (&du)[D], SlipPoint<D>& s, double (&e)[D],
                                              double& moved) {
  const double e2pre = elastic_slip<D>(n, d, s, e);
  double dun = 0;
  for (int i = 0; i < D; ++i) dun += du[i] * n[i];
  double eo[D], e2old = 0, e2 = 0;  // the old elastic slip, and the trial
  for (int i = 0; i < D; ++i) {
    eo[i] = e[i] - (du[i] - dun * n[i]);
    e2old += eo[i] * eo[i];
    e[i] += dD * ds[i];
    e2 += e[i] * e[i];
  }
  moved = 0.5 * p.ks * (e2 - e2pre);
  const double lim = kmax(0.0, p.tanphir * p.kn * kselect(dn < 0.0, -dn, 0.0) - tc);
  const double te = p.ks * kmath::sqrt(e2);
  const double c = te > lim ? (te > 0.0 ? lim / te : 0.0) : 1.0;
  double w = 0;  // (old + new elastic slip) . P du
  for (int i = 0; i < D; ++i) {
    e[i] *= c;
    s.sp[i] = ds[i] - e[i];
    w += (eo[i] + e[i]) * (du[i] - dun * n[i]);
  }
  return 0.5 * p.ks * (e2old + w - c * c * e2) + moved;
}

}  // namespace fdem
