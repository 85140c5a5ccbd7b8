// What cannot run is refused before the work starts, with exit status 2 and the numbers (issue 22,
// "Robustness II"): meshes too large for the memory (generators, .geo files), sizes Gmsh would not
// honour, Gmsh failures (in a child process: never an abort), a time step that is not positive or
// a run of more steps than kMaxRunSteps, a checkpoint interval shorter than a step or not a number.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Result {
  int rc;
  std::string out;
};

// Runs `fdem <args>` (through bash, with `prefix` before it), returns exit status and output.
Result fdem(const std::string& args, const std::string& prefix = "") {
  const fs::path log = fs::temp_directory_path() / ("fdem_refuse_" + std::to_string(::getpid()) + ".log");
  const std::string cmd =
      "bash -c '" + prefix + " " + FDEM_BINARY + " " + args + "' > " + log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream f(log);
  std::stringstream s;
  s << f.rdbuf();
  fs::remove(log);
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, s.str()};
}

bool has(const Result& r, const std::string& text) { return r.out.find(text) != std::string::npos; }

const std::string kSrc = FDEM_SOURCE_DIR;
const std::string kU = kSrc + "/cases/uniaxial_compression/case.json";
const std::string kSlope = kSrc + "/cases/slope_failure/case.json";

// A case with a Gmsh geometry file `geo` (written next to it) in a fresh folder.
std::string geo_case(const std::string& name, const std::string& geo) {
  const fs::path dir = fs::temp_directory_path() / ("fdem_refuse_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "m.geo") << geo;
  std::ofstream(dir / "case.json") << R"({"name": "t", "dimension": 2, "mesh": {"file": "m.geo"},
 "analysis": {"plane": "strain", "thickness": 1},
 "materials": {"rock": {"density": 2500, "E": 1e10, "nu": 0.25}}, "regions": {"body": "rock"},
 "time": {"end_time": 1e-3}})";
  return (dir / "case.json").string();
}

// Item 5: Gmsh 4.8 gave every curve one segment at h = 1e-9 (its segment count overflows an int):
// "case OK" with 6 elements. Now refused before meshing, naming the key, value and smallest size.
TEST(Refuse, GeoSizeThatCannotBeMeshedIsRefused) {
  const Result r = fdem("check " + kSlope + " --set parameters.h=1e-9");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "mesh.element_size = 1e-09")) << r.out;
  EXPECT_TRUE(has(r, "e+21 elements")) << r.out;  // area ~1885 m^2 / (1e-9 m)^2
  EXPECT_TRUE(has(r, "give mesh.element_size >= ")) << r.out;
  EXPECT_FALSE(has(r, "case OK")) << r.out;
  // without the memory check, the mesh Gmsh makes (6 elements) is refused as not honouring the size
  const Result m = fdem("check " + kSlope + " --set parameters.h=1e-9", "FDEM_MEMORY_CHECK=off");
  EXPECT_EQ(m.rc, 2) << m.out;
  EXPECT_TRUE(has(m, "Gmsh did not honour mesh.element_size = 1e-09 m: its mesh has 6 elements")) << m.out;
}

// Item 8: cell = 1e-5 allocated until std::bad_alloc (exit 1). Now: 4 x 5000 x 10000 = 2e8
// elements refused with the estimate and the memory available, before the generator runs.
TEST(Refuse, MeshTooLargeForMemoryIsRefusedBeforeMeshing) {
  Result r = fdem("check " + kU + " --set parameters.cell=1e-5");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "mesh.element_size = 1e-05 m (5000 x 10000 cells) would make about 2e+08 elements"))
      << r.out;
  EXPECT_TRUE(has(r, "available")) << r.out;
  // the limit of the process's address space counts (ulimit -v 3 GiB: 2e6 elements need ~5 GiB)
  r = fdem("check " + kU + " --set parameters.cell=1e-4", "ulimit -v 3145728;");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "2e+06 elements")) << r.out;
  EXPECT_TRUE(has(r, "RLIMIT_AS")) << r.out;
  // the budget applies to ordinary sizes too: 3200 elements do not fit in 1 MiB ...
  r = fdem("check " + kU, "FDEM_MEMORY_LIMIT_GB=0.001");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "3.2e+03 elements")) << r.out;
  // ... and the experts' switch turns the check off
  r = fdem("check " + kU, "FDEM_MEMORY_LIMIT_GB=0.001 FDEM_MEMORY_CHECK=off");
  EXPECT_EQ(r.rc, 0) << r.out;
}

// Item 8, .geo files: a size set in the file itself (1e-7 m on a 1 m square) ran Gmsh for hours;
// refused from a trial 1D mesh before meshing.
TEST(Refuse, GeoFileOwnSizesTooSmallAreRefused) {
  const std::string c = geo_case("tiny", R"(lc = 1e-7;
Point(1) = {0, 0, 0, lc}; Point(2) = {1, 0, 0, lc}; Point(3) = {1, 1, 0, lc}; Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Surface("body") = {1};
)");
  const Result r = fdem("check " + c);
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "the element sizes set in")) << r.out;
  EXPECT_TRUE(has(r, "area 1 m^2")) << r.out;
  fs::remove_all(fs::path(c).parent_path());
}

// Item 10: a zero-area surface made Gmsh throw inside its OpenMP region: SIGABRT (exit 134). Gmsh
// now runs in a child process; its death is reported with its messages, exit status 2.
TEST(Refuse, GmshAbortBecomesExit2WithGmshMessages) {
  const std::string c = geo_case("zero", R"(
Point(1) = {0, 0, 0, 0.1}; Point(2) = {1, 0, 0, 0.1}; Point(3) = {2, 0, 0, 0.1};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 1};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
Physical Surface("body") = {1};
)");
  const Result r = fdem("check " + c);
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "m.geo: Gmsh failed while trying to mesh the geometry")) << r.out;
  EXPECT_TRUE(has(r, "Error")) << r.out;  // Gmsh's own error line
  fs::remove_all(fs::path(c).parent_path());
}

// Item 11: density 1e-300 gave dt = 0 ("case OK", then the run hung).
TEST(Refuse, TimeStepNotPositiveIsRefused) {
  const Result r = fdem("check " + kU + " --set materials.rock.density=1e-300");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "dt = 0 s is not positive and finite")) << r.out;
}

// Item 12: dt = 1e-15 s to end_time = 1e9 s started 1e24 steps without a word.
TEST(Refuse, RunOfTooManyStepsIsRefused) {
  Result r = fdem("check " + kU + " --set time.dt=1e-15 --set time.end_time=1e9");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "= 1e+24 steps, above the limit of 1e+12 steps")) << r.out;
  // a max_steps below the limit bounds the run: accepted
  r = fdem("check " + kU + " --set time.dt=1e-15 --set time.end_time=1e9 --set time.max_steps=1000");
  EXPECT_EQ(r.rc, 0) << r.out;
}

// Item 11: --checkpoint-every 1e-300 looped before step 1, nan wrote nothing and said nothing;
// "abc" printed CLI11's 309-digit range of a double.
TEST(Refuse, CheckpointIntervalIsCheckedWithCleanMessages) {
  const std::string out =
      (fs::temp_directory_path() / ("fdem_refuse_ck_" + std::to_string(::getpid()))).string();
  Result r = fdem("run " + kU + " --quiet --out " + out + " --checkpoint-every 1e-300");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(
      has(r, "--checkpoint-every = 1e-300 s is not 0 (no checkpoints) or a finite time of at least one step"))
      << r.out;
  for (const char* bad : {"nan", "abc", "-1", "inf"}) {
    r = fdem("run " + kU + " --quiet --out " + out + " --checkpoint-every " + bad);
    EXPECT_EQ(r.rc, 2) << bad << ": " << r.out;
    EXPECT_TRUE(has(r, "is not a time in seconds")) << r.out;
    EXPECT_LT(r.out.size(), 300u) << r.out;  // no 309-digit range
  }
  fs::remove_all(out);
}

}  // namespace

// mesh.refine (src/mesh/refine.hpp): out of [0, 10] or not an integer refused naming the key;
// a refinement too large for the memory refused before Gmsh meshes, with the refined estimate.
TEST(Refuse, RefineOutOfRangeOrTooLargeIsRefusedBeforeMeshing) {
  const std::string disc = kSrc + "/cases/brazilian_disc/case.json";
  Result r = fdem("check " + disc + " --set mesh.refine=-1");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "mesh.refine: value -1 is out of range (allowed: integer 0 to 10)")) << r.out;
  r = fdem("check " + disc + " --set mesh.refine=1.5");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "mesh.refine: expected an integer")) << r.out;
  // 2342 triangles at 3 mm (Gmsh's estimate 2.36e3) x 4^8 = 1.5e8: no Gmsh run, the estimate named
  r = fdem("check " + disc + " --set mesh.refine=8");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "(disc of radius 0.05 m, refined 8 times) would make about 1.5")) << r.out;
  EXPECT_FALSE(has(r, "Gmsh")) << r.out;
  // a block generator: its 3200 triangles x 4^2 do not fit in 10 MiB
  r = fdem("check " + kU + " --set mesh.refine=2", "FDEM_MEMORY_LIMIT_GB=0.01");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(has(r, "5.12e+04 elements")) << r.out;
  r = fdem("check " + kU + " --set mesh.refine=1");
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_TRUE(has(r, "\"elements\": 12800")) << r.out;
}
