// Regression runs of the paper's cases at reduced cost (coarser loading, CI-sized), through the
// real command line. Tolerances are justified in each case's README.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

using fdem::test::slurp;

template <class T>
std::vector<T> read_dataset(hid_t file, const std::string& name, hid_t type, std::vector<hsize_t>& dims) {
  const hid_t d = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  const hid_t sp = H5Dget_space(d);
  dims.assign(static_cast<size_t>(H5Sget_simple_extent_ndims(sp)), 0);
  H5Sget_simple_extent_dims(sp, dims.data(), nullptr);
  size_t n = 1;
  for (auto v : dims) n *= v;
  std::vector<T> out(n);
  H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(sp);
  H5Dclose(d);
  return out;
}

// Name of the last snapshot group ("step_...") of an open snapshots.h5, "" if none.
std::string last_step(hid_t f) {
  std::string last;
  H5Literate(
      f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        if (std::string(name).rfind("step_", 0) == 0) *static_cast<std::string*>(data) = name;
        return 0;
      },
      &last);
  return last;
}

// Brazilian disc, reduced (issue 23: one mesh must not decide the strength): the case as shipped
// (loaded diameter meshed as element edges in a mesh symmetric about it, padded platens, 0.1 m/s
// approach for 0.26 mm, then 0.0125 m/s, local damping 0.1) on two of the ten R/12 meshes of the
// scatter study (4.10 and 4.38 mm; the default is 3 mm = R/17). Measured on the ten
// (perf/brazil_scatter.py, cases/brazilian_disc/README.md): mean +1.29 % from f_t, standard
// deviation 0.36 %, +0.82 to +1.84 %; these two +1.79 and +0.82 %. Each run: the tensile strength
// 2 P / (pi D t) between f_t - 0.5 % and f_t + 3 % (1.3 and 1.2 points beyond the ten; the same
// meshes without the symmetry gave up to +6.9 %, the case at 0.1 m/s throughout with damping 0.7
// +7.5 to +10.3 %), and the failed interfaces of the central half of the diameter (|y| < R/2)
// reach from below y = -R/3 to above R/3 and lie within R/10 of the loaded diameter on average
// (the paper's setting, case_paper.json, gives 12 mm = 0.24 R on average over ten R/12 meshes).
class CaseBrazilianDiscMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(CaseBrazilianDiscMeshes, StrengthAndSplitAlongTheLoadedDiameter) {
  const std::string h = GetParam();
  const std::string out =
      (fs::temp_directory_path() / ("fdem_case_disc_" + std::to_string(::getpid()) + "_" + h)).string();
  fs::remove_all(out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/brazilian_disc/case.json --quiet --out " + out +
                          " --set mesh.element_size=" + h + " --set output.snapshot_count=1 > " + out +
                          ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const double ft = 8e6, R = 0.05;
  const double sigma = s["results"]["tensile_strength_Pa"].get<double>();
  EXPECT_GT(sigma / ft, 0.995) << "tensile strength " << sigma << " at h = " << h;
  EXPECT_LT(sigma / ft, 1.03) << "tensile strength " << sigma << " at h = " << h;
  EXPECT_GT(s["interfaces_failed"].get<long>(), 10);

  const hid_t f = H5Fopen((out + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dx, di, dd;
  const auto X = read_dataset<double>(f, "/mesh/reference_coordinates", H5T_NATIVE_DOUBLE, dx);
  const auto I = read_dataset<int>(f, "/mesh/interfaces", H5T_NATIVE_INT, di);
  const std::string last = last_step(f);  // the last frame
  ASSERT_FALSE(last.empty());
  const auto D = read_dataset<double>(f, "/" + last + "/damage", H5T_NATIVE_DOUBLE, dd);
  H5Fclose(f);
  double sum_abs_x = 0, ymin = 1, ymax = -1;
  int n = 0;
  for (size_t q = 0; q < D.size(); ++q) {
    if (D[q] < 1.0) continue;
    const double x = 0.5 * (X[3 * I[2 * q]] + X[3 * I[2 * q + 1]]);
    const double y = 0.5 * (X[3 * I[2 * q] + 1] + X[3 * I[2 * q + 1] + 1]);
    if (std::fabs(y) > R / 2) continue;
    sum_abs_x += std::fabs(x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
    ++n;
  }
  ASSERT_GT(n, 3) << "no failed interfaces in the central part";
  EXPECT_LT(ymin, -R / 3) << "the split does not cross the centre";
  EXPECT_GT(ymax, R / 3) << "the split does not cross the centre";
  EXPECT_LT(sum_abs_x / n, R / 10)
      << "mean distance of the central failed interfaces from the loaded diameter";
  fs::remove_all(out);
  fs::remove(out + ".log");
}

INSTANTIATE_TEST_SUITE_P(TwoMeshes, CaseBrazilianDiscMeshes, ::testing::Values("0.0041005", "0.0043785"));

// Grain-based granite disc (cases/granite_brazilian/README.md), reduced: grains of 6 mm and
// elements of 2 mm (the case: 4 and 1.5 mm), platens at 0.4 m/s (the case: 0.2), seed 1. Measured
// on seeds 1, 2, 3 at these settings: strength 10.14, 8.82, 10.35 MPa; the grain boundaries are
// 14.5 - 15.1 % of the interface length but 39, 51, 47 % of the failed length (the crack prefers
// them, as they are the weakest interfaces); the central failed interfaces lie 5.7, 5.1, 3.1 mm
// (0.12 - 0.23 R) from the loaded diameter on average. Asserted: strength within 7.5 - 12.5 MPa,
// the grain boundaries' share of the crack at least twice their share of the interfaces, the split
// within 0.3 R of the diameter (failed interfaces spread evenly over the central half would give
// about 0.42 R) and reaching from below -R/3 to above R/3.
TEST(CaseGraniteBrazilian, ReducedRunSplitsAlongTheDiameterMostlyBetweenGrains) {
  const std::string out =
      (fs::temp_directory_path() / ("fdem_case_granite_" + std::to_string(::getpid()))).string();
  fs::remove_all(out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/granite_brazilian/case.json --quiet --out " + out +
                          " --set parameters.grain=0.006 --set parameters.h=0.002 --set parameters.rate=0.4" +
                          " --set output.snapshot_count=1 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const double R = 0.025;
  const double sigma = s["results"]["tensile_strength_Pa"].get<double>();
  EXPECT_GT(sigma, 7.5e6);
  EXPECT_LT(sigma, 12.5e6);
  const hid_t f = H5Fopen((out + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dx, di, dd, dm;
  const auto X = read_dataset<double>(f, "/mesh/reference_coordinates", H5T_NATIVE_DOUBLE, dx);
  const auto I = read_dataset<int>(f, "/mesh/interfaces", H5T_NATIVE_INT, di);
  const auto M = read_dataset<int>(f, "/mesh/interface_material", H5T_NATIVE_INT, dm);
  const std::string last = last_step(f);  // the last frame
  ASSERT_FALSE(last.empty());
  const auto D = read_dataset<double>(f, "/" + last + "/damage", H5T_NATIVE_DOUBLE, dd);
  H5Fclose(f);
  // interface materials sorted by name: biotite_if, feldspar_if, grain_boundary_if, quartz_if
  const int gb = 2;
  double len_all = 0, len_gb = 0, crack = 0, crack_gb = 0, sum_abs_x = 0, ymin = 1, ymax = -1;
  int n = 0;
  for (size_t q = 0; q < D.size(); ++q) {
    const double* a = &X[3 * I[2 * q]];
    const double* b = &X[3 * I[2 * q + 1]];
    const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
    len_all += len;
    len_gb += M[q] == gb ? len : 0.0;
    if (D[q] < 1.0) continue;
    crack += len;
    crack_gb += M[q] == gb ? len : 0.0;
    const double x = 0.5 * (a[0] + b[0]), y = 0.5 * (a[1] + b[1]);
    if (std::fabs(y) > R / 2) continue;
    sum_abs_x += std::fabs(x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
    ++n;
  }
  ASSERT_GT(n, 3) << "no failed interfaces in the central part";
  std::printf(
      "granite (reduced): strength %.2f MPa; grain boundaries %.1f %% of the interfaces, %.1f %% of "
      "the crack; split %.2f R from the diameter\n",
      sigma / 1e6, 100 * len_gb / len_all, 100 * crack_gb / crack, sum_abs_x / n / R);
  EXPECT_GT(crack_gb / crack, 2 * len_gb / len_all);
  EXPECT_LT(sum_abs_x / n, 0.3 * R);
  EXPECT_LT(ymin, -R / 3);
  EXPECT_GT(ymax, R / 3);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

}  // namespace

namespace {

using fdem::test::read_history;

// Slope at 2 m elements (1290 elements, 114 interfaces), settled to 0.3 s, the strength
// reduction factor rising by 1 per second from 0.5 to 2.5 (twice the case's rate):
// small deformation (the crest moves by less than 1 mm while SRF < 1.5), failure (the crest has
// moved 1 cm at an SRF between 1.55 and 2.0; measured 1.85 here, 1.72 in the full run, 1.67 at
// half its rate; limit equilibrium 1.735 without and 1.57 with a tension crack), overall sliding
// (the crest has moved more than 0.5 m at SRF 2.5; measured 1.2 m, kinetic energy 1.2 MJ), and
// the energy balance within 2 % (measured 0.34 %). Before the envelope followed the strength,
// nothing moved here even at SRF 2.5. Tolerances: cases/slope_failure/README.md.
TEST(CaseSlope, ReducedRunFailsNearTheLimitEquilibriumFactorAndSlides) {
  const std::string out = (fs::temp_directory_path() / ("fdem_case_slope_" + std::to_string(::getpid()))).string();
  fs::remove_all(out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/slope_failure/case.json --quiet --out " + out +
                          " --set parameters.h=2 --set parameters.t_settle=0.3 --set parameters.srf_rate=1"
                          " --set parameters.t_end=2.3 --set output.snapshot_count=0 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  auto h = read_history(out + "/history.csv");
  const auto& srf = h["strength_reduction_factor"];
  const auto& ux = h["wedge_top_ux [m]"];
  const auto& uy = h["wedge_top_uy [m]"];
  const auto& ek = h["E_kinetic [J]"];
  ASSERT_GT(srf.size(), 100u);
  size_t i0 = 0;
  while (i0 < srf.size() && srf[i0] <= srf[0]) ++i0;
  ASSERT_LT(i0, srf.size());
  double srf_fail = 0, small = 0;
  for (size_t i = i0; i < srf.size(); ++i) {
    const double du = std::hypot(ux[i] - ux[i0], uy[i] - uy[i0]);
    if (srf[i] < 1.5) small = std::max(small, du);
    if (srf_fail == 0 && du > 0.01) srf_fail = srf[i];
  }
  EXPECT_LT(small, 1e-3) << "crest displacement before SRF 1.5";
  EXPECT_GT(srf_fail, 1.55);
  EXPECT_LT(srf_fail, 2.0);
  EXPECT_NEAR(srf.back(), 2.5, 0.01);
  EXPECT_GT(std::hypot(ux.back() - ux[i0], uy.back() - uy[i0]), 0.5) << "the wedge does not slide";
  EXPECT_LT(ux.back() - ux[i0], -0.3) << "the wedge does not move out of the face";
  EXPECT_GT(ek.back(), 1e5);
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_LT(s["energy"]["max_relative_balance_error"].get<double>(), 0.02);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

}  // namespace

namespace {

// Uniaxial compression (cases/uniaxial_compression/README.md): 50 x 100 mm, crossed-diagonal mesh
// of 5 mm cells (800 triangles), platens at 0.1 m/s each. E_eff of the crossed mesh under
// uniaxial stress (plane strain): 1 / E_eff = (1 - nu^2) / E + (1 / d) (1 / kn + (1 / kn + 1 / ks)
// / sqrt(2)).
struct UniaxialRun {
  double peak = 0, slope = 0, lateral = 0;  // Pa, Pa, lateral over axial strain (10 - 50 % of the peak)
  std::string out;
};

UniaxialRun run_uniaxial_case(const std::string& name, const std::string& sets) {
  UniaxialRun r;
  r.out = (fs::temp_directory_path() / ("fdem_case_" + name + "_" + std::to_string(::getpid()))).string();
  fs::remove_all(r.out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/uniaxial_compression/case.json --quiet --out " + r.out +
                          " --set parameters.cell=0.005 --set parameters.rate=0.1 --set output.snapshot_count=4 " +
                          sets + " > " + r.out + ".log 2>&1";
  EXPECT_EQ(run(cmd), 0) << slurp(r.out + ".log");
  auto h = read_history(r.out + "/history.csv");
  const double W = 0.05, H = 0.1;
  const auto& top = h["top_displacement [m]"];
  const auto& bot = h["bottom_displacement [m]"];
  const auto& load = h["top_load [N]"];
  const auto& ul = h["left_ux [m]"];
  const auto& ur = h["right_ux [m]"];
  if (load.empty()) return r;
  const size_t ip = std::max_element(load.begin(), load.end()) - load.begin();
  r.peak = load[ip] / W;
  // least-squares slopes of stress against axial and lateral strain over 10 - 50 % of the peak
  double sx = 0, sy = 0, sxx = 0, sxy = 0, lx = 0, lxx = 0, lxy = 0;
  int n = 0;
  for (size_t i = 0; i <= ip; ++i) {
    const double s = load[i] / W, e = (top[i] + bot[i]) / H, l = (ur[i] - ul[i]) / W;
    if (s < 0.1 * r.peak || s > 0.5 * r.peak) continue;
    sx += e; sy += s; sxx += e * e; sxy += e * s; lx += l; lxx += l * l; lxy += l * s;
    ++n;
  }
  if (n > 2) {
    r.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    r.lateral = r.slope / ((n * lxy - lx * sy) / (n * lxx - lx * lx));
  }
  return r;
}

double e_eff_crossed(double E, double nu, double kn, double ks, double d) {
  return 1.0 / ((1 - nu * nu) / E + (1 / kn + (1 / kn + 1 / ks) / std::sqrt(2.0)) / d);
}

// Table 2 parameters, platen friction 0.2: the slope of the linear part is E_eff of the crossed
// mesh within 1.5 % (measured +0.5 % here, +0.6 % at 2.5 mm cells; the paper's E / (1.1 (1 -
// nu^2)) would be 10 % stiffer), and the specimen fails in an X: in each quadrant at least five
// failed diagonal interfaces, more than half of them along the diagonal from that quadrant's
// corner to the centre (measured 10/10, 10/12, 8/12, 10/10; with the contact springs' two-mass
// stable step, 8 of 14 in the lower right quadrant). The peak lies between 150 and 450 MPa
// (measured 303 MPa here, 241 MPa at 2.5 mm, 232 MPa at 2 mm): with phi = 45 degrees no interface
// of a crossed mesh can reach Mohr-Coulomb under uniform uniaxial stress (on the diagonals tau =
// sigma_n), so the peak is set by the stress concentrations at the platen corners, and it falls
// with the cell size; the band records that, it is not a target.
TEST(CaseUniaxial, ReducedRunFollowsTheCrossedMeshModulusAndFailsInAnX) {
  const auto r = run_uniaxial_case("ucs", "");
  const double Ee = e_eff_crossed(72e9, 0.2, 3.6e14, 1.5e14, 0.005);
  EXPECT_NEAR(r.slope / Ee, 1.0, 0.015) << "slope " << r.slope << " E_eff " << Ee;
  EXPECT_GT(r.peak, 150e6);
  EXPECT_LT(r.peak, 450e6);

  const hid_t f = H5Fopen((r.out + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dx, di, dd;
  const auto X = read_dataset<double>(f, "/mesh/reference_coordinates", H5T_NATIVE_DOUBLE, dx);
  const auto I = read_dataset<int>(f, "/mesh/interfaces", H5T_NATIVE_INT, di);
  std::string last;
  H5Literate(f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
             [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
               if (std::string(name).rfind("step_", 0) == 0) *static_cast<std::string*>(data) = name;
               return 0;
             },
             &last);
  ASSERT_FALSE(last.empty());
  const auto D = read_dataset<double>(f, "/" + last + "/damage", H5T_NATIVE_DOUBLE, dd);
  H5Fclose(f);
  int diag[4] = {0, 0, 0, 0}, along[4] = {0, 0, 0, 0};
  for (size_t q = 0; q < D.size(); ++q) {
    if (D[q] < 1.0) continue;
    const int a = I[2 * q], b = I[2 * q + 1];
    const double tx = X[3 * b] - X[3 * a], ty = X[3 * b + 1] - X[3 * a + 1];
    if (std::fabs(std::fabs(tx) - std::fabs(ty)) > 1e-6 * (std::fabs(tx) + std::fabs(ty))) continue;
    const double mx = 0.5 * (X[3 * a] + X[3 * b]), my = 0.5 * (X[3 * a + 1] + X[3 * b + 1]);
    const int k = (mx > 0 ? 1 : 0) + (my < 0.05 ? 2 : 0);  // 0 UL, 1 UR, 2 LL, 3 LR
    const bool slash = tx * ty > 0;                          // along (1, 1)
    ++diag[k];
    if (slash == (k == 1 || k == 2)) ++along[k];
  }
  for (int k = 0; k < 4; ++k) {
    EXPECT_GE(diag[k], 5) << "quadrant " << k;
    EXPECT_GT(along[k], 0.5 * diag[k]) << "quadrant " << k << ": " << along[k] << " of " << diag[k];
  }
  fs::remove_all(r.out);
  fs::remove(r.out + ".log");
}

// phi = 30 degrees and frictionless platens: the stress stays uniform, every diagonal interface
// carries tau = sigma_n = sigma / 2, and Mohr-Coulomb is met on all of them at once at
// sigma = 2 c / (1 - tan(phi)) = 78.36 MPa: the peak within 4 % (measured +2.3 % here, +1.7 % at
// 2.5 mm cells); slope within 1.5 % of E_eff (measured +0.3 %) and lateral over axial strain within
// 5 % of E_eff (nu (1 + nu) / E + (1 / ks - 1 / kn) / (sqrt(2) d)) (measured -2.4 %).
TEST(CaseUniaxial, FrictionlessAtThirtyDegreesFailsAtTheDiagonalStrength) {
  const auto r = run_uniaxial_case("ucs30", "--set interface_materials.rock_if.phi_deg=30"
                                            " --set platens.0.friction=0 --set platens.1.friction=0");
  const double c = 16.56e6, tanphi = std::tan(30 * M_PI / 180);
  EXPECT_NEAR(r.peak / (2 * c / (1 - tanphi)), 1.0, 0.04) << "peak " << r.peak;
  const double E = 72e9, nu = 0.2, kn = 3.6e14, ks = 1.5e14, d = 0.005;
  const double Ee = e_eff_crossed(E, nu, kn, ks, d);
  EXPECT_NEAR(r.slope / Ee, 1.0, 0.015);
  const double lat = Ee * (nu * (1 + nu) / E + (1 / ks - 1 / kn) / (std::sqrt(2.0) * d));
  EXPECT_NEAR(r.lateral / lat, 1.0, 0.05) << "lateral over axial strain " << r.lateral;
  fs::remove_all(r.out);
  fs::remove(r.out + ".log");
}

}  // namespace

namespace {

// SEN beam (cases/sen_beam/README.md) on its own mesh (1388 triangles), the load platen at
// 0.01 m/s (twice the case's rate) to 0.15 mm, past the peak. Peak load between 3.6 and 5.0 kN
// (measured 4.29 kN; 4.23 kN at the case's rate and at half of it), the supports carrying 90 - 105 %
// of the load at the peak (measured 95 %; with the old velocity-driven pad and local damping 0.7
// they carried 67 - 75 % and the peak was 13 - 22 kN), CMOD at the peak 0.04 - 0.15 mm (measured
// 0.07 mm), and the damage starts at the notch tip and runs up from it: at least 20 damaged
// interfaces, the lowest within 5 mm above the tip, the highest above y = 130 mm, all within
// 40 mm of mid-span (measured 47 damaged between x = -7 and 25 mm, up to y = 146 mm; before, the
// main crack formed under the load at x = 150 mm), and some failed ones within 20 mm of it.
TEST(CaseSenBeam, ReducedRunCracksFromTheNotchTip) {
  const std::string out = (fs::temp_directory_path() / ("fdem_case_sen_" + std::to_string(::getpid()))).string();
  fs::remove_all(out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/sen_beam/case.json --quiet --out " + out +
                          " --set parameters.rate=0.01 --set parameters.deflection=0.15e-3"
                          " --set output.snapshot_count=1 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  auto h = read_history(out + "/history.csv");
  const auto& P = h["load_load [N]"];
  const auto& R = h["supports_load [N]"];
  const auto& ml = h["mouth_left_ux [m]"];
  const auto& mr = h["mouth_right_ux [m]"];
  ASSERT_GT(P.size(), 50u);
  const size_t ip = std::max_element(P.begin(), P.end()) - P.begin();
  EXPECT_GT(P[ip], 3600.0);
  EXPECT_LT(P[ip], 5000.0);
  EXPECT_GT(R[ip] / P[ip], 0.9);
  EXPECT_LT(R[ip] / P[ip], 1.05);
  const double cmod = mr[ip] - ml[ip];
  EXPECT_GT(cmod, 0.04e-3);
  EXPECT_LT(cmod, 0.15e-3);
  EXPECT_LT(P.back(), 0.7 * P[ip]) << "no softening after the peak";

  const hid_t f = H5Fopen((out + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dx, di, dd;
  const auto X = read_dataset<double>(f, "/mesh/reference_coordinates", H5T_NATIVE_DOUBLE, dx);
  const auto I = read_dataset<int>(f, "/mesh/interfaces", H5T_NATIVE_INT, di);
  std::string last;
  H5Literate(f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
             [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
               if (std::string(name).rfind("step_", 0) == 0) *static_cast<std::string*>(data) = name;
               return 0;
             },
             &last);
  ASSERT_FALSE(last.empty());
  const auto D = read_dataset<double>(f, "/" + last + "/damage", H5T_NATIVE_DOUBLE, dd);
  H5Fclose(f);
  int damaged = 0, failed_near = 0;
  double ymin = 1, ymax = 0, xfar = 0;
  for (size_t q = 0; q < D.size(); ++q) {
    if (D[q] <= 0) continue;
    const double x = 0.5 * (X[3 * I[2 * q]] + X[3 * I[2 * q + 1]]);
    const double y = 0.5 * (X[3 * I[2 * q] + 1] + X[3 * I[2 * q + 1] + 1]);
    ++damaged;
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
    xfar = std::max(xfar, std::fabs(x));
    if (D[q] >= 1 && std::fabs(x) < 0.02) ++failed_near;
  }
  EXPECT_GE(damaged, 20);
  EXPECT_LT(ymin, 0.080) << "the damage does not start at the notch tip (y = 75 mm)";
  EXPECT_GT(ymax, 0.130);
  EXPECT_LT(xfar, 0.040) << "damage away from the notch (under the load or at a support)";
  EXPECT_GE(failed_near, 1);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

// The double impact test (cases/sphere_double_impact, README "CI check"): at h = 6 mm the plaster
// sphere struck at 5 m/s by the 7.4 kg platen splits through its loading axis into two halves
// (measured on one thread: 52 % and 35 % of the mass, each spanning the height from -22 to +21 mm,
// their centroids 8 and 12 mm from the axis on opposite sides) by 0.26 ms; the drop weight's loss of
// kinetic energy is the work the ledger books, and the ledger closes. (A sample: at 5.2 m/s this
// coarse mesh had crushed the ends but not yet split by 0.32 ms; README, "CI check".)
TEST(CaseSphereDoubleImpact, ReducedRunSplitsThroughTheLoadingAxis) {
  const std::string out = fdem::test::scratch_dir("case", "double_impact");
  const std::string cmd = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " + std::string(FDEM_BINARY) + " run " +
                          FDEM_SOURCE_DIR + "/cases/sphere_double_impact/case.json --quiet --out " + out +
                          " --set parameters.h=0.006 --set parameters.duration=2.6e-4"
                          " --set output.snapshot_count=0 --set output.history_rows=40 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const double R = 0.025;
  const auto& big = s["fragments"]["largest"];
  ASSERT_GE(big.size(), 2u);
  double c[2][3], share = 0;
  for (int j = 0; j < 2; ++j) {
    const double f = big[j]["fraction"].get<double>();
    share += f;
    EXPECT_GT(f, 0.2) << "fragment " << j;
    // a meridian piece: from near the anvil to near the weight
    EXPECT_LT(big[j]["reference_box_min"][2].get<double>(), -0.6 * R) << "fragment " << j;
    EXPECT_GT(big[j]["reference_box_max"][2].get<double>(), 0.6 * R) << "fragment " << j;
    for (int k = 0; k < 3; ++k) c[j][k] = big[j]["reference_centroid"][k].get<double>();
  }
  EXPECT_GT(share, 0.7);
  // on opposite sides of the loading axis (z), which passes between them
  const double dot = c[0][0] * c[1][0] + c[0][1] * c[1][1];
  EXPECT_LT(dot, 0.0);
  const double ex = c[1][0] - c[0][0], ey = c[1][1] - c[0][1];
  const double dist = std::fabs(c[0][0] * ey - c[0][1] * ex) / std::hypot(ex, ey);  // axis to their line
  EXPECT_LT(dist, 0.25 * R);

  const auto h = fdem::test::read_history(out + "/history.csv");
  const double M = 7.4, v0 = 5;
  const double V = h.at("weight_speed [m/s]").back(), W = h.at("W_external [J]").back();
  EXPECT_GT(W, 1.0);  // (3.0 J measured)
  EXPECT_NEAR(0.5 * M * (v0 * v0 - V * V), W, 1e-4 * W);
  EXPECT_GT(s["energy"]["fracture_J"].get<double>(), 0.1 * W);
  EXPECT_LT(s["energy"]["max_relative_balance_error"].get<double>(), 0.03);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

}  // namespace
