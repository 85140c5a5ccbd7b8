// Hostile inputs: every file in tests/data/hostile/ (see its README.md) is given to the real CLI,
// `fdem check`, which must exit with status 2 (input error) and say on stderr which file is wrong:
// no crash, no hang, no other exit status. Case files (case_*.json) are checked directly; meshes
// (*.msh) through mesh_case_2d.json with --set mesh.file=<mesh>.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

namespace fs = std::filesystem;

const fs::path kHostile = fs::path(FDEM_TEST_DATA) / "hostile";

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct CliResult {
  int status = -1;  // exit status; 128 + signal if killed; -1 if it could not run
  std::string err;  // stderr
};

// Runs FDEM_BINARY with `args` (a 60 s limit; stdout discarded, stderr captured).
CliResult run_fdem(const std::vector<std::string>& args) {
  const fs::path err_file =
      fs::path(::testing::TempDir()) / ("fdem_hostile_" + std::to_string(::getpid()) + ".err");
  std::string cmd = "timeout -k 5 60 " + quote(FDEM_BINARY);
  for (const auto& a : args) cmd += " " + quote(a);
  cmd += " > /dev/null 2> " + quote(err_file.string()) + " < /dev/null";
  const int raw = std::system(cmd.c_str());
  CliResult r;
  if (raw != -1 && WIFEXITED(raw)) r.status = WEXITSTATUS(raw);
  else if (raw != -1 && WIFSIGNALED(raw)) r.status = 128 + WTERMSIG(raw);
  std::ifstream in(err_file);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  std::error_code ec;
  fs::remove(err_file, ec);
  return r;
}

// Exit status 2 with a message that names `name`.
void expect_input_error(const CliResult& r, const std::string& name) {
  EXPECT_EQ(r.status, 2) << "stderr:\n" << r.err.substr(0, 2000)
                         << (r.status == 124 ? "\n(timed out)" : "")
                         << (r.status > 128 ? "\n(killed by a signal)" : "");
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err.substr(0, 2000);
  EXPECT_NE(r.err.find(name), std::string::npos)
      << "the message does not name '" << name << "':\n" << r.err.substr(0, 2000);
  EXPECT_EQ(r.err.find("unexpected error"), std::string::npos) << r.err.substr(0, 2000);
}

std::vector<std::string> hostile_files(const std::string& prefix, const std::string& ext) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(kHostile, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().extension() == ext) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

// ------------------------------------------------------------------------------------------------

class HostileCase : public ::testing::TestWithParam<std::string> {};

TEST_P(HostileCase, CheckExitsWithInputError) {
  const std::string file = (kHostile / GetParam()).string();
  expect_input_error(run_fdem({"check", file}), GetParam());
}

INSTANTIATE_TEST_SUITE_P(Hostile, HostileCase, ::testing::ValuesIn(hostile_files("case_", ".json")),
                         test_name);

class HostileMesh : public ::testing::TestWithParam<std::string> {};

TEST_P(HostileMesh, CheckExitsWithInputError) {
  const std::string mesh = (kHostile / GetParam()).string();
  const std::string carrier = (kHostile / "mesh_case_2d.json").string();
  expect_input_error(run_fdem({"check", carrier, "--set", "mesh.file=" + mesh}), GetParam());
}

INSTANTIATE_TEST_SUITE_P(Hostile, HostileMesh, ::testing::ValuesIn(hostile_files("", ".msh")),
                         test_name);

TEST(HostileFiles, CorpusIsThere) {
  EXPECT_GE(hostile_files("case_", ".json").size(), 15u);
  EXPECT_GE(hostile_files("", ".msh").size(), 15u);
  // The carrier case itself is valid: the mesh tests fail for the mesh, not for the case.
  CliResult ok = run_fdem({"check", (kHostile / "mesh_case_2d.json").string()});
  EXPECT_EQ(ok.status, 0) << ok.err;
}

// A .msh file holding a .geo script: Gmsh would run it (System "touch ..."); fdem must refuse it.
TEST(HostileFiles, GeoScriptInMshIsNotRun) {
  const fs::path marker = "/tmp/fdem_hostile_geo_script_ran";
  std::error_code ec;
  fs::remove(marker, ec);
  const std::string carrier = (kHostile / "mesh_case_2d.json").string();
  CliResult r =
      run_fdem({"check", carrier, "--set", "mesh.file=" + (kHostile / "msh_geo_script.msh").string()});
  expect_input_error(r, "msh_geo_script.msh");
  EXPECT_FALSE(fs::exists(marker)) << "the script in msh_geo_script.msh was run";
  fs::remove(marker, ec);
}

// Nesting deep enough to overflow the stack of a recursive reader (made here: 400 kB / 200 kB).
TEST(HostileFiles, DeepNesting) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("fdem_hostile_deep_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const int depth = 200000;
  {
    std::ofstream f(dir / "deep_nesting.json");
    f << "{\"dimension\": 2, \"platens\": " << std::string(depth, '[') << std::string(depth, ']')
      << "}";
  }
  {
    std::ofstream f(dir / "deep_expression.json");
    f << "{\"parameters\": {\"a\": 1}, \"time\": {\"end_time\": \"=" << std::string(depth / 2, '(')
      << "a" << std::string(depth / 2, ')') << "\"}}";
  }
  {
    std::ofstream f(dir / "deep_unary.json");
    f << "{\"time\": {\"end_time\": \"=" << std::string(depth / 2, '-') << "1\"}}";
  }
  for (const char* name : {"deep_nesting.json", "deep_expression.json", "deep_unary.json"})
    expect_input_error(run_fdem({"check", (dir / name).string()}), name);
  // The same through --set (an override value is a JSON document too).
  const std::string bar = (fs::path(FDEM_TEST_DATA) / "cases" / "bar.json").string();
  const std::string deep_value = std::string(20000, '[') + std::string(20000, ']');
  expect_input_error(run_fdem({"check", bar, "--set", "boundary.gravity=" + deep_value}),
                     "bar.json");
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// Not a regular file: a device that never ends, a folder.
TEST(HostileFiles, CaseIsDeviceOrFolder) {
  expect_input_error(run_fdem({"check", "/dev/zero"}), "/dev/zero");
  expect_input_error(run_fdem({"check", kHostile.string()}), kHostile.string());
}

// Hostile --set values: non-finite numbers, 2^63, out-of-range indices.
TEST(HostileFiles, HostileOverrides) {
  const std::string bar = (fs::path(FDEM_TEST_DATA) / "cases" / "bar.json").string();
  for (const char* ov : {"time.end_time=1e400", "time.end_time=-1e400", "time.end_time=nan",
                         "time.max_steps=9223372036854775808", "platens.99999999999999999999=1",
                         "materials.concrete.E=\"=1/0\"", "dimension=[]", "=", "a..b=1"})
    expect_input_error(run_fdem({"check", bar, "--set", ov}), "bar.json");
  // A --set value that is not UTF-8 cannot be written into the resolved case.json (this made
  // 'fdem run' fail with an unexpected json type_error, exit 1).
  const fs::path out = fs::path(::testing::TempDir()) / ("fdem_hostile_out_" + std::to_string(::getpid()));
  expect_input_error(run_fdem({"run", bar, "--quiet", "--out", out.string(), "--set",
                               "description=\xff\xfe"}),
                     "bar.json");
  std::error_code ec;
  fs::remove_all(out, ec);
}

// `fdem run` with an output folder that cannot be created.
TEST(HostileFiles, RunUnwritableOut) {
  const std::string bar = (fs::path(FDEM_TEST_DATA) / "cases" / "bar.json").string();
  CliResult r = run_fdem({"run", bar, "--out", "/proc/fdem_x", "--quiet"});
  expect_input_error(r, "/proc/fdem_x");
  EXPECT_NE(r.err.find("output"), std::string::npos) << r.err;
}

}  // namespace
