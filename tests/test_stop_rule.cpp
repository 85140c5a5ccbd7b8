// The stop rule and the energy-balance warning (solver/history_table.hpp): the load drop is judged
// on the platens' loads sampled on a cadence of their own and averaged over the load window, so
// that neither the density of history.csv nor the ringing of the platens' first contact decides
// when a run stops; the balance warning is printed once and recorded in summary.json.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "mesh/mesh.hpp"
#include "solver/history_table.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

using fdem::test::slurp;

// The uniaxial compression case at d = 10 mm and ten times the rate (10 000 steps, about a second
// on one thread), with `rows` history rows.
nlohmann::json ucs_reduced(long rows) {
  const std::string out = (fs::temp_directory_path() /
                           ("fdem_stop_rows" + std::to_string(rows) + "_" + std::to_string(::getpid())))
                              .string();
  fs::remove_all(out);
  const std::string cmd =
      "OMP_NUM_THREADS=1 " + std::string(FDEM_BINARY) + " run " + FDEM_SOURCE_DIR +
      "/cases/uniaxial_compression/case.json --quiet --out " + out +
      " --set parameters.cell=0.01 --set parameters.rate=0.5 --set output.snapshot_count=0"
      " --set output.history_rows=" +
      std::to_string(rows) + " > " + out + ".log 2>&1";
  EXPECT_EQ(run(cmd), 0) << slurp(out + ".log");
  nlohmann::json s = nlohmann::json::parse(slurp(out + "/summary.json"), nullptr, false);
  fs::remove_all(out);
  fs::remove(out + ".log");
  return s;
}

// Issue 22, item 6: with 20 000 rows the old rule, which compared the load at each history row
// with the peak of the rows, took the first-contact ringing (1.4e6 N, then a sample below 40 % of
// it) for failure and stopped at step 16; with 50 or 400 rows it stopped after the real peak
// (2.63e7 N). Now 50, 400 and 20 000 rows give the same stop (the same step, the time of the
// rule identical) and the same peak, after the real failure.
TEST(StopRule, IndependentOfHistoryRows) {
  const nlohmann::json a = ucs_reduced(50), b = ucs_reduced(400), c = ucs_reduced(20000);
  for (const auto* s : {&a, &b, &c}) {
    ASSERT_TRUE(s->is_object());
    EXPECT_EQ((*s)["stop_reason"], "load_drop");
    // after the real failure: the peak is the specimen's strength (about 2.6e7 N = 526 MPa over
    // 50 mm at this cell size and rate), not the first contact
    EXPECT_GT((*s)["results"]["peak_load_N"].get<double>(), 2.0e7);
    EXPECT_GT((*s)["end_time_s"].get<double>(), 5e-4);
    EXPECT_LT((*s)["energy"]["max_relative_balance_error"].get<double>(), 0.01);
    EXPECT_FALSE((*s)["energy"].contains("warning"));
  }
  const double t_a = a["results"]["stop_rule"]["met_at_s"].get<double>();
  const double p_a = a["results"]["peak_load_N"].get<double>();
  const double dt = a["time_step"]["dt_s"].get<double>();
  for (const auto* s : {&b, &c}) {
    // the rule is met at the same step; the run ends there or one step later (a final row)
    EXPECT_EQ((*s)["results"]["stop_rule"]["met_at_s"].get<double>(), t_a);
    EXPECT_NEAR((*s)["end_time_s"].get<double>(), a["end_time_s"].get<double>(), 1.01 * dt);
    EXPECT_NEAR((*s)["results"]["peak_load_N"].get<double>() / p_a, 1.0, 1e-9);
    EXPECT_NEAR((*s)["results"]["stop_rule"]["window_averaged_peak_load_N"].get<double>() /
                    a["results"]["stop_rule"]["window_averaged_peak_load_N"].get<double>(),
                1.0, 1e-9);
  }
  // the load window: the P-wave transit over the 100 mm height, c = sqrt(M / rho) with the plane
  // strain modulus M = E (1 - nu) / ((1 + nu) (1 - 2 nu)) = 80 GPa: 18.4 us, 32 samples in it
  const double window = 0.1 / std::sqrt(80e9 / 2700);
  EXPECT_NEAR(a["results"]["stop_rule"]["window_s"].get<double>() / window, 1.0, 1e-9);
  EXPECT_NEAR(a["results"]["stop_rule"]["sample_interval_s"].get<double>() * 32 / window, 1.0, 1e-9);
}

// The balance warning: from step 10 on, the first sampled step whose |error| exceeds 5 % of the
// energy scale is recorded and warned about once; the largest error is kept.
TEST(StopRule, BalanceWarningOnceAboveFivePercent) {
  fdem::Case c = fdem_test::basic_case(2);
  const fdem::HostMesh mesh = fdem::generate_crossed_rectangle(0, 0, 1, 1, 2, 2);
  fdem::Simulation<2> sim(c, mesh);
  fdem::HistoryTable<2> h(c, mesh, sim);
  auto energies = [](long step, double error) {
    fdem::Energies e;
    e.step = step;
    e.time = 1e-6 * static_cast<double>(step);
    e.scale = 100;
    e.balance_error = error;
    return e;
  };
  ::testing::internal::CaptureStderr();
  h.check_balance(energies(3, 40));  // start-up: not judged
  h.check_balance(energies(20, 4));  // 4 %: below the warning
  std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(err, "");
  EXPECT_LT(h.balance_warned_at(), 0);
  EXPECT_DOUBLE_EQ(h.max_relative_balance_error(), 0.04);

  ::testing::internal::CaptureStderr();
  h.check_balance(energies(30, -6));  // 6 % (energy lost counts as well)
  h.check_balance(energies(40, 31));  // 31 %: no second warning
  err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("warning: energy balance error 6 %"), std::string::npos) << err;
  EXPECT_EQ(err.find("fdem: warning:", err.find("fdem: warning:") + 1), std::string::npos) << err;
  EXPECT_EQ(h.balance_warned_step(), 30);
  EXPECT_DOUBLE_EQ(h.balance_warned_at(), 30e-6);
  EXPECT_DOUBLE_EQ(h.balance_warned_error(), 0.06);
  EXPECT_DOUBLE_EQ(h.max_relative_balance_error(), 0.31);

  // through a checkpoint: the warning stays given
  fdem::RunState s;
  h.save(s);
  fdem::HistoryTable<2> h2(c, mesh, sim);
  h2.restore(s, "test.h5");
  EXPECT_EQ(h2.balance_warned_step(), 30);
  ::testing::internal::CaptureStderr();
  h2.check_balance(energies(50, 20));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

}  // namespace
