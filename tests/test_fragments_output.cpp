// Fragment output of a run (fragments.csv, summary.json, the snapshot cell field), the case keys
// that go with it (output.fragments, mesh.element_size for .geo files) and the shipped impact and
// crushing cases.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "solver/run.hpp"
#include "test_files.hpp"

namespace {

using namespace fdem;
namespace fs = std::filesystem;

const std::string kCases = std::string(FDEM_SOURCE_DIR) + "/cases/";

using fdem::test::slurp;

std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    std::vector<std::string> r;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) r.push_back(cell);
    rows.push_back(r);
  }
  return rows;
}

std::string tmpdir(const std::string& name) {
  return (fs::temp_directory_path() / ("fdem_frag_" + name + "_" + std::to_string(::getpid()))).string();
}

// The 2D impact at 15 m/s on a coarse mesh for 150 us: fragments.csv has the documented columns
// and one row per history row, its mass column stays the particle's mass, its last row agrees
// with summary.json, and the snapshots carry the fragment field (checked by check_snapshots.py).
TEST(FragmentsOutput, RunWritesCsvSummaryAndSnapshotField) {
  RunOptions opt;
  opt.out_dir = tmpdir("run");
  opt.progress = false;
  opt.overrides = {"parameters.speed=15", "parameters.h=0.008", "parameters.duration=150e-6",
                   "output.snapshot_count=2", "output.history_rows=30"};
  const auto s = run_case(kCases + "particle_impact_2d/case.json", opt);
  const auto rows = read_csv(opt.out_dir + "/fragments.csv");
  ASSERT_GE(rows.size(), 2u);
  std::vector<std::string> want = {"time [s]", "step", "fragments", "largest_fraction",
                                   "largest_mass [kg]", "total_mass [kg]", "single_element_fragments"};
  for (const char* p : {"count_", "mass_"})
    for (const char* b : {"1e-1", "1e-2", "1e-3", "1e-4", "1e-5", "1e-6", "1e-7", "0"})
      want.push_back(std::string(p) + b);
  EXPECT_EQ(rows[0], want);
  const auto hist = read_csv(opt.out_dir + "/history.csv");
  EXPECT_EQ(rows.size(), hist.size());
  bool has_momentum = false;
  for (const auto& h : hist[0]) has_momentum = has_momentum || h == "momentum_y [N s]";
  EXPECT_TRUE(has_momentum);
  const double m0 = std::stod(rows[1][5]);
  for (size_t r = 1; r < rows.size(); ++r) {
    ASSERT_EQ(rows[r].size(), want.size());
    EXPECT_EQ(rows[r][0], hist[r][0]) << "row " << r;  // same instants as history.csv
    EXPECT_NEAR(std::stod(rows[r][5]), m0, 1e-9 * m0);
    double n = 0, mf = 0;
    for (int b = 0; b < 8; ++b) {
      n += std::stod(rows[r][7 + b]);
      mf += std::stod(rows[r][15 + b]);
    }
    EXPECT_EQ(n, std::stod(rows[r][2])) << "row " << r;
    EXPECT_NEAR(mf, 1.0, 1e-9) << "row " << r;
  }
  EXPECT_EQ(rows[1][2], "1");  // intact before the impact
  const auto& f = s["fragments"];
  EXPECT_GT(f["count"].get<int>(), 1);
  EXPECT_EQ(std::to_string(f["count"].get<int>()), rows.back()[2]);
  EXPECT_NEAR(f["total_mass_kg"].get<double>(), m0, 1e-9 * m0);
  EXPECT_NEAR(f["largest_fraction"].get<double>(), f["largest_fractions"][0].get<double>(), 1e-12);
  EXPECT_EQ(f["distribution"]["count"].size(), 8u);
  const auto summary = nlohmann::json::parse(slurp(opt.out_dir + "/summary.json"));
  EXPECT_EQ(summary["fragments"], f);
  EXPECT_EQ(summary["outputs"]["fragments"], opt.out_dir + "/fragments.csv");
  const std::string xdmf = slurp(opt.out_dir + "/snapshots.xdmf");
  EXPECT_NE(xdmf.find("Name=\"fragment\""), std::string::npos);
  if (std::system("/usr/bin/python3 -c 'import h5py' > /dev/null 2>&1") == 0) {
    const std::string cmd = "/usr/bin/python3 " + std::string(FDEM_SOURCE_DIR) + "/scripts/check_snapshots.py " +
                            opt.out_dir + " > " + opt.out_dir + ".check 2>&1";
    const int rc = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0) << slurp(opt.out_dir + ".check");
    fs::remove(opt.out_dir + ".check");
  }
  fs::remove_all(opt.out_dir);
}

// output.fragments = false, or a case without interfaces: no fragments.csv, no summary entry.
TEST(FragmentsOutput, OffWhenAskedOrWithoutInterfaces) {
  RunOptions opt;
  opt.out_dir = tmpdir("off");
  opt.progress = false;
  opt.overrides = {"parameters.h=0.01", "parameters.duration=20e-6", "output.fragments=false",
                   "output.snapshot_count=0"};
  auto s = run_case(kCases + "particle_impact_2d/case.json", opt);
  EXPECT_FALSE(fs::exists(opt.out_dir + "/fragments.csv"));
  EXPECT_FALSE(s.contains("fragments"));
  fs::remove_all(opt.out_dir);
  opt.overrides = {"parameters.h=0.01", "parameters.duration=20e-6", "output.snapshot_count=0",
                   "fracture=null"};
  s = run_case(kCases + "particle_impact_2d/case.json", opt);
  EXPECT_FALSE(fs::exists(opt.out_dir + "/fragments.csv"));
  EXPECT_FALSE(s.contains("fragments"));
  fs::remove_all(opt.out_dir);
}

TEST(FragmentsOutput, CaseKeyIsABoolean) {
  const std::string path = kCases + "particle_impact_2d/case.json";
  EXPECT_TRUE(load_case(path).output_fragments);
  EXPECT_EQ(load_case(path).resolved["output"]["fragments"], true);
  EXPECT_FALSE(load_case(path, {"output.fragments=false"}).output_fragments);
  try {
    load_case(path, {"output.fragments=1"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("output.fragments"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("true or false"), std::string::npos) << e.what();
  }
}

// The shipped cases parse; the irregular grain's .geo is meshed with the case's element size
// (a smaller size gives more elements) and element_size on a .msh file is refused.
TEST(ImpactCases, ShippedCasesLoadAndGeoElementSizeControlsTheMesh) {
  for (const char* f : {"particle_impact_2d/case.json", "particle_impact_3d/case.json",
                        "particle_impact_3d/multi/case.json", "grain_crushing_3d/case.json",
                        "grain_crushing_3d/case_polyhedron.json"})
    EXPECT_NO_THROW(load_case(kCases + f)) << f;
  const Case coarse = load_case(kCases + "grain_crushing_3d/case_polyhedron.json", {"parameters.h=0.008"});
  const Case fine = load_case(kCases + "grain_crushing_3d/case_polyhedron.json", {"parameters.h=0.005"});
  EXPECT_EQ(coarse.mesh.element_size, 0.008);
  const HostMesh mc = build_mesh(coarse.mesh, 3), mf = build_mesh(fine.mesh, 3);
  EXPECT_GT(mc.num_elems(), 50);
  EXPECT_GT(mf.num_elems(), 2 * mc.num_elems());
  EXPECT_EQ(mc.region_names, std::vector<std::string>{"grain"});
  EXPECT_TRUE(mc.node_sets.count("surface"));
  // the mesh fills the grain: z extent as the case's parameters say
  double zmin = 1, zmax = -1;
  for (int i = 0; i < mf.num_nodes(); ++i) {
    zmin = std::min(zmin, mf.X[3 * i + 2]);
    zmax = std::max(zmax, mf.X[3 * i + 2]);
  }
  EXPECT_NEAR(zmin, -0.0152651, 1e-6);
  EXPECT_NEAR(zmax, 0.0161878, 1e-6);
  nlohmann::json doc = nlohmann::json::parse(slurp(std::string(FDEM_TEST_DATA) + "/cases/bar.json"));
  doc["mesh"] = {{"file", std::string(FDEM_TEST_DATA) + "/two_regions_v41.msh"}, {"element_size", 0.01}};
  try {
    parse_case(doc, "x.json");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh.element_size"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(".geo"), std::string::npos) << e.what();
  }
}

}  // namespace
