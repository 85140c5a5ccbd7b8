// The set-up of a run: summary.json's "setup" and "memory" (common/setup_times.hpp) from a real
// `fdem run` of a small Gmsh sphere, and boundary_faces (linear in the mesh since the set-up
// work) against the sort of every face that it replaced.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "mesh/mesh.hpp"

namespace {

namespace fs = std::filesystem;

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(Setup, RunReportsPhasesAndPeakMemory) {
  const std::string out = (fs::temp_directory_path() / ("fdem_setup_" + std::to_string(::getpid()))).string();
  fs::remove_all(out);
  const std::string cmd =
      std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR + "/cases/particle_impact_3d/case.json --out " +
      out + " --set parameters.h=0.008 --set time.max_steps=2 --set output.snapshot_count=0 > " + out +
      ".log 2>&1";
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0) << slurp(out + ".log");
  const std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("fdem: set-up "), std::string::npos) << log;
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const auto& st = s.at("setup");
  std::map<std::string, double> wall;
  double sum = 0;
  for (const auto& p : st.at("phases")) {
    wall[p.at("name").get<std::string>()] = p.at("wall_seconds").get<double>();
    sum += p.at("wall_seconds").get<double>();
    EXPECT_GE(p.at("wall_seconds").get<double>(), 0.0);
    EXPECT_GE(p.at("cpu_seconds").get<double>(), 0.0);
    EXPECT_GT(p.at("rss_bytes").get<double>(), 0.0);
  }
  for (const char* name : {"gmsh_meshing", "gmsh_extraction", "renumbering", "interface_insertion",
                           "model_elements", "model_interfaces", "contact_setup", "output_setup"})
    EXPECT_EQ(wall.count(name), 1u) << name;
  EXPECT_GT(wall["gmsh_meshing"], 0.0);
  // the phases (with "other") add up to the total, from run_case to the first step
  EXPECT_NEAR(sum, st.at("wall_seconds").get<double>(), 1e-6);
  EXPECT_LT(st.at("wall_seconds").get<double>(), 600.0);
  const double peak = s.at("memory").at("peak_rss_bytes").get<double>();
  EXPECT_GT(st.at("peak_rss_bytes").get<double>(), 1e6);
  EXPECT_GE(peak, st.at("peak_rss_bytes").get<double>());
  EXPECT_GT(st.at("gmsh_peak_rss_bytes").get<double>(), 1e6);  // the Gmsh child's own peak
  EXPECT_NEAR(s.at("memory").at("peak_rss_bytes_per_element").get<double>(),
              peak / s.at("counts").at("elements").get<double>(), 1e-6 * peak);
  // the Views' memory (common/view_memory.hpp): within the resident peak (Kokkos fills every View
  // it allocates), the model's kind at least the nodes' positions, velocities and forces (X, x,
  // v, f: 4 x 3 doubles per node), contact arrays for the sphere's surface
  const auto& vm = s.at("memory").at("views");
  const double vpeak = vm.at("peak_bytes").get<double>();
  EXPECT_GT(vpeak, 0.0);
  EXPECT_LE(vpeak, peak);
  EXPECT_GE(vm.at("peak_by_kind").at("model").get<double>(), 4 * 3 * 8 * s.at("counts").at("nodes").get<double>());
  EXPECT_GT(vm.at("peak_by_kind").at("contact").get<double>(), 0.0);
  double kinds = 0;
  for (const auto& [k, b] : vm.at("peak_by_kind").items()) kinds += b.get<double>();
  EXPECT_EQ(kinds, vpeak);  // the kinds partition the peak
  EXPECT_LE(vm.at("device_bytes_per_element").get<double>(), vm.at("peak_bytes_per_element").get<double>());
  fs::remove_all(out);
  fs::remove(out + ".log");
}

TEST(Setup, PhasesNestAndAddUp) {
  namespace st = fdem::setup_times;
  st::reset();
  {
    st::Phase outer("outer");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    st::Phase inner("inner");  // inside outer: counted once, in inner
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  }
  st::finish();
  const auto r = st::report();
  double sum = 0;
  for (const auto& p : r.at("phases")) sum += p.at("wall_seconds").get<double>();
  ASSERT_GE(r.at("phases").size(), 2u);
  EXPECT_EQ(r.at("phases")[0].at("name"), "inner");
  EXPECT_EQ(r.at("phases")[1].at("name"), "outer");
  const double inner = r.at("phases")[0].at("wall_seconds").get<double>();
  const double outer = r.at("phases")[1].at("wall_seconds").get<double>();
  EXPECT_GE(inner, 0.03);
  EXPECT_GE(outer, 0.02);
  EXPECT_LT(outer, 0.02 + 0.5 * inner);  // without inner's time
  EXPECT_NEAR(sum, r.at("wall_seconds").get<double>(), 1e-9);
  EXPECT_NE(st::line().find("inner "), std::string::npos) << st::line();
}

// Phases opened in a Folded scope record nothing of their own: the phase around it counts their time.
TEST(Setup, PhasesInAFoldedScopeCountInTheOneAroundIt) {
  namespace st = fdem::setup_times;
  st::reset();
  {
    st::Phase outer("outer");
    st::Folded folded;
    st::Phase inner("inner");
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  }
  st::Phase after("after");  // (outside the scope again: its own)
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  after.stop();
  st::finish();
  const auto r = st::report();
  std::map<std::string, double> wall;
  for (const auto& p : r.at("phases")) wall[p.at("name").get<std::string>()] = p.at("wall_seconds").get<double>();
  EXPECT_EQ(wall.count("inner"), 0u);
  ASSERT_EQ(wall.count("outer"), 1u);
  EXPECT_GE(wall["outer"], 0.03);
  ASSERT_EQ(wall.count("after"), 1u);
  EXPECT_GE(wall["after"], 0.01);
}

// The boundary faces as before: every face sorted by its node set, those that occur once and
// are no side of an interface, in order of (element, local face).
std::vector<int> boundary_faces_by_sorting(const fdem::HostMesh& m) {
  const int dim = m.dim, npe = dim + 1;
  const int f3[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  const int f2[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  auto key = [&](const int* n) {
    std::array<int, 3> k{n[0], n[1], dim == 3 ? n[2] : -1};
    for (int i = 0; i < dim; ++i)  // insertion sort of the first dim entries
      for (int j = i; j > 0 && k[j] < k[j - 1]; --j) std::swap(k[j], k[j - 1]);
    return k;
  };
  std::map<std::array<int, 3>, int> count;
  std::set<std::array<int, 3>> sides;
  for (int i = 0; i < 2 * m.num_ifaces(); ++i)
    sides.insert(key(&m.ifaces[static_cast<std::size_t>(dim) * i]));
  std::vector<std::array<int, 3>> faces;
  for (int e = 0; e < m.num_elems(); ++e)
    for (int f = 0; f < npe; ++f) {
      std::array<int, 3> n{-1, -1, -1};
      for (int k = 0; k < dim; ++k)
        n[k] = m.elems[static_cast<std::size_t>(e) * npe + (dim == 3 ? f3[f][k] : f2[f][k])];
      faces.push_back(n);
      ++count[key(n.data())];
    }
  std::vector<int> out;
  for (const auto& n : faces)
    if (count[key(n.data())] == 1 && !sides.count(key(n.data())))
      out.insert(out.end(), n.begin(), n.begin() + dim);
  return out;
}

TEST(Setup, BoundaryFacesMatchTheSortOfEveryFace) {
  // a box of two regions, interfaces in one only (shared nodes and node copies side by side), and
  // a crossed rectangle with interfaces everywhere
  fdem::HostMesh box = fdem::generate_box({0, 0, 0}, {1, 1, 1}, 4, 3, 2);
  box.region_names = {"a", "b"};
  for (int e = 0; e < box.num_elems(); ++e) box.elem_region[e] = e % 5 == 0 ? 1 : 0;
  fdem::HostMesh rect = fdem::generate_crossed_rectangle(0, 0, 2, 1, 5, 3);
  for (fdem::HostMesh* m : {&box, &rect}) {
    EXPECT_EQ(fdem::boundary_faces(*m), boundary_faces_by_sorting(*m));
    std::vector<bool> frac(m->region_names.size(), true);
    if (m == &box) frac[0] = false;
    fdem::insert_interfaces(*m, frac);
    ASSERT_GT(m->num_ifaces(), 0);
    const auto bf = fdem::boundary_faces(*m);
    EXPECT_EQ(bf, boundary_faces_by_sorting(*m));
    EXPECT_FALSE(bf.empty());
  }
}

// mesh.mesher "hxt" (Gmsh's HXT, about 8 times faster at 1e6 tetrahedra): another valid mesh of
// the same sphere; an unknown mesher is refused with exit status 2.
TEST(Setup, SphereMesherHxt) {
  const double R = 1.0, h = 0.25;
  const fdem::HostMesh del = fdem::generate_sphere({0, 0, 0}, R, h);
  const fdem::HostMesh hxt = fdem::generate_sphere({0, 0, 0}, R, h, "body", "hxt");
  ASSERT_GT(hxt.num_elems(), 0);
  EXPECT_NO_THROW(fdem::check_elements(hxt, "hxt sphere"));
  const double ratio = static_cast<double>(hxt.num_elems()) / del.num_elems();
  EXPECT_GT(ratio, 0.7);
  EXPECT_LT(ratio, 1.4);
  double vol = 0;
  for (int e = 0; e < hxt.num_elems(); ++e) {
    const int* n = &hxt.elems[static_cast<std::size_t>(4) * e];
    double a[3][3];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) a[k][i] = hxt.X[3 * n[k + 1] + i] - hxt.X[3 * n[0] + i];
    vol += (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
            a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
            a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) /
           6;
  }
  EXPECT_NEAR(vol, 4.0 / 3.0 * M_PI, 0.05 * 4.0 / 3.0 * M_PI);  // flat faces on a sphere: a bit less
  EXPECT_FALSE(hxt.node_sets.at("surface").empty());
  EXPECT_THROW(fdem::generate_sphere({0, 0, 0}, R, h, "body", "tetgen"), fdem::InputError);

  const std::string out =
      (fs::temp_directory_path() / ("fdem_mesher_" + std::to_string(::getpid()))).string();
  const std::string cmd =
      std::string(FDEM_BINARY) + " check " + FDEM_SOURCE_DIR +
      "/cases/particle_impact_3d/case.json --set parameters.h=0.008 --set mesh.mesher=tetgen > " + out +
      ".log 2>&1";
  const int rc = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
  EXPECT_NE(slurp(out + ".log").find("mesh.mesher"), std::string::npos) << slurp(out + ".log");
  fs::remove(out + ".log");
}

}  // namespace

// mesh.refine: the refinement is a phase of its own, after Gmsh's coarse mesh; the run's counts
// are the coarse mesh's times 8 (interfaces: every face of the fine mesh inside the sphere).
TEST(Setup, RefinementIsAPhaseAndMultipliesTheElements) {
  const std::string out = (fs::temp_directory_path() / ("fdem_setup_refine_" + std::to_string(::getpid()))).string();
  auto run = [&](const std::string& sets) {
    fs::remove_all(out);
    const std::string cmd = std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
                            "/cases/particle_impact_3d/case.json --out " + out +
                            " --set parameters.h=0.008 --set time.max_steps=2 --set output.snapshot_count=0 " +
                            sets + " > " + out + ".log 2>&1";
    const int rc = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0) << slurp(out + ".log");
    return nlohmann::json::parse(slurp(out + "/summary.json"));
  };
  const auto coarse = run("");
  const auto fine = run("--set mesh.refine=1");
  const double ne = coarse.at("counts").at("elements").get<double>();
  EXPECT_EQ(fine.at("counts").at("elements").get<double>(), 8 * ne);
  // interior faces: (4 x 8 ne - boundary faces) / 2, the boundary's faces 4 times the coarse's
  const double bf = 4 * ne - 2 * coarse.at("counts").at("interfaces").get<double>();
  EXPECT_EQ(fine.at("counts").at("interfaces").get<double>(), (32 * ne - 4 * bf) / 2);
  int phases = 0;
  for (const auto& p : fine.at("setup").at("phases")) phases += p.at("name") == "refinement";
  EXPECT_EQ(phases, 1);
  for (const auto& p : coarse.at("setup").at("phases")) EXPECT_NE(p.at("name"), "refinement");
  fs::remove_all(out);
  fs::remove(out + ".log");
}
