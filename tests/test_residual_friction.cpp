// The residual friction of a softening interface point (docs/theory.md section 4): one 2D
// interface element (two node pairs) driven along a path by moving its B nodes, its forces from
// interface_forces, the work they take integrated by the trapezoid rule. Checks the shear
// traction from the Mohr-Coulomb peak down the softening branch to sigma_n tan(phi_r), the
// ledger (work = stored + fracture + friction), and that the fracture energies of the cohesive
// law are kept (in tension, in shear under compression, and under the paper's law).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "kernels/interface.hpp"

namespace {

using fdem::CohesiveParams;
using fdem::CohesivePoint;
using fdem::SlipPoint;

CohesiveParams joint(double phi_r_deg) {
  // kn = ks = 1e11 Pa/m, ft 1 MPa, c 1.5 MPa, phi 33 degrees, Gnc 10 N/m, Gsc 100 N/m
  CohesiveParams p{1e11, 1e11, 1e6, 1.5e6, std::tan(33 * M_PI / 180), 10, 100, 2.0};
  p.tanphir = phi_r_deg < 0 ? -1.0 : std::tan(phi_r_deg * M_PI / 180);
  return p;
}

struct Walk {
  std::vector<double> tau, slip;  // shear traction on side A per step, and the slip
  double work = 0, stored = 0, fracture = 0, friction = 0, damage = 0;
};

// B moves by (dx(u), dy(u)) for u in [0, 1] in n steps (A fixed at y = 0, length 1: the normal
// points from A to B, (0, -1), so dy > 0 closes the interface).
template <class Path>
Walk walk(const CohesiveParams& p, Path path, int n) {
  const double ap = 0.5;
  double xa[2][2] = {{0, 0}, {1, 0}}, xb[2][2];
  CohesivePoint h[2] = {{0, 0, 0, 0}, {0, 0, 0, 0}};
  SlipPoint<2> sl[2] = {fdem::zero_slip<2>(), fdem::zero_slip<2>()};
  double fa[2][2], fb[2][2], fb0[2][2] = {{0, 0}, {0, 0}}, d0[2] = {0, 0};
  Walk w;
  for (int i = 0; i <= n; ++i) {
    double d[2];
    path(static_cast<double>(i) / n, d[0], d[1]);
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) xb[k][j] = xa[k][j] + d[j];
    const double du[2][2] = {{d[0] - d0[0], d[1] - d0[1]}, {d[0] - d0[0], d[1] - d0[1]}};
    w.damage = fdem::interface_forces<2, true>(xa, xb, ap, p, h, sl, fa, fb, du);
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) w.work -= 0.5 * (fb0[k][j] + fb[k][j]) * (d[j] - d0[j]);
    w.tau.push_back(std::abs(fa[0][0]) / ap);
    w.slip.push_back(d[0]);
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) fb0[k][j] = fb[k][j];
    d0[0] = d[0];
    d0[1] = d[1];
  }
  const double n_[2] = {0, -1};
  for (int k = 0; k < 2; ++k) {
    const double dd[2] = {xb[k][0] - xa[k][0], xb[k][1] - xa[k][1]};
    const double dn = dd[0] * n_[0] + dd[1] * n_[1], ds = std::abs(dd[0]);
    const double dmg = fdem::cohesive_damage(h[k]);
    double e[2];
    w.stored += ap * fdem::cohesive_stored(p, dn, ds, dmg);
    if (p.tanphir >= 0 && h[k].dm0 > 0) w.stored += ap * 0.5 * p.ks * fdem::elastic_slip<2>(n_, dd, sl[k], e);
    w.fracture += ap * h[k].wd;
    w.friction += ap * sl[k].wf;
  }
  return w;
}

// Shear at a constant closure (sigma_n = kn * closure): the traction peaks at the Mohr-Coulomb
// t_p = c + sigma_n tan(phi), follows the paper's softening branch t_p (delta_mf - delta) /
// (delta_mf - delta_m0) (delta_m0 = t_p / k_s, delta_mf = 2 G_sc / t_p) until it meets mu sigma_n
// (mu = tan(phi_r)) and stays there. Dissipated in all: G_sc (the work of the cohesive branch)
// plus the work of the friction traction (mu sigma_n - branch from where the branch meets
// mu sigma_n, delta_c, to delta_mf, and mu sigma_n beyond) less the energy its spring keeps; of
// it the fracture dissipation is G_sc less what the damage moved into the friction spring (which
// the slip then dissipates as friction). The work is what is stored, plus fracture, plus
// friction, within 0.05 % (the moved energy is booked at the step's end values: 0.012 % in the
// most brittle case here, delta_mf = 1.19 delta_m0).
TEST(ResidualFriction, ShearUnderCompressionGoesFromThePeakToTheResidualFriction) {
  for (double sigma : {1.5e6, 4e6}) {
    for (double phi_r : {33.0, 25.0}) {
      const CohesiveParams p = joint(phi_r);
      const double closure = sigma / p.kn, smax = 10 * 2 * p.Gsc / (p.c + sigma * p.tanphi);
      const Walk w = walk(p, [&](double u, double& dx, double& dy) {
        dy = closure * std::min(1.0, 10 * u);  // close first, then slide
        dx = smax * std::max(0.0, (u - 0.1) / 0.9);
      }, 200000);
      const double tp = p.c + sigma * p.tanphi, mus = p.tanphir * sigma, d0 = tp / p.ks, df = 2 * p.Gsc / tp;
      const double dc = df - mus * (df - d0) / tp;  // where the branch meets mu sigma_n
      double worst = 0;  // largest departure from max(branch, mu sigma_n) after the peak
      size_t ip = std::max_element(w.tau.begin(), w.tau.end()) - w.tau.begin();
      for (size_t i = ip; i < w.tau.size(); ++i) {
        const double branch = w.slip[i] < df ? tp * (df - w.slip[i]) / (df - d0) : 0.0;
        worst = std::max(worst, std::abs(w.tau[i] - std::max(branch, mus)));
      }
      const double lowest = *std::min_element(w.tau.begin() + ip, w.tau.end());
      std::printf("sigma_n %.3g MPa, phi_r %.0f: peak %.6g MPa (c + sigma_n tan(phi) %.6g), largest departure from "
                  "the curve %.3g Pa, friction %.6g J against %.6g, fracture %.6g J (G_sc %.6g)\n",
                  sigma / 1e6, phi_r, w.tau[ip] / 1e6, tp / 1e6, worst, w.friction,
                  mus * (smax - dc) - 0.5 * mus * (df - dc) - 0.5 * mus * mus / p.ks, w.fracture, p.Gsc);
      EXPECT_NEAR(w.tau[ip], tp, 1e-3 * tp) << sigma << " " << phi_r;
      EXPECT_LT(worst, 1e-3 * tp) << sigma << " " << phi_r;
      EXPECT_GT(lowest, mus * (1 - 1e-9)) << sigma << " " << phi_r;
      EXPECT_NEAR(w.tau.back(), mus, 1e-9 * mus) << sigma << " " << phi_r;
      EXPECT_DOUBLE_EQ(w.damage, 1.0);
      const double fric = mus * (smax - dc) - 0.5 * mus * (df - dc) - 0.5 * mus * mus / p.ks;  // area 1
      EXPECT_NEAR(w.fracture + w.friction, p.Gsc + fric, 2e-3 * (p.Gsc + fric)) << sigma << " " << phi_r;
      EXPECT_LT(w.fracture, p.Gsc);
      EXPECT_NEAR(w.work, w.stored + w.fracture + w.friction, 5e-4 * w.work) << sigma << " " << phi_r;
    }
  }
}

// Opening (mode I) and the paper's law under compression: no friction, and the fracture energy
// of the cohesive law (Gnc in tension; Gsc for the paper's law in shear under compression) is
// all the work less what stays stored.
TEST(ResidualFriction, TensionAndThePaperLawKeepTheFractureEnergy) {
  const CohesiveParams p = joint(25);
  const double dmax = 10 * 2 * p.Gnc / p.ft;
  const Walk open = walk(p, [&](double u, double& dx, double& dy) { dx = 0; dy = -dmax * u; }, 200000);
  EXPECT_DOUBLE_EQ(open.friction, 0.0);
  EXPECT_NEAR(open.fracture, p.Gnc * 1.0, 2e-3 * p.Gnc);  // length 1: area 1
  EXPECT_NEAR(open.work, open.fracture + open.stored, 1e-4 * open.work);
  const CohesiveParams paper = joint(-1);
  const double sigma = 2e6, closure = sigma / p.kn, smax = 10 * 2 * p.Gsc / (p.c + sigma * p.tanphi);
  const Walk sh = walk(paper, [&](double u, double& dx, double& dy) {
    dy = closure * std::min(1.0, 10 * u);
    dx = smax * std::max(0.0, (u - 0.1) / 0.9);
  }, 200000);
  EXPECT_DOUBLE_EQ(sh.friction, 0.0);
  EXPECT_LT(sh.tau.back(), 1e-9 * p.c);  // failed: no shear
  EXPECT_NEAR(sh.fracture, p.Gsc, 2e-3 * p.Gsc);
}

}  // namespace
