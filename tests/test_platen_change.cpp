// A platen's one change of velocity (platens[i].change, docs/case-format.md): fast approach, slow
// loading. The plane moves at `velocity` until `change.time` and at `change.velocity` after it;
// the gap, the shear increment and the platen's work follow the path (kernels/model.hpp,
// PlatenDev::shift and mean_velocity). Checked on the uniaxial compression case at d = 10 mm and
// ten times its rate, up to 0.3 ms (before any interface fails at this rate): the displacement
// history, the energy balance, the load after the change, and that a change to the same velocity
// gives the run without one.
#include <gtest/gtest.h>

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
  nlohmann::json summary;
  std::map<std::string, std::vector<double>> h;
};

PlatenRun compression(const std::string& name, const std::string& change) {
  const std::string out = fdem::test::scratch_dir("platen_change", name);
  const std::string cmd = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " + std::string(FDEM_BINARY) + " run " +
                          FDEM_SOURCE_DIR + "/cases/uniaxial_compression/case.json --quiet --out " + out +
                          " --set parameters.cell=0.01 --set parameters.rate=0.5 --set time.end_time=3e-4"
                          " --set output.snapshot_count=0 --set output.history_rows=60" +
                          (change.empty() ? "" : " --set 'platens.0.change=" + change + "'") + " > " + out +
                          ".log 2>&1";
  PlatenRun r;
  EXPECT_EQ(fdem::test::system_status(cmd), 0) << slurp(out + ".log");
  r.summary = nlohmann::json::parse(slurp(out + "/summary.json"), nullptr, false);
  r.h = read_history(out + "/history.csv");
  fs::remove_all(out);
  fs::remove(out + ".log");
  return r;
}

TEST(PlatenChange, FastApproachThenSlowLoading) {
  const double v = 0.5, v2 = 0.125, tc = 1e-4;
  const PlatenRun a = compression("slow", R"({"time": 1e-4, "velocity": [0, -0.125]})");
  const PlatenRun b = compression("steady", "");
  const PlatenRun same = compression("same", R"({"time": 1e-4, "velocity": [0, -0.5]})");
  ASSERT_TRUE(a.summary.is_object() && b.summary.is_object() && same.summary.is_object());
  const auto& t = a.h.at("time [s]");
  ASSERT_GT(t.size(), 30u);
  ASSERT_EQ(t.size(), b.h.at("time [s]").size());
  EXPECT_EQ(a.summary["interfaces_failed"].get<long>(), 0);

  // the plane's path (history.csv has ten digits): the top platen slows at tc, the bottom one does not
  for (size_t r = 0; r < t.size(); ++r) {
    const double top = t[r] <= tc ? v * t[r] : v * tc + v2 * (t[r] - tc);
    EXPECT_NEAR(a.h.at("top_displacement [m]")[r], top, 1e-9 * v * t.back()) << "t = " << t[r];
    EXPECT_NEAR(a.h.at("bottom_displacement [m]")[r], v * t[r], 1e-9 * v * t.back()) << "t = " << t[r];
  }

  // the work of the platens follows the path: the balance holds as tightly as without the change
  const double ea = a.summary["energy"]["max_relative_balance_error"].get<double>();
  const double eb = b.summary["energy"]["max_relative_balance_error"].get<double>();
  EXPECT_LT(ea, 1e-3);
  EXPECT_LT(ea, 2 * eb + 1e-6) << "with the change " << ea << ", without " << eb;

  // before the change the runs are the same; at the end the closure is (v + v) t against
  // v t + v tc + v2 (t - tc), 0.75 of it, and the specimen carries about that share of the load
  const auto& la = a.h.at("top_load [N]");
  const auto& lb = b.h.at("top_load [N]");
  for (size_t r = 0; r < t.size() && t[r] <= tc; ++r) EXPECT_EQ(la[r], lb[r]) << "t = " << t[r];
  const double closure = (v * t.back() + v * tc + v2 * (t.back() - tc)) / (2 * v * t.back());
  EXPECT_NEAR(la.back() / lb.back(), closure, 0.08) << la.back() << " N against " << lb.back() << " N";

  // a change to the same velocity is no change (to round-off in the step that spans tc)
  const auto& ls = same.h.at("top_load [N]");
  double peak = 0;
  for (double x : lb) peak = std::max(peak, std::fabs(x));
  for (size_t r = 0; r < t.size(); ++r) EXPECT_NEAR(ls[r], lb[r], 1e-9 * peak) << "t = " << t[r];
}

// Bad input names the key and the allowed range (exit status 2).
TEST(PlatenChange, BadChangeIsRefused) {
  const std::string out = fdem::test::scratch_dir("platen_change", "bad");
  fs::create_directories(out);
  const std::string base = std::string(FDEM_BINARY) + " check " + FDEM_SOURCE_DIR +
                           "/cases/uniaxial_compression/case.json --set 'platens.0.change=";
  EXPECT_EQ(
      fdem::test::system_status(base + R"({"time": -1, "velocity": [0, 1]})" + "' > " + out + "/a.log 2>&1"),
      2);
  EXPECT_NE(slurp(out + "/a.log").find("platens.0.change.time: value -1 is out of range (allowed: >= 0)"),
            std::string::npos)
      << slurp(out + "/a.log");
  EXPECT_EQ(fdem::test::system_status(base + R"({"time": 1e-3})" + "' > " + out + "/b.log 2>&1"), 2);
  EXPECT_NE(slurp(out + "/b.log").find("platens.0.change.velocity: required key is missing"),
            std::string::npos)
      << slurp(out + "/b.log");
  fs::remove_all(out);
}

}  // namespace
