// A platen with a mass (platens[i].mass, docs/case-format.md): a guided drop weight whose motion
// along its normal follows from the force of the body on it and gravity (kernels/platens.hpp,
// advance_platens). Checked on the shipped cases with the mass set: momentum of body and platen
// conserved to round-off in a free collision (3D impact: the sphere on a plate of its own size that
// may move), the platen's kinetic energy against the work the ledger books, a free fall against
// the closed form, a heavy platen against the same motion prescribed (2D compression), and bad
// input refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;
using fdem::test::read_history;
using fdem::test::slurp;

struct PlatenRun {
  int rc = -1;
  std::string log;
  nlohmann::json summary;
  std::map<std::string, std::vector<double>> h;
};

// `fdem run CASE` on one thread with the overrides `sets` (each "--set ..." text), no snapshots.
PlatenRun run_case(const std::string& name, const std::string& rel_case, const std::string& sets) {
  const std::string out = fdem::test::scratch_dir("driven_platen", name);
  const std::string cmd = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " + std::string(FDEM_BINARY) + " run " +
                          FDEM_SOURCE_DIR + "/" + rel_case + " --quiet --out " + out +
                          " --set output.snapshot_count=0 " + sets + " > " + out + ".log 2>&1";
  PlatenRun r;
  r.rc = fdem::test::system_status(cmd);
  r.log = slurp(out + ".log");
  if (r.rc == 0) {
    r.summary = nlohmann::json::parse(slurp(out + "/summary.json"), nullptr, false);
    r.h = read_history(out + "/history.csv");
  }
  fs::remove_all(out);
  fs::remove(out + ".log");
  return r;
}

// The 3D impact's sphere (20 m/s down) on its plate made free with a mass of 0.1 kg (the sphere:
// 0.177 kg at h = 8 mm's mesh, less): nothing else acts on either, so the momentum of the two along
// z stays the sphere's initial one, and the plate's kinetic energy is the work it took from the
// body (the ledger's W_external, negative).
TEST(DrivenPlaten, FreeCollisionConservesMomentumAndBooksThePlatensEnergy) {
  const double M = 0.1, v0 = 20;
  const PlatenRun r = run_case("free", "cases/particle_impact_3d/case.json",
                         "--set parameters.h=0.008 --set parameters.duration=1.5e-4 --set output.history_rows=60"
                         " --set platens.0.mass=0.1");
  ASSERT_EQ(r.rc, 0) << r.log;
  const auto& t = r.h.at("time [s]");
  const auto& pz = r.h.at("momentum_z [N s]");
  const auto& V = r.h.at("plate_speed [m/s]");  // along the plate's normal, +z
  const auto& W = r.h.at("W_external [J]");
  ASSERT_GT(t.size(), 40u);
  const double p0 = pz.front() + M * V.front();
  ASSERT_LT(p0, 0);
  EXPECT_EQ(V.front(), 0.0);
  const double ms = -pz.front() / v0;  // the sphere's mass
  double vmax = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    // (history.csv has ten digits)
    EXPECT_NEAR(pz[i] + M * V[i], p0, 1e-8 * std::fabs(p0)) << "t = " << t[i];
    // the plate's kinetic energy (at the forces' time, the mean of its half-step speeds) is what
    // the body lost to it, to the leap-frog's (dV / 2)^2 and the output's digits
    EXPECT_NEAR(0.5 * M * V[i] * V[i], -W[i], 1e-6 * 0.5 * ms * v0 * v0) << "t = " << t[i];
    vmax = std::max(vmax, -V[i]);
  }
  // the plate was struck and moves down: faster than the two moving together would
  // (ms v0 / (ms + M), the sphere's pieces near it end slower) and slower than an elastic
  // collision of rigid bodies could make it (2 ms v0 / (ms + M))
  EXPECT_GT(-V.back(), ms * v0 / (ms + M));
  EXPECT_LT(vmax, 2 * ms * v0 / (ms + M));
  EXPECT_LT(r.summary["energy"]["max_relative_balance_error"].get<double>(), 0.03);
}

// The double impact's drop weight far above the sphere, under gravity: it falls as
// travel = v0 t + g t^2 / 2 (the leap-frog from v(-dt/2) = v0 adds g t dt / 2) and its speed is
// v0 + g t (to g dt / 2 at the forces' time) until it touches.
TEST(DrivenPlaten, FreeFallFollowsTheClosedForm) {
  const double v0 = 1, g = 9.81, T = 2e-3;
  const PlatenRun r = run_case("fall", "cases/sphere_double_impact/case.json",
                         "--set parameters.h=0.01 --set parameters.speed=1 --set parameters.gap=0.01"
                         " --set time.end_time=2e-3 --set output.history_rows=20 --set output.fragments=false"
                         " --set 'boundary.gravity=[0, 0, -9.81]'");
  ASSERT_EQ(r.rc, 0) << r.log;
  const auto& t = r.h.at("time [s]");
  const auto& s = r.h.at("weight_displacement [m]");
  const auto& V = r.h.at("weight_speed [m/s]");
  const auto& F = r.h.at("weight_load [N]");
  ASSERT_GT(t.size(), 15u);
  const double dt = r.summary["time_step"]["dt_s"].get<double>();
  ASSERT_GT(dt, 0);
  EXPECT_NEAR(t.back(), T, 2 * dt);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(F[i], 0.0) << "t = " << t[i];
    EXPECT_NEAR(s[i], v0 * t[i] + 0.5 * g * t[i] * t[i], g * t[i] * dt + 1e-12) << "t = " << t[i];
    EXPECT_NEAR(V[i], v0 + g * t[i], g * dt + 1e-9) << "t = " << t[i];
  }
}

// A platen whose speed the body cannot change in double precision (1e30 kg: F dt / M far below an
// ulp of its speed) is its prescribed motion: the 2D compression's top platen with that mass and
// the same initial velocity gives the run in which it is prescribed (before any interface fails),
// and its work is booked as the prescribed platen's. (Not a lighter one: this case amplifies a
// relative change of 2e-14 in a platen's prescribed speed to 0.2 % of the load within 300 us,
// and 1e15 kg changes the speed by about that much.)
TEST(DrivenPlaten, HeavyPlatenIsThePrescribedOne) {
  const std::string base =
      "--set parameters.cell=0.01 --set parameters.rate=0.5 --set time.end_time=3e-4 --set output.history_rows=60";
  const PlatenRun a = run_case("heavy", "cases/uniaxial_compression/case.json", base + " --set platens.0.mass=1e30");
  const PlatenRun b = run_case("prescribed", "cases/uniaxial_compression/case.json", base);
  ASSERT_EQ(a.rc, 0) << a.log;
  ASSERT_EQ(b.rc, 0) << b.log;
  const auto& t = a.h.at("time [s]");
  ASSERT_EQ(t.size(), b.h.at("time [s]").size());
  double peak = 0, wmax = 0;
  for (double x : b.h.at("top_load [N]")) peak = std::max(peak, std::fabs(x));
  for (double x : b.h.at("W_external [J]")) wmax = std::max(wmax, std::fabs(x));
  ASSERT_GT(peak, 0);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(a.h.at("top_load [N]")[i], b.h.at("top_load [N]")[i], 1e-7 * peak) << "t = " << t[i];
    EXPECT_NEAR(a.h.at("top_displacement [m]")[i], b.h.at("top_displacement [m]")[i], 1e-12) << "t = " << t[i];
    EXPECT_NEAR(a.h.at("W_external [J]")[i], b.h.at("W_external [J]")[i], 1e-7 * wmax) << "t = " << t[i];
    EXPECT_NEAR(a.h.at("top_speed [m/s]")[i], 0.5, 1e-9) << "t = " << t[i];
  }
  EXPECT_EQ(b.h.count("top_speed [m/s]"), 0u);  // (a column only for a platen with a mass)
}

// A run killed after a checkpoint and restarted from it goes on with the drop weight where it was,
// at the speed it had (Model::platen_motion in the checkpoint): history.csv as the uninterrupted
// run's, byte for byte (one thread).
TEST(DrivenPlaten, RestartContinuesItsMotion) {
  const std::string sets = "--set parameters.h=0.01 --set parameters.duration=1.2e-4 --set output.history_rows=60";
  const std::string ref = fdem::test::scratch_dir("driven_platen", "ref");
  const std::string out = fdem::test::scratch_dir("driven_platen", "killed");
  auto cmd = [&sets](const std::string& dir, const std::string& extra, const std::string& env) {
    return "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " + env + " " + FDEM_BINARY + " run " + FDEM_SOURCE_DIR +
           "/cases/sphere_double_impact/case.json --quiet --out " + dir + " " + sets + " " + extra + " > " + dir +
           ".log 2>&1";
  };
  ASSERT_EQ(fdem::test::system_status(cmd(ref, "", "")), 0) << slurp(ref + ".log");
  EXPECT_EQ(fdem::test::system_status(cmd(out, "--checkpoint-every 4e-5", "FDEM_TEST_CHECKPOINT_KILL=during:2")),
            128 + 9)
      << slurp(out + ".log");
  ASSERT_TRUE(fs::exists(out + "/checkpoint.h5"));
  ASSERT_EQ(fdem::test::system_status(cmd(out, "--checkpoint-every 4e-5 --restart " + out + "/checkpoint.h5", "")), 0)
      << slurp(out + ".log");
  const std::string a = slurp(ref + "/history.csv"), b = slurp(out + "/history.csv");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_NE(a.find("weight_speed [m/s]"), std::string::npos);
  EXPECT_EQ(a, b);
  for (const auto& d : {ref, out}) {
    fs::remove_all(d);
    fs::remove(d + ".log");
  }
}

// Bad input names the key and the allowed range (exit status 2).
TEST(DrivenPlaten, BadMassIsRefused) {
  const std::string out = fdem::test::scratch_dir("driven_platen", "bad");
  fs::create_directories(out);
  const std::string base = std::string(FDEM_BINARY) + " check " + FDEM_SOURCE_DIR +
                           "/cases/uniaxial_compression/case.json --set platens.0.mass=";
  EXPECT_EQ(fdem::test::system_status(base + "-1 > " + out + "/a.log 2>&1"), 2);
  EXPECT_NE(slurp(out + "/a.log").find("platens.0.mass: value -1 is out of range (allowed: >= 0)"), std::string::npos)
      << slurp(out + "/a.log");
  EXPECT_EQ(fdem::test::system_status(base + "2 --set 'platens.0.change={\"time\": 1e-4, \"velocity\": [0, 0]}' > " +
                                      out + "/b.log 2>&1"),
            2);
  EXPECT_NE(slurp(out + "/b.log").find("platens.0.change: a platen with a mass"), std::string::npos)
      << slurp(out + "/b.log");
  fs::remove_all(out);
}

}  // namespace
