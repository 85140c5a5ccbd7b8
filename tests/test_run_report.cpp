// What a run tells a person (issue 51, items 8, 18, 19): summary.json's phases say they are
// estimated from the timed steps (solver/summary.hpp phases_report), a run with progress ends with
// its key results taken from its summary (key_results, print_run_end), and the progress line
// estimates the time left only once the pace is known (solver/run_progress.hpp time_left).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "solver/run_progress.hpp"
#include "solver/summary.hpp"
#include "test_files.hpp"

namespace {

using fdem::test::slurp;
constexpr auto npos = std::string::npos;

// The parts of summary.json a Brazilian disc run wrote (cases/brazilian_disc/case.json, values
// of a real run), the closing line's throughput with them.
nlohmann::json disc_summary() {
  return nlohmann::json::parse(R"({
    "case": "brazilian_disc", "stop_reason": "load_drop", "element_steps_per_second": 5.1e6,
    "counts": {"elements": 2342, "interfaces": 3460, "nodes": 7026},
    "interfaces_damaged": 516, "interfaces_failed": 60,
    "fragments": {"count": 1, "largest_fraction": 1.0, "largest_mass_kg": 0.0212,
                  "total_mass_kg": 0.0212},
    "results": {"peak_load_N": 1292.7083436319983, "tensile_strength_Pa": 8229636.914606759,
                "platens": {"top": {"peak_load_N": 1292.7083436319983,
                                    "displacement_at_peak_m": 0.00034697875056631316},
                            "bottom": {"peak_load_N": 1290.2186716508375,
                                       "displacement_at_peak_m": 0.00034662865744569465}}},
    "energy": {"external_work_J": 0.3488685209261746, "fracture_J": 0.07478884161289305,
               "kinetic_J": 0.09996112191731676, "strain_J": 0.06224751388046552,
               "balance_error_J": -1.333479806797655e-06,
               "max_relative_balance_error": 0.00026443900487879127, "warning_threshold": 0.05}
  })");
}

const char* kDiscResults =
    "fdem: key results of brazilian_disc:\n"
    "  tensile strength 8.23 MPa (2 P / (pi D L) of the peak load 1293 N)\n"
    "  peak load: bottom 1290 N at 0.3466 mm, top 1293 N at 0.347 mm\n"
    "  interfaces: 60 failed, 516 damaged of 3460; fragments: 1, the largest 100.0 % of the mass\n"
    "  energy: external work 0.3489 J, fracture 0.07479 J, kinetic 0.09996 J; balance error at most "
    "0.02644 % of the energy scale\n";

// What print_run_end writes to stdout and stderr together, in the order a terminal shows it.
std::string run_end_output(const nlohmann::json& summary, bool progress) {
  const std::string path = fdem::test::scratch_dir("run_report", "end") + ".log";
  std::fflush(stdout);
  std::fflush(stderr);
  const int out = dup(1), err = dup(2);
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0 || out < 0 || err < 0) return "cannot redirect to " + path;
  dup2(fd, 1);
  dup2(fd, 2);
  close(fd);
  fdem::RunRecord r;
  r.out = "/tmp/out/brazilian_disc";
  r.stop_reason = summary.value("stop_reason", "");
  r.loop_wall_seconds = 22.9;
  fdem::print_run_end(summary, r, 49909, progress);
  std::fflush(stdout);
  std::fflush(stderr);
  dup2(out, 1);
  dup2(err, 2);
  close(out);
  close(err);
  const std::string text = slurp(path);
  std::remove(path.c_str());
  return text;
}

}  // namespace

// Item 8: the seconds of the phases done on every step are their mean over the timed (sampled)
// steps times every step (they summed to 506 s for a loop of 316 s); the summary says so, and how
// many steps were timed, without changing a number.
TEST(SummaryPhases, SayTheyAreEstimatedFromTheTimedSteps) {
  fdem::PhaseTimes p;
  p.forces = 0.23;
  p.platens = 0.01;
  p.contact = 0.03;
  p.ledger = 0.11;
  p.nodes = 0.09;
  p.steps = 49909;
  p.timed = 678;
  const nlohmann::json j = fdem::phases_report(p);
  EXPECT_TRUE(j.value("estimated", false)) << j.dump();
  const std::string note = j.value("note", "");
  EXPECT_NE(note.find("estimated from 678 timed steps of 49909"), npos) << note;
  EXPECT_NE(note.find("total_seconds can exceed loop_wall_seconds"), npos) << note;
  const double scale = static_cast<double>(p.steps) / static_cast<double>(p.timed);
  EXPECT_EQ(j["forces"]["seconds"].get<double>(), p.forces * scale);  // the numbers as before
  EXPECT_EQ(j["ledger"]["seconds"].get<double>(), p.ledger);
  EXPECT_EQ(j["timed_steps"].get<long>(), 678);

  p.timed = p.steps;  // every step timed: measured
  EXPECT_FALSE(fdem::phases_report(p).value("estimated", true));
  EXPECT_EQ(fdem::phases_report(p).value("note", ""), "measured on every step");
  p.timed = 0;
  EXPECT_FALSE(fdem::phases_report(p).value("estimated", true));
  EXPECT_EQ(fdem::phases_report(p).value("note", ""), "no step was timed");
}

// Item 18: the result a case exists for, from its summary: strength, peak loads, failed
// interfaces and fragments, energies and their balance.
TEST(RunEnd, KeyResultsOfADiscBetweenPlatens) { EXPECT_EQ(fdem::key_results(disc_summary()), kDiscResults); }

// Without platens or fragments those lines are left out; a balance warning and an interrupted run
// are said.
TEST(RunEnd, KeyResultsSayWhatTheSummaryHolds) {
  nlohmann::json s = disc_summary();
  s["results"] = nlohmann::json::object();
  s["fragments"] = nullptr;  // (a process that does not write)
  s["stop_reason"] = "interrupted";
  s["energy"]["max_relative_balance_error"] = 0.073;
  s["energy"]["warning"] = {{"time_s", 1.25e-3}, {"step", 1200}, {"relative_balance_error", 0.051}};
  EXPECT_EQ(fdem::key_results(s),
            "fdem: key results of brazilian_disc so far (interrupted):\n"
            "  interfaces: 60 failed, 516 damaged of 3460\n"
            "  energy: external work 0.3489 J, fracture 0.07479 J, kinetic 0.09996 J; balance error at most "
            "7.3 % of the energy scale (above the 5 % warning from t = 0.00125 s)\n");
  // nothing it knows, or of other types: the heading alone, no exception
  EXPECT_EQ(fdem::key_results(nlohmann::json::object()), "fdem: key results:\n");
  EXPECT_EQ(fdem::key_results(nlohmann::json::parse(R"({"case": 3, "results": [1], "energy": "x",
                                                       "counts": {"interfaces": "many"}, "fragments": 2})")),
            "fdem: key results:\n");
}

// Item 18: with progress on, the key results are the last lines a person sees (on stderr, after
// the paths on stdout); with --quiet (progress off) only the paths, as before.
TEST(RunEnd, KeyResultsAreTheLastLinesOfARunWithProgress) {
  const std::string paths =
      "results: /tmp/out/brazilian_disc\n"
      "  history:   /tmp/out/brazilian_disc/history.csv\n"
      "  summary:   /tmp/out/brazilian_disc/summary.json\n";
  const std::string with = run_end_output(disc_summary(), true);
  EXPECT_EQ(with, "fdem: 49909 steps in 22.9 s (5.1e+06 element-steps/s); stopped by load_drop\n" + paths +
                      kDiscResults);
  EXPECT_EQ(run_end_output(disc_summary(), false), paths);
}

// Item 19: the time left from the pace since the first update, once kPaceSeconds and kPaceSteps
// have passed ("?" before: the first line of a 24 s run said "left 68.6 min").
TEST(ProgressLine, TimeLeftOnlyOnceThePaceIsKnown) {
  EXPECT_TRUE(std::isnan(fdem::time_left(0.08, 1, 2e-5, 0.99998)));  // the first step
  EXPECT_TRUE(std::isnan(fdem::time_left(1.9, 10000, 0.08, 0.9)));   // under kPaceSeconds
  EXPECT_TRUE(std::isnan(fdem::time_left(30.0, 5, 0.5, 0.5)));       // under kPaceSteps
  EXPECT_TRUE(std::isnan(fdem::time_left(30.0, 100, 0.0, 0.5)));     // no simulated time yet
  EXPECT_DOUBLE_EQ(fdem::time_left(2.4, 5000, 0.1, 0.9), 21.6);      // the pace of the 24 s run
  EXPECT_EQ(fdem::time_left(0.5, 3, 1.0, 0.0), 0.0);                 // the end
  EXPECT_EQ(fdem::time_left(0.5, 3, 1.0, 1e-12), 0.0);               // (the loop's end test)
  EXPECT_EQ(fdem::time_left(0.5, 3, 1.0, -5e-5), 0.0);               // past it ("left -0 s" before)
  EXPECT_EQ(fdem::fmt_time(fdem::time_left(0.08, 1, 2e-5, 0.99998)), "?");
}

// Item 19: the lines a run prints at once (its first step, a forced line) say "left ?", the last one
// "left 0 s".
TEST(ProgressLine, FirstLinesOfARunSayTheTimeLeftIsNotKnownYet) {
  ::testing::internal::CaptureStderr();
  {
    fdem::Progress p(true, 0, 0.0);
    p.update(1, 7.3e-8, 3.6e-3);  // the Brazilian disc's first step
    p.update(2, 1.46e-7, 3.6e-3, true);
    p.update(49909, 3.6e-3, 3.6e-3, true);
    p.done();
  }
  const std::string log = ::testing::internal::GetCapturedStderr();
  const size_t first = log.find('\n'), second = log.find('\n', first + 1);
  ASSERT_NE(second, npos) << log;
  EXPECT_NE(log.substr(0, first).find("left ?"), npos) << log;
  EXPECT_NE(log.substr(first, second - first).find("left ?"), npos) << log;
  EXPECT_NE(log.substr(second).find("(100.0 %)"), npos) << log;
  EXPECT_NE(log.substr(second).find("left 0 s"), npos) << log;
}
