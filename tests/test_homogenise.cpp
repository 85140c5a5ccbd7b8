// Effective elastic moduli of a mesh with its interfaces (`fdem check --moduli`,
// src/solver/homogenise.hpp): exact for a continuum, the crossed-diagonal mesh's closed form
// (cases/uniaxial_compression/README.md) with interfaces, and the report's fits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "solver/homogenise.hpp"
#include "solver_fixtures.hpp"
#include "test_files.hpp"

namespace {

using fdem::EffectiveModuli;

void expect_rel(double got, double want, double tol, const char* what) {
  EXPECT_NEAR(got, want, tol * std::abs(want)) << what;
}

TEST(EffectiveModuli, ContinuumIsExactInPlaneStrainPlaneStressAnd3D) {
  const double E = 30e9, nu = 0.25;
  for (bool plane_stress : {false, true}) {
    fdem::Case c = fdem_test::basic_case(2, E, nu);
    c.plane_stress = plane_stress;
    const fdem::HostMesh m = fdem::generate_crossed_rectangle(0, 0, 0.2, 0.1, 8, 4);
    const EffectiveModuli r = fdem::effective_moduli(c, m);
    const auto& S = r.compliance;
    const double a = plane_stress ? 1 / E : (1 - nu * nu) / E,
                 b = plane_stress ? -nu / E : -nu * (1 + nu) / E;
    expect_rel(S[0][0], a, 1e-8, "S_xx");
    expect_rel(S[1][1], a, 1e-8, "S_yy");
    expect_rel(S[0][1], b, 1e-8, "S_xy");
    expect_rel(S[2][2], 2 * (1 + nu) / E, 1e-8, "S_shear");
    EXPECT_NEAR(S[0][2], 0.0, 1e-8 * a);
    const nlohmann::json j = fdem::effective_moduli_report(c, r);
    expect_rel(j["isotropic_fit"]["E_Pa"].get<double>(), E, 1e-8, "fitted E");
    expect_rel(j["isotropic_fit"]["nu"].get<double>(), nu, 1e-8, "fitted nu");
  }
  fdem::Case c = fdem_test::basic_case(3, E, nu);
  const fdem::HostMesh box = fdem::generate_box({0, 0, 0}, {0.1, 0.1, 0.1}, 3, 3, 3);
  const EffectiveModuli r = fdem::effective_moduli(c, box);
  for (int i = 0; i < 3; ++i) {
    expect_rel(r.compliance[i][i], 1 / E, 1e-8, "S_ii");
    expect_rel(r.compliance[3 + i][3 + i], 2 * (1 + nu) / E, 1e-8, "S_shear");
    for (int k = i + 1; k < 3; ++k) expect_rel(r.compliance[i][k], -nu / E, 1e-8, "S_ik");
  }
}

// The crossed-diagonal mesh with interfaces everywhere: under a uniform stress every triangle has
// the same stress and every interface its traction, so the closed form of
// cases/uniaxial_compression/README.md is exact (plane strain, cell size d), once the finite mesh
// is counted: along x, n_x cells have n_x - 1 inner grid lines across the load, so
//   1 / E_x = (1 - nu^2) / E + (1 / d) ((n_x - 1) / n_x / kn + (1 / kn + 1 / ks) / sqrt(2))
//   lateral / axial strain = E_x (nu (1 + nu) / E + (1 / ks - 1 / kn) / (sqrt(2) d))
// (the README's form is the limit of many cells).
TEST(EffectiveModuli, CrossedMeshWithInterfacesFollowsItsClosedForm) {
  const double E = 72e9, nu = 0.2, d = 2.5e-3;
  const int nx = 16, ny = 12;
  struct Row {
    double kn, ks;
  };
  // the uniaxial case's interfaces, and kn = E / (0.1 d), ks = G / (0.1 d) (the guideline)
  for (const Row& k : {Row{3.6e14, 1.5e14}, Row{E / (0.1 * d), E / (2 * (1 + nu)) / (0.1 * d)}}) {
    fdem::Case c = fdem_test::basic_case(2, E, nu);
    c.interface_materials = {fdem_test::strong_interface(k.kn, k.ks)};
    c.fracture_material = 0;
    c.fracturable_regions = {"body"};
    fdem::HostMesh m = fdem::generate_crossed_rectangle(0, 0, nx * d, ny * d, nx, ny);
    fdem::insert_interfaces(m, {true});
    const EffectiveModuli r = fdem::effective_moduli(c, m);
    auto modulus = [&](int n) {
      return 1 /
             ((1 - nu * nu) / E + (1 / d) * ((n - 1.0) / n / k.kn + (1 / k.kn + 1 / k.ks) / std::sqrt(2.0)));
    };
    const double Ex = modulus(nx), Ey = modulus(ny), Einf = modulus(1 << 30);
    const double lat = Ex * (nu * (1 + nu) / E + (1 / k.ks - 1 / k.kn) / (std::sqrt(2.0) * d));
    const nlohmann::json j = fdem::effective_moduli_report(c, r);
    std::printf(
        "crossed mesh %dx%d, kn %.3g, ks %.3g: E_x %.6g Pa (closed form %.6g), E_y %.6g (%.6g), "
        "many cells %.4g = %.3f E; lateral/axial %.5f (%.5f); CG %d iterations\n",
        nx, ny, k.kn, k.ks, 1 / r.compliance[0][0], Ex, 1 / r.compliance[1][1], Ey, Einf, Einf / E,
        -r.compliance[0][1] / r.compliance[0][0], lat, r.iterations);
    expect_rel(1 / r.compliance[0][0], Ex, 1e-6, "E_x");
    expect_rel(1 / r.compliance[1][1], Ey, 1e-6, "E_y");
    expect_rel(-r.compliance[0][1] / r.compliance[0][0], lat, 1e-6, "lateral / axial");
    EXPECT_LT(j["E_over_bulk_E"].get<double>(), 1.0);
  }
}

// Very stiff interfaces (Robustness III, item 6): from kn h / E about 1e5 on the solver stalled
// ("did not converge", residuals below 1e-6 printed as 0.000000), and at kn = 1e25 on another
// mesh it stopped with E = 1.0017 times the bulk's. Now every stiffness up to 1e30 converges,
// follows the closed form to 1e-6 (springs beyond what double precision resolves are solved at
// the largest ratio it does, 1e7 times the bulk at their nodes, which the report counts and says:
// E = (1 - 2.2e-7) E_bulk for kn = 1e25) and never gives an E above the bulk's.
TEST(EffectiveModuli, StiffInterfacesConvergeAndNeverStiffenTheMesh) {
  const double E = 72e9, nu = 0.2, d = 2.5e-3;
  const int nx = 16, ny = 12;
  for (double k : {1e17, 1e19, 1e21, 1e23, 1e25, 1e27, 1e30}) {
    fdem::Case c = fdem_test::basic_case(2, E, nu);
    c.interface_materials = {fdem_test::strong_interface(k, k)};
    c.fracture_material = 0;
    c.fracturable_regions = {"body"};
    fdem::HostMesh m = fdem::generate_crossed_rectangle(0, 0, nx * d, ny * d, nx, ny);
    fdem::insert_interfaces(m, {true});
    EffectiveModuli r;
    ASSERT_NO_THROW(r = fdem::effective_moduli(c, m)) << "kn " << k;
    const double Ex = 1 / ((1 - nu * nu) / E + (1 / d) * ((nx - 1.0) / nx / k + 2 / k / std::sqrt(2.0)));
    const nlohmann::json j = fdem::effective_moduli_report(c, r);
    std::printf(
        "kn %.0e: E_x %.12g (closed form %.12g), E / bulk E %.15g, %d iterations, residual %.2g "
        "(rounding %.2g), stiffest spring %.3g times the bulk, %ld capped\n",
        k, 1 / r.compliance[0][0], Ex, j["E_over_bulk_E"].get<double>(), r.iterations, r.residual, r.rounding,
        r.max_spring_ratio, r.capped_springs);
    expect_rel(1 / r.compliance[0][0], Ex, 1e-6, "E_x");
    EXPECT_LE(j["E_over_bulk_E"].get<double>(), 1.0) << "kn " << k;
    // the residual: 1e-8 of the load, or at the level of rounding in the stiff springs' forces
    EXPECT_LE(r.residual, std::max(1e-8, 16 * r.rounding)) << "kn " << k;
    EXPECT_EQ(r.capped_springs > 0, j["solver"].contains("note")) << "kn " << k;
    if (k >= 1e25) {
      EXPECT_GT(r.capped_springs, 0) << "kn " << k;
    }
  }
}

// A mesh whose pieces are held by nothing (frictional joints everywhere: the inner elements get
// no load, the outer ones an unbalanced one) has no static equilibrium: said at once, with the
// share of the load that is unbalanced as a number, where the solver ran 20 iterations per
// unknown and stopped with "did not converge" (residuals below 1e-6 printed as 0.000000).
TEST(EffectiveModuli, UnbalancedPieceIsNamed) {
  fdem::Case c = fdem_test::basic_case(2, 72e9, 0.2);
  fdem::InterfaceMaterial joint = fdem_test::strong_interface(1e14, 1e14);
  joint.ft = joint.c = 0;  // frictional: carries nothing
  c.interface_materials = {joint};
  c.fracture_material = 0;
  c.fracturable_regions = {"body"};
  fdem::HostMesh m = fdem::generate_crossed_rectangle(0, 0, 0.01, 0.0075, 4, 3);
  fdem::insert_interfaces(m, {true});
  std::string what;
  try {
    fdem::effective_moduli(c, m);
  } catch (const fdem::InputError& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("held by nothing but contact"), std::string::npos) << what;
  EXPECT_NE(what.find("carries an unbalanced load (0."), std::string::npos) << what;
  EXPECT_EQ(what.find("0.000000"), std::string::npos) << what;
}

// `fdem check --moduli` reports the same moduli for a case file (the uniaxial case's material and
// interfaces on its crossed mesh, 16 x 12 cells) as the closed form above.
TEST(EffectiveModuli, CheckReportsThem) {
  const std::string dir = fdem::test::scratch_dir("moduli", "cli");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/case.json") << R"({
    "name": "moduli", "dimension": 2, "time": {"end_time": 1e-3},
    "mesh": {"generator": "rectangle", "size": [0.04, 0.03], "cells": [16, 12]},
    "analysis": {"plane": "strain", "thickness": 1.0},
    "materials": {"rock": {"density": 2700, "E": 72e9, "nu": 0.2}}, "regions": {"body": "rock"},
    "interface_materials": {"rock_if": {"kn": 3.6e14, "ks": 1.5e14, "ft": 8e6, "c": 16.56e6, "phi_deg": 45,
                                        "Gnc": 30, "Gsc": 600}},
    "fracture": {"regions": ["body"], "interface_material": "rock_if"}})";
  const std::string env = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ";
  ASSERT_EQ(fdem::test::system_status(env + FDEM_BINARY + " check " + dir + "/case.json --moduli > " + dir +
                                      "/check.log 2> " + dir + "/err.log"),
            0)
      << fdem::test::slurp(dir + "/err.log");
  const std::string log = fdem::test::slurp(dir + "/check.log");
  const nlohmann::json r = nlohmann::json::parse(log.substr(0, log.rfind('}') + 1));
  const nlohmann::json& m = r["effective_moduli"];
  const double E = 72e9, nu = 0.2, d = 2.5e-3, kn = 3.6e14, ks = 1.5e14;
  const double Ex = 1 / ((1 - nu * nu) / E + (1 / d) * (15.0 / 16 / kn + (1 / kn + 1 / ks) / std::sqrt(2.0)));
  expect_rel(m["apparent"]["E_x_Pa"].get<double>(), Ex, 1e-6, "E_x");
  EXPECT_EQ(m["bulk"]["E_Pa"].get<double>(), E);
  EXPECT_LT(m["solver"]["relative_residual"].get<double>(), 1e-8);
  EXPECT_NE(fdem::test::slurp(dir + "/err.log").find("stress state 3 of 3"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
