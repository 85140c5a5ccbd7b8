// Verification of the cohesive law (docs/theory.md section 4) at one integration point: strengths,
// fracture energies (pure modes, Benzeggagh-Kenane mixed mode), compression, unloading/reloading.
// The work is integrated numerically from the tractions the law returns, so these tests check the
// law's consistency, not its bookkeeping.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "kernels/cohesive.hpp"

namespace {

using fdem::CohesiveParams;
using fdem::CohesivePoint;

// Table 1 of the paper (Brazilian disc).
CohesiveParams table1() {
  return CohesiveParams{1.10e14, 4.40e13, 8e6, 16.56e6, std::tan(45.0 * M_PI / 180), 75, 1500, 2.0};
}

struct PathResult {
  double work = 0;        // integral of t . d(delta), per unit area
  double peak_tn = 0, peak_ts = 0;
  double final_damage = 0;
  double dissipation = 0;  // as reported by cohesive_dissipation
};

// Follows delta(s) = (dn(s), ds(s)) for s in [0, 1] in n steps, integrating the work (trapezoid).
// The steps are s = (i/n)^3, fine near the origin where initiation happens.
template <class Path>
PathResult follow(const CohesiveParams& p, Path path, int n, CohesivePoint& h) {
  PathResult r;
  double dn0, ds0;
  path(0.0, dn0, ds0);
  double tn0, kss0, D;
  fdem::cohesive_update(p, dn0, ds0, h, tn0, kss0, D);
  double ts0 = kss0 * ds0;
  for (int i = 1; i <= n; ++i) {
    double dn, ds, tn, kss;
    const double u = static_cast<double>(i) / n;
    path(u * u * u, dn, ds);
    fdem::cohesive_update(p, dn, ds, h, tn, kss, D);
    const double ts = kss * ds;
    r.work += 0.5 * (tn + tn0) * (dn - dn0) + 0.5 * (ts + ts0) * (ds - ds0);
    r.peak_tn = std::max(r.peak_tn, tn);
    r.peak_ts = std::max(r.peak_ts, ts);
    dn0 = dn; ds0 = ds; tn0 = tn; ts0 = ts;
    r.final_damage = D;
  }
  r.dissipation = fdem::cohesive_dissipation(h);
  return r;
}

TEST(Cohesive, ModeIPeaksAtTensileStrengthAndDissipatesGnc) {
  const auto p = table1();
  const double dmax = 3 * 2 * p.Gnc / p.ft;  // well past complete failure
  CohesivePoint h{0, 0, 0, 0};
  const auto r = follow(p, [&](double s, double& dn, double& ds) { dn = s * dmax; ds = 0; }, 200000, h);
  EXPECT_NEAR(r.peak_tn / p.ft, 1.0, 0.005);
  EXPECT_NEAR(r.work / p.Gnc, 1.0, 0.005);
  EXPECT_NEAR(r.dissipation / p.Gnc, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.final_damage, 1.0);
  EXPECT_NEAR(h.dm0, p.ft / p.kn, 1e-3 * p.ft / p.kn);
  EXPECT_NEAR(h.dmf, 2 * p.Gnc / p.ft, 1e-3 * 2 * p.Gnc / p.ft);
  // the softening branch: traction falls linearly from ft at dm0 to 0 at dmf
  double tn, kss, D;
  CohesivePoint h2{0, 0, 0, 0};
  fdem::cohesive_update(p, 1.0001 * h.dm0, 0.0, h2, tn, kss, D);
  const double dq = h2.dm0 + 0.25 * (h2.dmf - h2.dm0);
  fdem::cohesive_update(p, dq, 0.0, h2, tn, kss, D);
  EXPECT_NEAR(tn / (0.75 * p.kn * h2.dm0), 1.0, 1e-9);
}

TEST(Cohesive, ModeIIPeaksAtCohesionAndDissipatesGsc) {
  const auto p = table1();
  const double smax = 2 * 2 * p.Gsc / p.c;
  CohesivePoint h{0, 0, 0, 0};
  const auto r = follow(p, [&](double s, double& dn, double& ds) { dn = 0; ds = s * smax; }, 200000, h);
  EXPECT_NEAR(r.peak_ts / p.c, 1.0, 0.005);
  EXPECT_NEAR(r.work / p.Gsc, 1.0, 0.005);
  EXPECT_NEAR(r.dissipation / p.Gsc, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.final_damage, 1.0);
}

// Proportional mixed-mode paths at three mode ratios: the work equals the BK energy
// G_c = Gnc + (Gsc - Gnc) (G_S / G_T)^eta with the mode ratio of the path.
TEST(Cohesive, MixedModeDissipatesBenzeggaghKenaneEnergy) {
  const auto p = table1();
  for (double angle_deg : {20.0, 45.0, 70.0}) {
    const double a = angle_deg * M_PI / 180;
    const double cn = std::cos(a), cs = std::sin(a);
    const double GS = p.ks * cs * cs, GT = p.kn * cn * cn + GS;  // ratios, up to a common factor
    const double gc = p.Gnc + (p.Gsc - p.Gnc) * std::pow(GS / GT, p.eta);
    const double len = 4 * 2 * p.Gsc / std::min(p.ft, p.c);
    CohesivePoint h{0, 0, 0, 0};
    const auto r = follow(p, [&](double s, double& dn, double& ds) { dn = s * len * cn; ds = s * len * cs; },
                          400000, h);
    EXPECT_NEAR(r.work / gc, 1.0, 0.005) << "path angle " << angle_deg;
    // the history holds the BK energy: area under the envelope 0.5 K dm0 dmf, K of the path
    const double K = p.kn * cn * cn + p.ks * cs * cs;
    EXPECT_NEAR(0.5 * K * h.dm0 * h.dmf / gc, 1.0, 1e-9) << "path angle " << angle_deg;
    EXPECT_NEAR(r.dissipation / gc, 1.0, 1e-9) << "path angle " << angle_deg;
    EXPECT_DOUBLE_EQ(r.final_damage, 1.0);
    // initiation on the Mohr-Coulomb/tension cut-off envelope
    const double tn0 = p.kn * h.dm0 * cn, ts0 = p.ks * h.dm0 * cs;
    EXPECT_TRUE(tn0 >= p.ft * 0.999 || ts0 >= p.c * 0.999) << tn0 << " " << ts0;
    EXPECT_TRUE(tn0 <= p.ft * 1.005 && ts0 <= p.c * 1.005) << tn0 << " " << ts0;
  }
}

TEST(Cohesive, CompressionRaisesShearStrengthByTanPhi) {
  auto p = table1();
  p.tanphi = std::tan(30.0 * M_PI / 180);
  for (double sigc : {0.0, 5e6, 20e6}) {
    const double dn = -sigc / p.kn;
    const double smax = 3 * 2 * p.Gsc / p.c;
    CohesivePoint h{0, 0, 0, 0};
    const auto r = follow(p, [&](double s, double& a, double& b) { a = dn; b = s * smax; }, 200000, h);
    EXPECT_NEAR(r.peak_ts / (p.c + sigc * p.tanphi), 1.0, 0.005) << "sigma_c " << sigc;
    // shear under compression dissipates the mode II energy (normal part never damages)
    EXPECT_NEAR(r.work / p.Gsc, 1.0, 0.005) << "sigma_c " << sigc;
  }
}

// kselect (kernels/fdem_kokkos.hpp) is the branch-free `c ? a : b` of the cohesive law and the
// node update: it must give the same bits, signed zeros, infinities and NaN payloads included.
TEST(Cohesive, BranchFreeSelectGivesTheSameBitsAsTheConditional) {
  const double vals[] = {0.0, -0.0, 1.0, -2.5e-300, 4.9e-324, 1.7e308, -HUGE_VAL, HUGE_VAL, std::nan("7"), 0.1};
  auto bits = [](double x) {
    unsigned long long u;
    std::memcpy(&u, &x, sizeof u);
    return u;
  };
  for (double a : vals)
    for (double b : vals)
      for (bool c : {true, false}) EXPECT_EQ(bits(fdem::kselect(c, a, b)), bits(c ? a : b)) << a << " " << b << " " << c;
  // the traction of a closed point: (1.0 * kn) * dn, the bits of kn * dn
  const auto p = table1();
  CohesivePoint h{0, 0, 0, 0};
  double tn, kss, D;
  for (double dn : {-3e-9, -1e-12, -0.0}) {
    fdem::cohesive_update(p, dn, 0.0, h, tn, kss, D);
    EXPECT_EQ(bits(tn), bits(p.kn * dn)) << dn;
  }
}

TEST(Cohesive, CompressionIsNeverDamaged) {
  const auto p = table1();
  CohesivePoint h{0, 0, 0, 0};
  // fail the point in tension, then close it: compression is still carried by the penalty
  follow(p, [&](double s, double& dn, double& ds) { dn = s * 3 * 2 * p.Gnc / p.ft; ds = 0; }, 1000, h);
  double tn, kss, D;
  fdem::cohesive_update(p, -1e-8, 0.0, h, tn, kss, D);
  EXPECT_DOUBLE_EQ(D, 1.0);
  EXPECT_DOUBLE_EQ(tn, p.kn * -1e-8);
  EXPECT_DOUBLE_EQ(kss, 0.0);
}

TEST(Cohesive, UnloadingFollowsDamagedSecantAndReloadingDoesNotHeal) {
  const auto p = table1();
  const double d0 = p.ft / p.kn, df = 2 * p.Gnc / p.ft;
  const double dmid = d0 + 0.4 * (df - d0);
  CohesivePoint h{0, 0, 0, 0};
  follow(p, [&](double s, double& dn, double& ds) { dn = s * dmid; ds = 0; }, 20000, h);
  const double Dmid = fdem::cohesive_damage(h);
  EXPECT_GT(Dmid, 0.5);
  EXPECT_LT(Dmid, 1.0);
  // unloading to zero: secant stiffness (1 - D) kn, damage unchanged
  for (double frac : {0.8, 0.5, 0.1, 0.0}) {
    double tn, kss, D;
    fdem::cohesive_update(p, frac * dmid, 0.0, h, tn, kss, D);
    EXPECT_DOUBLE_EQ(D, Dmid);
    EXPECT_NEAR(tn, (1 - Dmid) * p.kn * frac * dmid, 1e-9 * p.ft);
  }
  // reloading up to the previous maximum: still the same secant, no healing
  double tn, kss, D;
  fdem::cohesive_update(p, dmid, 0.0, h, tn, kss, D);
  EXPECT_DOUBLE_EQ(D, Dmid);
  // past it, softening continues on the original envelope
  const double d2 = d0 + 0.6 * (df - d0);
  fdem::cohesive_update(p, d2, 0.0, h, tn, kss, D);
  EXPECT_NEAR(tn, p.ft * (df - d2) / (df - d0), 1e-3 * p.ft);
  EXPECT_GT(D, Dmid);
}

}  // namespace

namespace {

// A strength lowered while the separation stays (strength reduction in slope stability), or a
// step that overshoots the strength: the point initiates on the envelope and softens at once, so
// the traction never exceeds the present strength.
TEST(Cohesive, InitiationLiesOnTheEnvelopeWhenTheStrengthDrops) {
  auto p = table1();
  const double d = 0.9 * p.ft / p.kn;  // elastic at the original strength
  CohesivePoint h{0, 0, 0, 0};
  double tn, kss, D;
  fdem::cohesive_update(p, d, 0.0, h, tn, kss, D);
  EXPECT_DOUBLE_EQ(D, 0.0);
  EXPECT_NEAR(tn, 0.9 * p.ft, 1e-6 * p.ft);
  p.ft *= 0.5;  // strength halved at the same separation
  fdem::cohesive_update(p, d, 0.0, h, tn, kss, D);
  const double dm0 = p.ft / p.kn, dmf = 2 * p.Gnc / p.ft;
  EXPECT_NEAR(h.dm0, dm0, 1e-9 * dm0);
  EXPECT_NEAR(tn, p.ft * (dmf - d) / (dmf - dm0), 1e-9 * p.ft);  // on the softening line
  EXPECT_LE(tn, p.ft);
  EXPECT_GT(D, 0.0);
  // the energy dissipated so far is the area between the envelope and the secant
  EXPECT_NEAR(fdem::cohesive_dissipation(h), p.Gnc * (d - dm0) / (dmf - dm0), 1e-9 * p.Gnc);
}

}  // namespace

namespace {

// Strength reduction of an initiated point (slope stability, CohesiveParams::rescale): the
// softening envelope follows the present strength, and the energy the point releases when its
// damage rises at fixed separation is dissipated, so that work = stored + dissipated throughout.
CohesiveParams reduced(CohesiveParams p0, double srf_old, double srf_new) {
  CohesiveParams p = p0;
  p.ft = p0.ft / srf_new;
  p.c = p0.c / srf_new;
  p.tanphi = p0.tanphi / srf_new;
  p.rescale = srf_old / srf_new;
  return p;
}

TEST(Cohesive, EnvelopeFollowsTheReducedStrength) {
  const auto p0 = table1();
  // mode II, a little past initiation at SRF 1
  const double s0 = p0.c / p0.ks, sf = 2 * p0.Gsc / p0.c;
  const double d = s0 + 0.05 * (sf - s0);
  CohesivePoint h{0, 0, 0, 0};
  double tn, kss, D;
  fdem::cohesive_update(p0, 0.0, 0.5 * s0, h, tn, kss, D);
  fdem::cohesive_update(p0, 0.0, d, h, tn, kss, D);
  const double D1 = D, ts1 = kss * d;
  EXPECT_NEAR(ts1, p0.c * (sf - d) / (sf - s0), 1e-9 * p0.c);
  const double stored1 = fdem::cohesive_stored(p0, 0.0, d, D1), wd1 = h.wd;
  // SRF 1 -> 2 at the same separation: the point is on the envelope of c / 2 with the same G_sc
  const auto p2 = reduced(p0, 1.0, 2.0);
  fdem::cohesive_update(p2, 0.0, d, h, tn, kss, D);
  const double s2 = 0.5 * s0, sf2 = 2 * sf;
  EXPECT_NEAR(h.dm0, s2, 1e-12 * s0);
  EXPECT_NEAR(h.dmf, sf2, 1e-12 * sf);
  EXPECT_NEAR(kss * d, 0.5 * p0.c * (sf2 - d) / (sf2 - s2), 1e-9 * p0.c);
  EXPECT_GT(D, D1);
  // nothing was done on the point: the stored energy it lost is dissipated
  EXPECT_NEAR(fdem::cohesive_stored(p2, 0.0, d, D) + h.wd, stored1 + wd1, 1e-9 * (stored1 + wd1));
  // a second update at the same strength changes nothing
  const CohesivePoint before = h;
  auto p2b = p2;
  p2b.rescale = 1.0;
  fdem::cohesive_update(p2b, 0.0, d, h, tn, kss, D);
  EXPECT_EQ(h.dmax, before.dmax);
  EXPECT_EQ(h.wd, before.wd);
}

// Loading to failure while the strength falls step by step (mixed mode, 45 degrees, SRF 1 ->
// 2.5 along the path): the point stays on the envelope of the present strength, the work
// integrated from the tractions equals stored + dissipated energy throughout, and at failure all
// of it is dissipated. That is more than the G_c of the mode mix (the envelope of the final
// strength): earlier the point followed higher envelopes; the reduction divides the strengths,
// not G_c (the area under every envelope is G_c).
TEST(Cohesive, StrengthFallingDuringSofteningDissipatesTheWorkDone) {
  const auto p0 = table1();
  const double a = 45 * M_PI / 180, cn = std::cos(a), cs = std::sin(a);
  const double K = p0.kn * cn * cn + p0.ks * cs * cs;
  const double GS = p0.ks * cs * cs, GT = p0.kn * cn * cn + GS;
  const double gc = p0.Gnc + (p0.Gsc - p0.Gnc) * std::pow(GS / GT, p0.eta);
  const double len = 6 * 2 * p0.Gsc / std::min(p0.ft, p0.c);
  const int n = 400000;
  CohesivePoint h{0, 0, 0, 0};
  double work = 0, tn0 = 0, ts0 = 0, dn0 = 0, ds0 = 0, srf_old = 1.0, D = 0;
  int on_envelope = 0;
  double dm0_1 = 0;  // the initiation separation at SRF 1
  for (int i = 1; i <= n; ++i) {
    const double u = static_cast<double>(i) / n, s = u * u * u;
    const double srf = 1.0 + 1.5 * std::sqrt(u);  // 1 -> 2.5 along the path, mostly while softening
    const auto p = reduced(p0, srf_old, srf);
    srf_old = srf;
    const double dn = s * len * cn, ds = s * len * cs;
    double tn, kss;
    const bool initiated = h.dm0 > 0;
    fdem::cohesive_update(p, dn, ds, h, tn, kss, D);
    if (!initiated && h.dm0 > 0) dm0_1 = h.dm0 * srf;
    const double ts = kss * ds;
    work += 0.5 * (tn + tn0) * (dn - dn0) + 0.5 * (ts + ts0) * (ds - ds0);
    if (i % 10000 == 0) {
      EXPECT_NEAR(fdem::cohesive_stored(p, dn, ds, D) + h.wd, work, 1e-3 * gc) << "step " << i;
      const double dm = s * len;
      const double e0 = dm0_1 / srf, ef = 2 * gc / (K * e0);  // envelope of the present strength
      if (h.dm0 > 0 && dm < ef) {  // (1 - D) K dm on it
        EXPECT_NEAR(h.dm0 / e0, 1.0, 1e-9) << "step " << i;
        EXPECT_NEAR(h.dmf / ef, 1.0, 1e-9) << "step " << i;
        EXPECT_NEAR((1 - D) * K * dm, K * e0 * (ef - dm) / (ef - e0), 1e-6 * p0.ft) << "step " << i;
        ++on_envelope;
      }
    }
    dn0 = dn; ds0 = ds; tn0 = tn; ts0 = ts;
  }
  EXPECT_GT(on_envelope, 5);
  EXPECT_DOUBLE_EQ(D, 1.0);
  EXPECT_NEAR(h.wd / work, 1.0, 2e-3);
  EXPECT_GT(h.wd, gc);
}

// Damage never heals under a change of strength: far into the softening branch a reduction would
// lower D (G_c is kept, so dmf grows), and so would a strength that rises again. At a fixed
// separation, through a sequence of factors up and down, D never falls, stored + dissipated
// energy stays what the work put in, and where D stays the present secant meets the new envelope
// at dmax (the point softens further on the new envelope from there).
TEST(Cohesive, ChangingTheStrengthNeverHealsDamage) {
  const auto p0 = table1();
  const double d0 = p0.ft / p0.kn, df = 2 * p0.Gnc / p0.ft;
  const double d = d0 + 0.8 * (df - d0);
  CohesivePoint h{0, 0, 0, 0};
  double tn, kss, D;
  fdem::cohesive_update(p0, 0.5 * d0, 0.0, h, tn, kss, D);
  fdem::cohesive_update(p0, d, 0.0, h, tn, kss, D);
  const double total = fdem::cohesive_stored(p0, d, 0.0, D) + h.wd;
  double srf_old = 1.0, Dprev = D;
  int kept = 0;
  for (double srf : {3.0, 2.0, 1.2, 2.5, 4.0}) {
    const auto p = reduced(p0, srf_old, srf);
    srf_old = srf;
    fdem::cohesive_update(p, d, 0.0, h, tn, kss, D);
    EXPECT_GE(D, Dprev - 1e-13) << "SRF " << srf;
    EXPECT_NEAR(fdem::cohesive_stored(p, d, 0.0, D) + h.wd, total, 1e-9 * total) << "SRF " << srf;
    EXPECT_GE(h.dmax, d);
    EXPECT_NEAR(h.dm0, d0 / srf, 1e-9 * d0) << "SRF " << srf;  // the envelope of the present strength
    if (std::fabs(D - Dprev) < 1e-13 && D < 1.0) {
      ++kept;
      const double env = p0.kn * h.dm0 * (h.dmf - h.dmax) / (h.dmf - h.dm0);
      EXPECT_NEAR((1 - D) * p0.kn * h.dmax, env, 1e-6 * p0.ft) << "SRF " << srf;
    }
    Dprev = D;
  }
  EXPECT_GE(kept, 2);  // the sequence did reach states where the new envelope would heal
  // a failed point stays failed when the strength rises
  CohesivePoint f{0, 0, 0, 0};
  fdem::cohesive_update(p0, 0.5 * d0, 0.0, f, tn, kss, D);
  fdem::cohesive_update(p0, 1.5 * df, 0.0, f, tn, kss, D);
  ASSERT_DOUBLE_EQ(D, 1.0);
  fdem::cohesive_update(reduced(p0, 1.0, 0.5), 1.5 * df, 0.0, f, tn, kss, D);
  EXPECT_DOUBLE_EQ(D, 1.0);
  fdem::cohesive_update(reduced(p0, 0.5, 3.0), 1.5 * df, 0.0, f, tn, kss, D);
  EXPECT_DOUBLE_EQ(D, 1.0);
}

}  // namespace
