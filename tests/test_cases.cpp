// Regression runs of the paper's cases at reduced cost (coarser loading, CI-sized), through the
// real command line. Tolerances are justified in each case's README.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

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

// Brazilian disc at the paper's element size (3 mm) and a loading rate of 0.1 m/s per platen
// (100 times the paper's; the strength moved by less than 1 % between 0.02, 0.05 and 0.1 m/s,
// cases/brazilian_disc/README.md): the tensile strength 2 P / (pi D L) within 5 % of the input
// f_t = 8 MPa, and a split through the central half of the disc parallel to the loaded diameter:
// the failed interfaces with |y| < R/2 reach from below y = -R/3 to above y = R/3, and lie within
// R/3 of the diameter on average. (On this mesh the split runs about 15 mm = 0.3 R left of the
// diameter: cases/brazilian_disc/README.md; the tolerance records that, it is not a target.)
TEST(CaseBrazilianDisc, ReducedRunGivesInputStrengthAndCentralSplit) {
  const std::string out = (fs::temp_directory_path() / ("fdem_case_disc_" + std::to_string(::getpid()))).string();
  fs::remove_all(out);
  const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                          "/cases/brazilian_disc/case.json --quiet --out " + out +
                          " --set mesh.element_size=0.003 --set parameters.rate=0.1"
                          " --set output.snapshot_count=4 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const double ft = 8e6, R = 0.05;
  const double sigma = s["results"]["tensile_strength_Pa"].get<double>();
  EXPECT_NEAR(sigma / ft, 1.0, 0.05) << "tensile strength " << sigma;
  EXPECT_GT(s["interfaces_failed"].get<long>(), 10);

  const hid_t f = H5Fopen((out + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dx, di, dd;
  const auto X = read_dataset<double>(f, "/mesh/reference_coordinates", H5T_NATIVE_DOUBLE, dx);
  const auto I = read_dataset<int>(f, "/mesh/interfaces", H5T_NATIVE_INT, di);
  // last frame
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
  EXPECT_LT(sum_abs_x / n, R / 3) << "mean distance of the central failed interfaces from the loaded diameter";
  fs::remove_all(out);
}

}  // namespace

namespace {

// history.csv as columns by name.
std::map<std::string, std::vector<double>> read_history(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  std::vector<std::string> names;
  {
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) names.push_back(x);
  }
  std::map<std::string, std::vector<double>> cols;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string x;
    for (size_t k = 0; k < names.size() && std::getline(ss, x, ','); ++k) cols[names[k]].push_back(std::stod(x));
  }
  return cols;
}

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
}

}  // namespace
