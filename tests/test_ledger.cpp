// The energy ledger as one table (src/solver/ledger.hpp): the balance and the checkpoint vector are
// generated from it, and a term added to it reaches every output of a run: the history column,
// summary.json's "energy" block, the checkpoint's energies and the balance itself.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/checkpoint.hpp"
#include "solver/ledger.hpp"
#include "solver/run.hpp"
#include "test_files.hpp"

using namespace fdem;

namespace {

const std::string kCases = std::string(FDEM_SOURCE_DIR) + "/cases/";

Energies some_energies() {
  Energies e;
  e.time = 1.5e-4;
  e.step = 321;
  e.kinetic = 0.1;
  e.strain = 0.2;
  e.interface_elastic = 0.03;
  e.contact_elastic = 0.004;
  e.fracture = 0.0005;
  e.damping = 0.06;
  e.friction = 0.007;
  e.work_external = 0.5;
  e.balance_error = -1e-9;
  e.scale = 0.5;
  e.damaged = 12;
  e.failed = 3;
  e.momentum[0] = 1.25;
  e.momentum[1] = -2.5;
  e.momentum[2] = 0.125;
  return e;
}

// The one-process run of the 2D impact, short, with a checkpoint (every 10 us) and its outputs.
nlohmann::json run_impact(const std::string& out) {
  RunOptions opt;
  opt.out_dir = out;
  opt.progress = false;
  opt.checkpoint_every = 1e-5;
  opt.overrides = {"parameters.speed=15", "parameters.h=0.01", "parameters.duration=2e-5",
                   "output.snapshot_count=0", "output.history_rows=10"};
  return run_case(kCases + "particle_impact_2d/case.json", opt);
}

}  // namespace

TEST(Ledger, BalanceSumsAreTheBuiltInTermsWrittenOut) {
  const Energies e = some_energies();
  // the balance's sums as they were written term by term before the table: the same bits
  const double now = e.kinetic + e.strain + e.interface_elastic + e.contact_elastic + e.fracture + e.damping +
                     e.friction;
  EXPECT_EQ(energy_now(e), now);
  EXPECT_EQ(energy_work(e), e.work_external);
  ASSERT_EQ(energy_terms().size(), 8u);
  int stored = 0, dissipated = 0, work = 0;
  for (const auto& t : energy_terms()) {
    stored += t.side == EnergySide::stored;
    dissipated += t.side == EnergySide::dissipated;
    work += t.side == EnergySide::work;
  }
  EXPECT_EQ(stored, 4);
  EXPECT_EQ(dissipated, 3);
  EXPECT_EQ(work, 1);
}

TEST(Ledger, CheckpointVectorKeepsTheOldLayoutAndNowTheMomentum) {
  const Energies e = some_energies();
  const std::vector<double> v = energies_to_vector(e);
  ASSERT_EQ(v.size(), static_cast<size_t>(kEnergyFieldCount + 3));
  // the layout of the checkpoints written before the table
  const std::vector<double> old = {e.time, 321, 0.1, 0.2, 0.03, 0.004, 0.0005, 0.06, 0.007, 0.5, -1e-9, 0.5, 12, 3};
  EXPECT_EQ(std::vector<double>(v.begin(), v.begin() + kEnergyFieldCount), old);
  const Energies back = energies_from_vector(v);
  EXPECT_EQ(energies_to_vector(back), v);
  EXPECT_EQ(back.momentum[1], -2.5);
  const Energies from_old = energies_from_vector(old);  // an older checkpoint: no momentum
  EXPECT_EQ(from_old.kinetic, 0.1);
  EXPECT_EQ(from_old.failed, 3);
  EXPECT_EQ(from_old.momentum[0], 0.0);
  EXPECT_THROW(energies_from_vector(std::vector<double>(13, 0.0), "run/last_row_energies"), InputError);
}

TEST(Ledger, SumOverProcessesTakesEverySummedTermTheMomentumAndTheCounts) {
  Energies e = some_energies();
  int n = 0;
  sum_energies(e, [&n](double* v, int count) {  // a stand-in for two processes holding the same
    n = count;
    for (int i = 0; i < count; ++i) v[i] *= 2;
  });
  EXPECT_EQ(n, 8 + 3 + 2);
  EXPECT_EQ(e.kinetic, 0.2);
  EXPECT_EQ(e.work_external, 1.0);
  EXPECT_EQ(e.momentum[2], 0.25);
  EXPECT_EQ(e.failed, 6);
  EXPECT_EQ(e.balance_error, -1e-9);  // not a sum: computed from the sums
}

TEST(Ledger, AnAddedTermReachesEveryOutput) {
  namespace fs = std::filesystem;
  const std::string plain = fdem::test::scratch_dir("ledger", "plain");
  const std::string added = fdem::test::scratch_dir("ledger", "added");
  run_impact(plain);
  // a dummy work term: 3 J/s times the time, the same on every process
  constexpr double kRate = 3.0;
  clear_added_energy_terms();
  add_energy_term("dummy_work", "W_dummy [J]", EnergySide::work, [](double t, long) { return kRate * t; });
  const nlohmann::json s = run_impact(added);
  clear_added_energy_terms();

  // history.csv: its column, with its values; the other columns unchanged but the balance error,
  // which is now lower by the dummy work done since the first row
  const auto a = fdem::test::read_history(plain + "/history.csv");
  const auto b = fdem::test::read_history(added + "/history.csv");
  ASSERT_TRUE(b.count("W_dummy [J]"));
  EXPECT_FALSE(a.count("W_dummy [J]"));
  const auto& t = b.at("time [s]");
  ASSERT_GE(t.size(), 5u);
  for (size_t i = 0; i < t.size(); ++i) {
    // (history.csv holds 10 significant digits)
    EXPECT_NEAR(b.at("W_dummy [J]")[i], kRate * t[i], 1e-9 * kRate * t[i] + 1e-300);
    EXPECT_EQ(b.at("E_kinetic [J]")[i], a.at("E_kinetic [J]")[i]);
    EXPECT_NEAR(b.at("energy_error [J]")[i], a.at("energy_error [J]")[i] - kRate * (t[i] - t[0]),
                1e-10 + 1e-9 * std::fabs(a.at("energy_error [J]")[i]));
  }
  // summary.json
  ASSERT_TRUE(s["energy"].contains("dummy_work_J"));
  EXPECT_NEAR(s["energy"]["dummy_work_J"].get<double>(), kRate * t.back(), 1e-9 * kRate * t.back());
  // the checkpoint: the energies' vector carries it after the momentum
  CheckpointHeader h;
  const StateArrays st = read_checkpoint(added + "/checkpoint.h5", h);
  const std::vector<double>& v = st.array("simulation/energies");
  ASSERT_EQ(v.size(), static_cast<size_t>(kEnergyFieldCount + 3 + 1));
  EXPECT_DOUBLE_EQ(v.back(), kRate * v[0]);
  fs::remove_all(plain);
  fs::remove_all(added);
}
