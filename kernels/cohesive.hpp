#pragma once
// Cohesive interface law at one integration point (METHOD.md section 4): uncoupled penalty
// traction-separation with scalar damage, Mohr-Coulomb initiation with tension cut-off, and
// Benzeggagh-Kenane mixed-mode linear softening. Irreversible (damage follows the largest
// equivalent separation reached). Compression is never damaged (penalty).
#include "fdem_kokkos.hpp"

namespace fdem {

struct CohesiveParams {
  double kn, ks;     // Pa/m
  double ft, c;      // Pa
  double tanphi;     // -
  double Gnc, Gsc;   // N/m
  double eta;        // BK exponent
};

// History of one integration point. dm0 == 0: not initiated yet. After initiation:
// dm0 = equivalent separation at initiation, dmf = at complete failure, dmax = largest reached,
// gc = mixed-mode fracture energy fixed at initiation.
struct CohesivePoint {
  double dmax, dm0, dmf, gc;
};

KOKKOS_INLINE_FUNCTION double cohesive_damage(const CohesivePoint& s) {
  if (s.dm0 <= 0.0 || s.dmax <= s.dm0) return 0.0;
  if (s.dmax >= s.dmf) return 1.0;
  return s.dmf * (s.dmax - s.dm0) / (s.dmax * (s.dmf - s.dm0));
}

// Energy dissipated per unit area so far (exact for the linear-softening equivalent law:
// gc * (dmax - dm0) / (dmf - dm0), capped at gc).
KOKKOS_INLINE_FUNCTION double cohesive_dissipation(const CohesivePoint& s) {
  if (s.dm0 <= 0.0 || s.dmax <= s.dm0) return 0.0;
  if (s.dmax >= s.dmf) return s.gc;
  return s.gc * (s.dmax - s.dm0) / (s.dmf - s.dm0);
}

// Updates the history with the separation (dn normal, ds = |tangential|) and returns the
// tractions: tn (tension positive) and the secant shear stiffness kss so that the shear traction
// vector is kss * delta_s_vector. Also returns the damage D.
KOKKOS_INLINE_FUNCTION void cohesive_update(const CohesiveParams& p, double dn, double ds,
                                            CohesivePoint& s, double& tn, double& kss, double& D) {
  const double dnp = dn > 0.0 ? dn : 0.0;
  const double dm = kmath::sqrt(dnp * dnp + ds * ds);
  if (s.dm0 <= 0.0) {
    // Undamaged: initiation check on the elastic tractions (tensile failure has priority).
    const double tn_e = p.kn * dn;
    const double ts_e = p.ks * ds;
    const double sigc = tn_e < 0.0 ? -tn_e : 0.0;
    const bool tensile = tn_e >= p.ft;
    const bool shear = ts_e >= p.c + sigc * p.tanphi;
    if ((tensile || shear) && dm > 0.0) {
      const double Gn = 0.5 * p.kn * dnp * dnp;
      const double GS = 0.5 * p.ks * ds * ds;
      const double GT = Gn + GS;
      const double ratio = GT > 0.0 ? GS / GT : 0.0;
      const double gc = p.Gnc + (p.Gsc - p.Gnc) * kmath::pow(ratio, p.eta);
      const double keff = 2.0 * GT / (dm * dm);
      double dmf = 2.0 * gc / (keff * dm);
      if (dmf < dm * (1.0 + 1e-12)) dmf = dm * (1.0 + 1e-12);  // brittle limit: fails at once
      s.dm0 = dm;
      s.dmf = dmf;
      s.gc = gc;
      s.dmax = dm;
    }
  } else if (dm > s.dmax) {
    s.dmax = dm;
  }
  D = cohesive_damage(s);
  const double g = 1.0 - D;
  tn = dn > 0.0 ? g * p.kn * dn : p.kn * dn;
  kss = g * p.ks;
}

// Elastic energy stored per unit area at the current separation.
KOKKOS_INLINE_FUNCTION double cohesive_stored(const CohesiveParams& p, double dn, double ds, double D) {
  const double g = 1.0 - D;
  return dn > 0.0 ? 0.5 * (g * p.kn * dn * dn + g * p.ks * ds * ds)
                  : 0.5 * (p.kn * dn * dn + g * p.ks * ds * ds);
}

}  // namespace fdem
