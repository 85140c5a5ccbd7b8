// Checkpoint and restart through the real command line (issue 8): a run killed right after a
// checkpoint, or in the middle of writing one, and restarted gives the same history, snapshots
// and summary as a run that was not stopped, bit for bit (one thread; with two threads bit for
// bit or within the last bits that contact atomics leave to chance). Bad restart input and
// unwritable outputs give exit status 2 and a message naming the file.
//
// Cases: the Brazilian disc at element size R/6 (288 elements, 413 interfaces), platens at
// 0.5 m/s, run to 1.2 ms (9972 steps): the disc cracks from about 0.7 ms on (17 interfaces fail,
// 14 are handed over to contact; the step shortens then), so a checkpoint at 0.8 ms carries cracks, contact pair lists
// and platen shear springs; its crack faces open and do not touch. And uniaxial compression at
// 10 mm cells (200 elements, 285 interfaces), platens at 0.5 m/s, to 1 ms (16671 steps): shear
// cracks whose faces press and slide on each other from 0.84 ms on, so a checkpoint at 0.92 ms
// carries contact pairs in contact with their normal and shear history and friction.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "solver/run.hpp"
#include "solver/run_setup.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

// the paper's setting of the Brazilian disc, on which these tests were made
const std::string kDisc = std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case_paper.json";
const std::string kSets =
    " --set 'mesh.element_size=\"=radius / 6\"' --set parameters.rate=0.5"
    " --set parameters.closure=1.2e-3";
constexpr double kEvery = 2e-4;  // checkpoints at 0.2, 0.4, ... ms

int sh(const std::string& cmd) { return fdem::test::system_status(cmd); }

using fdem::test::slurp;

std::string tmpdir(const std::string& name) { return fdem::test::scratch_dir("ckpt", name); }

const std::string kUniaxial = std::string(FDEM_SOURCE_DIR) + "/cases/uniaxial_compression/case.json";
const std::string kUniaxialSets =
    " --set parameters.cell=0.01 --set parameters.rate=0.5 --set time.stop.drop_fraction=0.999"
    " --set time.end_time=1e-3";  // to 1 ms (two threads stopped at 0.88 ms by a 95 % load drop)
// checkpoints at 0.23, 0.46, 0.69, 0.92 ms; by the 4th, fragments are in contact (the first
// contacts start at 0.84 ms)
constexpr double kUniaxialEvery = 2.3e-4;

// fdem run of a case with `threads` OpenMP threads; extra: more options; env: environment.
// Waiting threads sleep (OMP_WAIT_POLICY=passive): on a loaded machine spinning threads make a
// two-thread run 40 times slower; the results do not depend on it.
int run_case(const std::string& c, const std::string& sets, const std::string& out, int threads,
             const std::string& extra = "", const std::string& env = "") {
  const std::string cmd = "env OMP_NUM_THREADS=" + std::to_string(threads) +
                          " OMP_PROC_BIND=false OMP_WAIT_POLICY=passive " + env + " " + FDEM_BINARY + " run " + c +
                          " --out " + out + " --quiet" + sets + " " + extra + " > " + out +
                          ".log 2>&1";
  return sh(cmd);
}

int run_disc(const std::string& out, int threads, const std::string& extra = "",
             const std::string& env = "") {
  return run_case(kDisc, kSets, out, threads, extra, env);
}

int run_uniaxial(const std::string& out, int threads, const std::string& extra = "",
                 const std::string& env = "") {
  return run_case(kUniaxial, kUniaxialSets, out, threads, extra, env);
}

std::string every(double t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "--checkpoint-every %.17g", t);
  return buf;
}

struct H5File {
  hid_t id;
  explicit H5File(const std::string& p) : id(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {}
  ~H5File() {
    if (id >= 0) H5Fclose(id);
  }
};

std::vector<double> read_doubles(hid_t f, const std::string& name) {
  std::vector<double> out;
  hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  if (d < 0) return out;
  hid_t s = H5Dget_space(d);
  out.resize(static_cast<size_t>(H5Sget_simple_extent_npoints(s)));
  if (!out.empty()) H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(s);
  H5Dclose(d);
  return out;
}

long long read_int(hid_t f, const std::string& name) {
  long long v = -1;
  hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  if (d < 0) return v;
  H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v);
  H5Dclose(d);
  return v;
}

template <class T>
T root_attr(hid_t f, const char* name, hid_t type) {
  T v{};
  hid_t a = H5Aopen(f, name, H5P_DEFAULT);
  if (a >= 0) {
    H5Aread(a, type, &v);
    H5Aclose(a);
  }
  return v;
}

std::vector<std::string> frames(hid_t f) {
  std::vector<std::string> out;
  H5G_info_t info;
  H5Gget_info(f, &info);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char buf[256];
    H5Lget_name_by_idx(f, "/", H5_INDEX_NAME, H5_ITER_INC, i, buf, sizeof buf, H5P_DEFAULT);
    if (std::string(buf).rfind("step_", 0) == 0) out.push_back(buf);
  }
  return out;
}

// Everything a run leaves that must not depend on whether it was stopped: history.csv (text),
// every snapshot frame's positions, velocities and damage (bits), and the summary's results.
struct Results {
  std::string history;
  std::vector<std::string> frame_names;
  std::vector<std::vector<double>> x, v, damage;
  nlohmann::json summary;
};

Results results(const std::string& out) {
  Results r;
  r.history = slurp(out + "/history.csv");
  H5File f(out + "/snapshots.h5");
  EXPECT_GE(f.id, 0) << out;
  if (f.id < 0) return r;
  r.frame_names = frames(f.id);
  for (const auto& g : r.frame_names) {
    r.x.push_back(read_doubles(f.id, g + "/coordinates"));
    r.v.push_back(read_doubles(f.id, g + "/velocity"));
    r.damage.push_back(read_doubles(f.id, g + "/damage"));
  }
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  r.summary = {{"steps", s["steps"]},
               {"end_time_s", s["end_time_s"]},
               {"energy", s["energy"]},
               {"results", s["results"]},
               {"interfaces_damaged", s["interfaces_damaged"]},
               {"interfaces_failed", s["interfaces_failed"]},
               {"stop_reason", s["stop_reason"]}};
  return r;
}

// Bitwise comparison; returns a description of the first difference ("" when equal).
std::string differ(const Results& a, const Results& b) {
  if (a.history != b.history) return "history.csv differs";
  if (a.frame_names != b.frame_names) return "snapshot frames differ";
  for (size_t k = 0; k < a.x.size(); ++k) {
    if (a.x[k] != b.x[k]) return "coordinates of " + a.frame_names[k] + " differ";
    if (a.v[k] != b.v[k]) return "velocities of " + a.frame_names[k] + " differ";
    if (a.damage[k] != b.damage[k]) return "damage of " + a.frame_names[k] + " differs";
  }
  if (a.summary != b.summary) return "summary differs: " + a.summary.dump() + " vs " + b.summary.dump();
  return "";
}

class CheckpointRestart : public ::testing::Test {
 protected:
  // The uninterrupted run (one thread, no checkpoints), shared by the tests.
  static void SetUpTestSuite() {
    ref_dir_ = tmpdir("reference");
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(run_disc(ref_dir_, 1), 0) << slurp(ref_dir_ + ".log");
    ref_wall_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ref_ = results(ref_dir_);
  }
  static void TearDownTestSuite() {
    fs::remove_all(ref_dir_);
    fs::remove(ref_dir_ + ".log");
  }
  static std::string ref_dir_;
  static Results ref_;
  static double ref_wall_;  // s, the whole process
};
std::string CheckpointRestart::ref_dir_;
double CheckpointRestart::ref_wall_ = 0;
Results CheckpointRestart::ref_;

TEST_F(CheckpointRestart, KilledAfterCheckpointRestartsBitwise) {
  ASSERT_EQ(ref_.frame_names.size(), 10u);
  ASSERT_EQ(ref_.summary["steps"], 9972);
  ASSERT_GT(ref_.summary["interfaces_failed"].get<long>(), 10);

  const std::string out = tmpdir("after");
  // killed (SIGKILL) right after the 4th checkpoint, t = 0.8 ms
  ASSERT_EQ(run_disc(out, 1, every(kEvery),
                     "FDEM_TEST_CHECKPOINT_KILL=after:4"),
            128 + 9)
      << slurp(out + ".log");
  ASSERT_TRUE(fs::exists(out + "/checkpoint.h5"));
  EXPECT_FALSE(fs::exists(out + "/summary.json"));
  {
    H5File f(out + "/checkpoint.h5");
    ASSERT_GE(f.id, 0);
    const double t = root_attr<double>(f.id, "time", H5T_NATIVE_DOUBLE);
    EXPECT_NEAR(t, 4 * kEvery, 2e-7);
    EXPECT_EQ(read_int(f.id, "simulation/step"), root_attr<long long>(f.id, "step", H5T_NATIVE_LLONG));
    // the state carries cracks, contact pair lists, platen springs
    EXPECT_GT(read_int(f.id, "contact/handed_over"), 0);
    EXPECT_GT(read_int(f.id, "contact/pair_count"), 0);
    double fs_max = 0;
    for (double s : read_doubles(f.id, "model/platen_fs")) fs_max = std::max(fs_max, std::fabs(s));
    EXPECT_GT(fs_max, 0.0);
  }
  ASSERT_EQ(run_disc(out, 1, every(kEvery) + " --restart " + out +
                                 "/checkpoint.h5"),
            0)
      << slurp(out + ".log");
  const Results r = results(out);
  EXPECT_EQ(differ(ref_, r), "");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["checkpoint"]["restarted_from"]["step"], 5894);
  EXPECT_EQ(s["checkpoint"]["written"], 6);  // 4 before the kill, 2 after the restart
}

// A checkpoint written before any interface failed: contact's springs are not in the step yet
// (the step shortens when the first interface is handed over, after the restart); the restarted
// run takes the same steps, the same change of step and the same results.
TEST_F(CheckpointRestart, KilledBeforeTheContactStepRestartsBitwise) {
  const auto ref_summary = nlohmann::json::parse(slurp(ref_dir_ + "/summary.json"));
  const long changed = ref_summary["time_step"].value("dt_changed_at_step", -1L);
  ASSERT_GT(changed, 0) << "the reference run's step should shorten when the disc cracks";
  const std::string out = tmpdir("before");
  ASSERT_EQ(run_disc(out, 1, every(kEvery), "FDEM_TEST_CHECKPOINT_KILL=after:2"), 128 + 9)
      << slurp(out + ".log");
  {
    H5File f(out + "/checkpoint.h5");
    ASSERT_GE(f.id, 0);
    EXPECT_EQ(read_int(f.id, "simulation/contact_step_pending"), 1);
    EXPECT_EQ(read_int(f.id, "simulation/dt_changed_at"), -1);
    EXPECT_LT(read_int(f.id, "simulation/step"), changed);
  }
  ASSERT_EQ(run_disc(out, 1, every(kEvery) + " --restart " + out + "/checkpoint.h5"), 0)
      << slurp(out + ".log");
  const Results r = results(out);
  EXPECT_EQ(differ(ref_, r), "");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["time_step"], ref_summary["time_step"]);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

TEST_F(CheckpointRestart, KillWhileWritingKeepsPreviousCheckpoint) {
  const std::string out = tmpdir("during");
  // killed in the middle of writing the 5th checkpoint (t = 1.0 ms): the 4th stays
  ASSERT_EQ(run_disc(out, 1, every(kEvery),
                     "FDEM_TEST_CHECKPOINT_KILL=during:5"),
            128 + 9)
      << slurp(out + ".log");
  ASSERT_TRUE(fs::exists(out + "/checkpoint.h5.tmp"));  // the half-written one
  {
    H5File f(out + "/checkpoint.h5");
    ASSERT_GE(f.id, 0);
    EXPECT_NEAR(root_attr<double>(f.id, "time", H5T_NATIVE_DOUBLE), 4 * kEvery, 2e-7);
  }
  // the killed run wrote history rows and a snapshot (0.9 ms) after that checkpoint
  {
    H5File f(out + "/snapshots.h5");
    ASSERT_GE(f.id, 0);
    EXPECT_EQ(frames(f.id).size(), 7u);  // 0, 0.15, ..., 0.9 ms
  }
  EXPECT_GT(slurp(out + "/history.csv").size(), ref_.history.size() * 8 / 10);

  // the half-written file is not taken for a checkpoint
  EXPECT_EQ(run_disc(out + "_tmp", 1, "--restart " + out + "/checkpoint.h5.tmp"), 2);
  EXPECT_NE(slurp(out + "_tmp.log").find(out + "/checkpoint.h5.tmp"), std::string::npos)
      << slurp(out + "_tmp.log");

  // restart from the 4th: later rows and frames are dropped and written again
  ASSERT_EQ(run_disc(out, 1, every(kEvery) + " --restart " + out +
                                 "/checkpoint.h5"),
            0)
      << slurp(out + ".log");
  EXPECT_EQ(differ(ref_, results(out)), "");
  // and a restart from the last checkpoint of a completed run only adds the final row
  ASSERT_EQ(run_disc(out + "_end", 1, every(kEvery)), 0);
  ASSERT_EQ(run_disc(out + "_end", 1, "--restart " + out + "_end/checkpoint.h5"), 0)
      << slurp(out + "_end.log");
  EXPECT_EQ(differ(ref_, results(out + "_end")), "");
}

// Killed at an arbitrary moment (SIGKILL from outside after a wall time between 40 % and 95 % of
// the reference run's, so it may fall in a step, a history row, a snapshot or a checkpoint):
// the restart from whatever checkpoint is there reproduces the uninterrupted run.
TEST_F(CheckpointRestart, KilledAtArbitraryMomentRestartsBitwise) {
  const double wall = ref_wall_;
  static unsigned calls = 0;  // --gtest_repeat: another moment each time
  const unsigned seed = static_cast<unsigned>(::getpid()) + 7919u * calls++;
  const double delay = wall * (0.4 + 0.55 * ((seed * 2654435761u) % 1000u) / 1000.0);
  SCOPED_TRACE("kill after " + std::to_string(delay) + " s of " + std::to_string(wall) + " s");
  const std::string out = tmpdir("arbitrary");
  const int rc = run_disc(out, 1, every(kEvery / 4), "timeout -s KILL " + std::to_string(delay));
  if (rc == 0) GTEST_SKIP() << "the run finished before the kill";
  ASSERT_EQ(rc, 128 + 9) << slurp(out + ".log");
  if (!fs::exists(out + "/checkpoint.h5")) GTEST_SKIP() << "killed before the first checkpoint";
  ASSERT_EQ(run_disc(out, 1, every(kEvery / 4) + " --restart " + out + "/checkpoint.h5"), 0)
      << slurp(out + ".log");
  const Results r = results(out);
  if (slurp(out + ".log").find("snapshots.h5.damaged") != std::string::npos) {
    // killed while writing a frame: the frames from the restart on must still agree
    EXPECT_EQ(r.history, ref_.history);
    EXPECT_EQ(r.x.back(), ref_.x.back());
  } else {
    EXPECT_EQ(differ(ref_, r), "");
  }
}

// A snapshots.h5 that cannot be continued (here: cut short, as a full disk or a kill in the middle
// of a frame might leave it) does not stop the restart: it is set aside and a new one started.
TEST_F(CheckpointRestart, DamagedSnapshotFileIsSetAside) {
  const std::string out = tmpdir("damaged");
  ASSERT_EQ(run_disc(out, 1, every(kEvery), "FDEM_TEST_CHECKPOINT_KILL=after:5"), 128 + 9);
  fs::resize_file(out + "/snapshots.h5", fs::file_size(out + "/snapshots.h5") / 2);
  ASSERT_EQ(run_disc(out, 1, "--restart " + out + "/checkpoint.h5"), 0) << slurp(out + ".log");
  const std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("snapshots.h5.damaged"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out + "/snapshots.h5.damaged"));
  const Results r = results(out);
  EXPECT_EQ(r.history, ref_.history);
  // the new file has the frames after the checkpoint (1.05 and 1.2 ms, and the final one)
  ASSERT_EQ(r.frame_names.size(), 3u);
  EXPECT_EQ(r.frame_names.back(), ref_.frame_names.back());
  EXPECT_EQ(r.x.back(), ref_.x.back());
  EXPECT_EQ(r.damage.back(), ref_.damage.back());
}

TEST(CheckpointRestartContact, FragmentsInContactRestartBitwise) {
  const std::string ref = tmpdir("uniaxial_ref"), out = tmpdir("uniaxial");
  ASSERT_EQ(run_uniaxial(ref, 1), 0) << slurp(ref + ".log");
  const Results a = results(ref);
  ASSERT_EQ(a.summary["stop_reason"], "end_time");
  ASSERT_GT(a.summary["interfaces_failed"].get<long>(), 20);
  ASSERT_EQ(run_uniaxial(out, 1, every(kUniaxialEvery), "FDEM_TEST_CHECKPOINT_KILL=after:4"), 128 + 9)
      << slurp(out + ".log");
  {
    H5File f(out + "/checkpoint.h5");
    ASSERT_GE(f.id, 0);
    EXPECT_NEAR(root_attr<double>(f.id, "time", H5T_NATIVE_DOUBLE), 4 * kUniaxialEvery, 2e-7);
    int in_contact = 0;
    double fs_max = 0;
    const auto fn = read_doubles(f.id, "contact/pair_fn");
    const auto fs = read_doubles(f.id, "contact/pair_fs");
    for (double x : fn) in_contact += x > 0;
    for (double x : fs) fs_max = std::max(fs_max, std::fabs(x));
    EXPECT_GT(in_contact, 0);
    EXPECT_GT(fs_max, 0.0);
    EXPECT_GT(read_doubles(f.id, "contact/dissipated").at(0), 0.0);
  }
  ASSERT_EQ(run_uniaxial(out, 1, every(kUniaxialEvery) + " --restart " + out + "/checkpoint.h5"), 0)
      << slurp(out + ".log");
  EXPECT_EQ(differ(a, results(out)), "");
}

// With two threads the node forces (bulk, interfaces and contact: one scatter view with a copy
// per thread) repeat bit for bit from run to run (three uninterrupted runs of this case: the same
// history), but the platens' force and work sums are added with atomics, so the order of those
// additions (and the last bits of the platen columns) may differ. (Before the contact forces went
// through the scatter view, two runs differed by 1e-15 m/s in a few velocities, and once the
// force kernel did elements with their interfaces, by O(1) at the end: cracks amplified the
// difference.) So the restarted run must match the uninterrupted one bit for bit or within 1e-9 of each field's largest value in
// every frame, with the same steps and failed interfaces; a state the restart lost (a contact's
// spring or friction history, an interface's damage) shows far above that.
double largest_gap(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b) {
  if (a.size() != b.size()) return 1e300;
  double gap = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    if (a[k].size() != b[k].size()) return 1e300;
    double big = 0, d = 0;
    for (size_t i = 0; i < a[k].size(); ++i) {
      big = std::max(big, std::fabs(a[k][i]));
      d = std::max(d, std::fabs(a[k][i] - b[k][i]));
    }
    gap = std::max(gap, big > 0 ? d / big : d);
  }
  return gap;
}

// The same frames, steps and failed interfaces, and every field within 1e-9 of its largest value.
void expect_within_roundoff(const Results& a, const Results& b) {
  if (differ(a, b).empty()) return;
  ASSERT_EQ(a.frame_names, b.frame_names);
  EXPECT_EQ(a.summary["steps"], b.summary["steps"]);
  EXPECT_EQ(a.summary["interfaces_failed"], b.summary["interfaces_failed"]);
  EXPECT_LE(largest_gap(a.x, b.x), 1e-9) << differ(a, b);
  EXPECT_LE(largest_gap(a.v, b.v), 1e-9) << differ(a, b);
  EXPECT_LE(largest_gap(a.damage, b.damage), 1e-9) << differ(a, b);
}

// A run over several processes writes its contacts in whole-mesh numbering ("contact/pairs": each
// own surface node's pairs that hold a history, with the face's vertices), and a restart on another
// process count or on one process builds its lists anew from those rows and carries the histories
// over (ContactSystem::load_state). The same path on one process: the checkpoint above with its own
// lists taken out restarts from the rows alone. Without the rows' histories the springs and the
// friction state of the contacts would start from zero, which shows far above the bound; with them
// the run goes on as the uninterrupted one up to the order in which a rebuilt list adds a node's
// contacts (bound 1e-9 of each field's largest value, as between two thread counts below).
TEST(CheckpointRestartContact, PairsInWholeNumberingCarryTheHistories) {
  const std::string ref = tmpdir("pairs_ref"), out = tmpdir("pairs");
  ASSERT_EQ(run_uniaxial(ref, 1), 0) << slurp(ref + ".log");
  ASSERT_EQ(run_uniaxial(out, 1, every(kUniaxialEvery), "FDEM_TEST_CHECKPOINT_KILL=after:4"), 128 + 9)
      << slurp(out + ".log");
  const std::string ck = out + "/checkpoint.h5";
  fdem::CheckpointHeader h;
  fdem::StateArrays s = fdem::read_checkpoint(ck, h);
  ASSERT_TRUE(s.has("contact/pairs"));
  const size_t row = static_cast<size_t>(s.get_int("contact/pair_row"));
  ASSERT_EQ(row, 4u + 2u * static_cast<size_t>(h.dim));
  const std::vector<double>& rows = s.array("contact/pairs");
  ASSERT_EQ(rows.size() % row, 0u);
  size_t springs = 0;  // rows with a shear spring
  for (size_t r = 0; r < rows.size() / row; ++r)
    for (int k = 0; k < h.dim; ++k) springs += rows[r * row + 4 + h.dim + k] != 0.0 ? 1 : 0;
  EXPECT_GT(springs, 0u);
  for (const char* name : {"contact/pair_count", "contact/pair_off", "contact/pair_face", "contact/pair_fn",
                           "contact/pair_ac", "contact/pair_g0", "contact/pair_fs", "contact/xb"}) {
    ASSERT_TRUE(s.has(name)) << name;
    s.f64.erase(name);
    s.i64.erase(name);
  }
  fdem::write_checkpoint(ck, h, s);
  ASSERT_EQ(run_uniaxial(out, 1, "--restart " + ck), 0) << slurp(out + ".log");
  expect_within_roundoff(results(ref), results(out));
}

TEST(CheckpointRestartContact, TwoThreadsRestartMatchesUninterrupted) {
  const std::string a = tmpdir("two_a"), b = tmpdir("two_b");
  ASSERT_EQ(run_uniaxial(a, 2), 0) << slurp(a + ".log");
  ASSERT_EQ(run_uniaxial(b, 2, every(kUniaxialEvery), "FDEM_TEST_CHECKPOINT_KILL=after:4"), 128 + 9);
  ASSERT_EQ(run_uniaxial(b, 2, "--restart " + b + "/checkpoint.h5"), 0) << slurp(b + ".log");
  expect_within_roundoff(results(a), results(b));
}

// Strength reduction (slope stability): the factor the interface histories were last updated
// under is part of the state. The slope case at 3 m elements (594 elements, 68 interfaces),
// settled to 0.2 s, the factor rising by 2 per second from 0.5: killed after the checkpoint at
// 0.96 s (factor 2.02, damaged interfaces softening as the strength falls, the wedge starting to
// slide), the restarted run matches the uninterrupted one bit for bit.
TEST(CheckpointRestartStrengthReduction, SlopeRestartsBitwise) {
  const std::string slope = std::string(FDEM_SOURCE_DIR) + "/cases/slope_failure/case.json";
  const std::string sets =
      " --set parameters.h=3 --set parameters.t_settle=0.2 --set parameters.srf_rate=2"
      " --set parameters.t_end=1.2 --set output.snapshot_count=6";
  const std::string ref = tmpdir("slope_ref"), out = tmpdir("slope");
  ASSERT_EQ(run_case(slope, sets, ref, 1), 0) << slurp(ref + ".log");
  const Results a = results(ref);
  ASSERT_GT(a.summary["interfaces_damaged"].get<long>(), 20);
  ASSERT_EQ(run_case(slope, sets, out, 1, every(0.32), "FDEM_TEST_CHECKPOINT_KILL=after:3"), 128 + 9)
      << slurp(out + ".log");
  {
    H5File f(out + "/checkpoint.h5");
    ASSERT_GE(f.id, 0);
    const auto sr = read_doubles(f.id, "simulation/strength_reduction");
    ASSERT_EQ(sr.size(), 3u);
    EXPECT_NEAR(sr[0], 0.5 + 2 * (0.96 - 0.2), 1e-3);  // the factor of the last step
    EXPECT_EQ(sr[1], sr[0]);                            // the histories follow it
  }
  ASSERT_EQ(run_case(slope, sets, out, 1, every(0.32) + " --restart " + out + "/checkpoint.h5"), 0)
      << slurp(out + ".log");
  EXPECT_EQ(differ(a, results(out)), "");
  fs::remove_all(ref);
  fs::remove_all(out);
}

TEST_F(CheckpointRestart, BadRestartInputExits2NamingTheFile) {
  const std::string out = tmpdir("bad");
  fs::create_directories(out);
  auto expect_rejected = [&](const std::string& file, const std::string& extra_sets,
                             const std::string& what) {
    const std::string o = out + "/run";
    EXPECT_EQ(run_disc(o, 1, extra_sets + " --restart " + file), 2) << what << ": " << slurp(o + ".log");
    const std::string log = slurp(o + ".log");
    EXPECT_NE(log.find(file), std::string::npos) << what << ": " << log;
    EXPECT_NE(log.find(what), std::string::npos) << log;
  };
  expect_rejected(out + "/missing.h5", "", "does not exist");
  {
    std::ofstream(out + "/text.h5") << "not a checkpoint\n";
  }
  expect_rejected(out + "/text.h5", "", "not an HDF5 file");
  expect_rejected(ref_dir_ + "/snapshots.h5", "", "not an fdem checkpoint");

  // a checkpoint of this case (short run: 800 steps)
  const std::string ck = out + "/short";
  ASSERT_EQ(run_disc(ck, 1, "--set time.max_steps=800 --checkpoint-every 5e-5"), 0) << slurp(ck + ".log");
  ASSERT_TRUE(fs::exists(ck + "/checkpoint.h5"));
  // other --set options: same mesh, another case
  expect_rejected(ck + "/checkpoint.h5", "", "another case");
  // another mesh
  expect_rejected(ck + "/checkpoint.h5", "--set time.max_steps=800 --set 'mesh.element_size=\"=radius / 5\"'",
                  "another case or mesh: nodes");
  // a longer run is another case too (max_steps is part of it)
  EXPECT_EQ(run_disc(ck, 1, "--set time.max_steps=900 --restart " + ck + "/checkpoint.h5"), 2);
  // precision: "double" given is the default (the case hash leaves it out, as versions before the
  // key had it); "mixed" is another case
  EXPECT_EQ(run_disc(out + "/dbl", 1, "--set time.max_steps=800 --set precision=double --restart " + ck +
                                          "/checkpoint.h5"),
            0)
      << slurp(out + "/dbl.log");
  expect_rejected(ck + "/checkpoint.h5", "--set time.max_steps=800 --set precision=mixed", "another case");
  // The header's mesh hash is the sum of the rows' hashes (a run whose mesh no process holds sums
  // its parts'); a checkpoint written before 2026-12-07 keeps the hash of then (FNV-1a over the
  // arrays in order) and still restarts; any other hash is another mesh.
  {
    const fdem::Case c = fdem::load_case(kDisc, {"mesh.element_size=\"=radius / 6\"", "parameters.rate=0.5",
                                                 "parameters.closure=1.2e-3", "time.max_steps=800"});
    const fdem::HostMesh mesh = fdem::prepare_mesh(c);
    fdem::CheckpointHeader h;
    const fdem::StateArrays st = fdem::read_checkpoint(ck + "/checkpoint.h5", h);
    EXPECT_EQ(h.mesh_hash, fdem::mesh_hash(mesh));
    const std::string old_hash = fdem::mesh_hash_before_2026_12_07(mesh);
    EXPECT_NE(old_hash, h.mesh_hash);
    h.mesh_hash = old_hash;
    fdem::write_checkpoint(out + "/old_hash.h5", h, st);
    EXPECT_EQ(run_disc(out + "/old", 1, "--set time.max_steps=800 --restart " + out + "/old_hash.h5"), 0)
        << slurp(out + "/old.log");
    h.mesh_hash = "0123456789abcdef";
    fdem::write_checkpoint(out + "/other_hash.h5", h, st);
    expect_rejected(out + "/other_hash.h5", "--set time.max_steps=800", "the mesh coordinates or connectivity differ");
  }
  // the same case goes on (the checkpoint interval may change)
  EXPECT_EQ(run_disc(ck, 1, "--set time.max_steps=800 --restart " + ck + "/checkpoint.h5"), 0)
      << slurp(ck + ".log");
}

TEST(CheckpointOutput, CaseKeyWritesCheckpoints) {
  const std::string out = tmpdir("casekey");
  const std::string cmd = std::string("env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ") + FDEM_BINARY +
                          " run " + FDEM_TEST_DATA + "/cases/bar.json --out " + out +
                          " --quiet --set output.checkpoint_every=5e-4 > " + out + ".log 2>&1";
  ASSERT_EQ(sh(cmd), 0) << slurp(out + ".log");
  H5File f(out + "/checkpoint.h5");
  ASSERT_GE(f.id, 0);
  EXPECT_EQ(read_int(f.id, "run/checkpoints_written"), 4);  // 0.5, 1, 1.5, 2 ms
  EXPECT_FALSE(fs::exists(out + "/checkpoint.h5.tmp"));
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["checkpoint"]["written"], 4);
}

// A full disk (/dev/full behind the file) or a checkpoint path that cannot be replaced: exit 2,
// the message names the file, nothing half-written is left under the final name.
TEST(CheckpointOutput, UnwritableOutputsExit2NamingTheFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  auto run_bar = [](const std::string& out, const std::string& extra) {
    return sh(std::string("env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ") + FDEM_BINARY + " run " +
              FDEM_TEST_DATA + "/cases/bar.json --out " + out + " --quiet " + extra + " > " + out +
              ".log 2>&1");
  };
  {
    const std::string out = tmpdir("full_history");
    fs::create_directories(out);
    fs::create_symlink("/dev/full", out + "/history.csv");
    EXPECT_EQ(run_bar(out, ""), 2);
    const std::string log = slurp(out + ".log");
    EXPECT_NE(log.find(out + "/history.csv"), std::string::npos) << log;
    EXPECT_NE(log.find("No space left on device"), std::string::npos) << log;
  }
  {
    const std::string out = tmpdir("full_checkpoint");
    fs::create_directories(out);
    fs::create_symlink("/dev/full", out + "/checkpoint.h5.tmp");
    EXPECT_EQ(run_bar(out, "--checkpoint-every 5e-4"), 2);
    const std::string log = slurp(out + ".log");
    EXPECT_NE(log.find("cannot write checkpoint '" + out + "/checkpoint.h5'"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out + "/checkpoint.h5"));
    EXPECT_FALSE(fs::exists(out + "/summary.json"));
  }
  {
    const std::string out = tmpdir("dir_checkpoint");
    fs::create_directories(out + "/checkpoint.h5");
    EXPECT_EQ(run_bar(out, "--checkpoint-every 5e-4"), 2);
    const std::string log = slurp(out + ".log");
    EXPECT_NE(log.find(out + "/checkpoint.h5"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out + "/checkpoint.h5.tmp"));
  }
}

}  // namespace
