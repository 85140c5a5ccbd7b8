// Regression runs of the paper's cases at reduced cost (coarser loading, CI-sized), through the
// real command line. Tolerances are justified in each case's README.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
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
