// Restart and interruption through the real command line (issue 22): a run killed (SIGKILL) after a
// checkpoint and restarted continues every output file (history.csv, fragments.csv, snapshots,
// summary) as the uninterrupted run wrote it; SIGTERM / SIGINT end a run after its step with a
// checkpoint, summary.json (stop reason "interrupted") and exit status 143 / 130; a checkpoint
// whose data or header were altered is refused with exit status 2 naming the file and the dataset.
//
// Case: the particle impact (cases/particle_impact_2d) at 10 mm elements (80 elements, 108
// interfaces), 20 m/s, to 0.205 ms (about 2700 steps, under a second on one thread): the particle
// breaks into tens of fragments, so fragments.csv changes from row to row.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kCase = std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_2d/case.json";
const std::string kSets = " --set parameters.h=0.01 --set parameters.speed=20 --set parameters.duration=2e-4";

int status_of(int rc) {
  if (WIFEXITED(rc)) return WEXITSTATUS(rc);
  return WIFSIGNALED(rc) ? 128 + WTERMSIG(rc) : -1;
}

using fdem::test::slurp;

std::string tmpdir(const std::string& name) { return fdem::test::scratch_dir("restart", name); }

// The shell command of a one-thread run of the case into `out` (log: out.log).
std::string run_cmd(const std::string& out, const std::string& extra, const std::string& env = "") {
  return "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false OMP_WAIT_POLICY=passive " + env + " " + FDEM_BINARY +
         " run " + kCase + " --out " + out + " --quiet" + kSets + " " + extra + " > " + out + ".log 2>&1";
}

int run(const std::string& out, const std::string& extra = "", const std::string& env = "") {
  return status_of(std::system(run_cmd(out, extra, env).c_str()));
}

size_t lines(const std::string& path) {
  const std::string s = slurp(path);
  size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// The snapshot frames: names and their positions, velocities, fragment ids (bits).
struct Frames {
  std::vector<std::string> names;
  std::vector<std::vector<double>> x, v;
  std::vector<std::vector<int>> fragment;
};

Frames frames(const std::string& file) {
  Frames r;
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << file;
  if (f < 0) return r;
  H5G_info_t info;
  H5Gget_info(f, &info);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char buf[256];
    H5Lget_name_by_idx(f, "/", H5_INDEX_NAME, H5_ITER_INC, i, buf, sizeof buf, H5P_DEFAULT);
    if (std::string(buf).rfind("step_", 0) == 0) r.names.push_back(buf);
  }
  auto read = [&](const std::string& name, hid_t type, auto& out) {
    hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
    if (d < 0) return;
    hid_t s = H5Dget_space(d);
    out.resize(static_cast<size_t>(H5Sget_simple_extent_npoints(s)));
    H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
    H5Sclose(s);
    H5Dclose(d);
  };
  for (const auto& g : r.names) {
    r.x.emplace_back();
    r.v.emplace_back();
    r.fragment.emplace_back();
    read(g + "/coordinates", H5T_NATIVE_DOUBLE, r.x.back());
    read(g + "/velocity", H5T_NATIVE_DOUBLE, r.v.back());
    read(g + "/fragment", H5T_NATIVE_INT, r.fragment.back());
  }
  H5Fclose(f);
  return r;
}

// The summary's fields that do not depend on wall time or on how the run was split.
nlohmann::json results(const std::string& out) {
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  return {{"steps", s["steps"]},
          {"end_time_s", s["end_time_s"]},
          {"energy", s["energy"]},
          {"fragments", s["fragments"]},
          {"results", s["results"]},
          {"stop_reason", s["stop_reason"]},
          {"interfaces_failed", s["interfaces_failed"]}};
}

// Every output of a run against the uninterrupted one's, bit for bit (one thread); "" when equal.
std::string differ(const std::string& ref, const std::string& out) {
  for (const char* f : {"history.csv", "fragments.csv", "snapshots.xdmf"})
    if (slurp(ref + "/" + f) != slurp(out + "/" + f))
      return std::string(f) + " differs (" + std::to_string(lines(ref + "/" + f)) + " vs " +
             std::to_string(lines(out + "/" + f)) + " lines)";
  const Frames a = frames(ref + "/snapshots.h5"), b = frames(out + "/snapshots.h5");
  if (a.names != b.names) return "snapshot frames differ";
  for (size_t k = 0; k < a.names.size(); ++k)
    if (a.x[k] != b.x[k] || a.v[k] != b.v[k] || a.fragment[k] != b.fragment[k])
      return "frame " + a.names[k] + " differs";
  if (results(ref) != results(out))
    return "summary differs: " + results(ref).dump() + " vs " + results(out).dump();
  return "";
}

class Restart : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ref_ = tmpdir("reference");
    ASSERT_EQ(run(ref_), 0) << slurp(ref_ + ".log");
  }
  static void TearDownTestSuite() {
    fs::remove_all(ref_);
    fs::remove(ref_ + ".log");
  }
  static std::string ref_;
};
std::string Restart::ref_;

// Killed (SIGKILL) in the middle of writing its 3rd checkpoint (0.12 ms): the 2nd (0.08 ms) stays,
// and every file holds rows or frames the killed run wrote after it. The restart keeps the rows up
// to the checkpoint, drops the later ones and writes them again: all files as the uninterrupted
// run's. (Before, fragments.csv was started anew: it kept only the rows after the checkpoint.)
TEST_F(Restart, KilledRunContinuesEveryOutputFile) {
  ASSERT_EQ(lines(ref_ + "/history.csv"), 202u);  // header + 200 rows + the final one
  ASSERT_EQ(lines(ref_ + "/fragments.csv"), 202u);
  const auto ref_summary = nlohmann::json::parse(slurp(ref_ + "/summary.json"));
  ASSERT_GT(ref_summary["fragments"]["count"].get<int>(), 10);

  const std::string out = tmpdir("killed");
  ASSERT_EQ(run(out, "--checkpoint-every 4e-5", "FDEM_TEST_CHECKPOINT_KILL=during:3"), 128 + SIGKILL)
      << slurp(out + ".log");
  ASSERT_TRUE(fs::exists(out + "/checkpoint.h5"));
  EXPECT_FALSE(fs::exists(out + "/summary.json"));
  // the killed run got to 0.12 ms: about 117 rows, 58 of them after the checkpoint at 0.08 ms
  const size_t killed_rows = lines(out + "/fragments.csv");
  EXPECT_GT(killed_rows, 100u);
  EXPECT_LT(killed_rows, 140u);
  EXPECT_EQ(lines(out + "/history.csv"), killed_rows);

  ASSERT_EQ(run(out, "--checkpoint-every 4e-5 --restart " + out + "/checkpoint.h5"), 0)
      << slurp(out + ".log");
  EXPECT_EQ(differ(ref_, out), "");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["checkpoint"]["written"], 5);  // 2 before the kill, 3 after the restart
  EXPECT_NEAR(s["checkpoint"]["restarted_from"]["time_s"].get<double>(), 8e-5, 1e-7);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

// Starts a run in the background; returns its process id (the fdem process itself: sh execs env,
// env execs fdem).
pid_t start(const std::string& out, const std::string& extra) {
  const std::string cmd = "exec " + run_cmd(out, extra);
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// A signal once the run has written `rows` history rows; returns the exit status (1000 + the
// signal when the process was killed by a signal instead of exiting) and the rows there were when
// the signal was sent.
int signal_after_rows(const std::string& out, const std::string& extra, int sig, size_t rows, size_t& seen) {
  const pid_t pid = start(out, extra);
  if (pid < 0) return -1;
  const auto t0 = std::chrono::steady_clock::now();
  seen = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    seen = fs::exists(out + "/history.csv") ? lines(out + "/history.csv") : 0;
    if (seen >= rows + 1) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, sig);
  int rc = 0;
  waitpid(pid, &rc, 0);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : WIFSIGNALED(rc) ? 1000 + WTERMSIG(rc) : -1;
}

// SIGTERM while stepping (no checkpoint interval): the run finishes its step, writes a checkpoint
// and summary.json (stop reason "interrupted"), says so and exits with 143; the restart from that
// checkpoint completes with the uninterrupted run's files.
TEST_F(Restart, SigtermWritesCheckpointSummaryAndExits143) {
  const std::string out = tmpdir("sigterm");
  size_t seen = 0;
  ASSERT_EQ(signal_after_rows(out, "", SIGTERM, 5, seen), 128 + SIGTERM) << slurp(out + ".log");
  const std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("interrupted by SIGTERM"), std::string::npos) << log;
  EXPECT_NE(log.find("--restart " + out + "/checkpoint.h5"), std::string::npos) << log;
  ASSERT_TRUE(fs::exists(out + "/checkpoint.h5"));
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["stop_reason"], "interrupted");
  EXPECT_EQ(s["signal"], SIGTERM);
  EXPECT_EQ(s["checkpoint"]["written"], 1);
  // stopped early: fewer rows than the whole run's 201
  const size_t rows_at_stop = lines(out + "/history.csv") - 1;
  EXPECT_GE(rows_at_stop, seen - 1);
  EXPECT_LT(rows_at_stop, 150u) << "the run was nearly done before the signal";
  EXPECT_LT(s["steps"].get<long>(),
            nlohmann::json::parse(slurp(ref_ + "/summary.json"))["steps"].get<long>());

  ASSERT_EQ(run(out, "--restart " + out + "/checkpoint.h5"), 0) << slurp(out + ".log");
  EXPECT_EQ(results(out)["stop_reason"], "end_time");
  EXPECT_EQ(differ(ref_, out), "");
  fs::remove_all(out);
  fs::remove(out + ".log");
}

TEST_F(Restart, SigintExits130WithCheckpoint) {
  const std::string out = tmpdir("sigint");
  size_t seen = 0;
  ASSERT_EQ(signal_after_rows(out, "--checkpoint-every 1e-3", SIGINT, 3, seen), 128 + SIGINT)
      << slurp(out + ".log");
  EXPECT_NE(slurp(out + ".log").find("interrupted by SIGINT"), std::string::npos) << slurp(out + ".log");
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["stop_reason"], "interrupted");
  EXPECT_EQ(s["signal"], SIGINT);
  hid_t f = H5Fopen((out + "/checkpoint.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  long long step = -1;
  hid_t a = H5Aopen(f, "step", H5P_DEFAULT);
  H5Aread(a, H5T_NATIVE_LLONG, &step);
  H5Aclose(a);
  H5Fclose(f);
  EXPECT_EQ(step, s["steps"].get<long long>());  // the checkpoint is of the moment it stopped
  fs::remove_all(out);
  fs::remove(out + ".log");
}

// A checkpoint with one byte of a dataset's data flipped reads back without an HDF5 error (the
// value is just different); its checksum refuses it: exit 2 naming the file and the dataset. An
// altered header attribute fails the root checksum. Checkpoints of earlier versions (without
// checksums) are refused.
TEST_F(Restart, CorruptedCheckpointIsRefusedNamingTheDataset) {
  const std::string out = tmpdir("corrupt");
  const std::string sets = "--set time.max_steps=300 --checkpoint-every 1e-5";
  ASSERT_EQ(run(out, sets), 0) << slurp(out + ".log");
  const std::string good = out + "/checkpoint.h5";
  ASSERT_TRUE(fs::exists(good));

  // the byte: in the middle of model/x (node coordinates)
  const std::string bad = out + "/flipped.h5";
  fs::copy_file(good, bad);
  haddr_t offset = HADDR_UNDEF;
  std::vector<double> before, after;
  auto read_x = [](const std::string& file, std::vector<double>& x, haddr_t* where) {
    hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, "model/x", H5P_DEFAULT);
    hid_t s = H5Dget_space(d);
    x.resize(static_cast<size_t>(H5Sget_simple_extent_npoints(s)));
    H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, x.data());
    if (where) *where = H5Dget_offset(d);
    H5Sclose(s);
    H5Dclose(d);
    H5Fclose(f);
  };
  read_x(bad, before, &offset);
  ASSERT_NE(offset, HADDR_UNDEF);
  ASSERT_GT(before.size(), 100u);
  {
    std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
    const auto at = static_cast<std::streamoff>(offset + 8 * (before.size() / 2) + 6);
    f.seekg(at);
    char c = 0;
    f.read(&c, 1);
    c = static_cast<char>(c ^ 0x10);
    f.seekp(at);
    f.write(&c, 1);
  }
  read_x(bad, after, nullptr);
  ASSERT_EQ(after.size(), before.size());
  EXPECT_NE(after[before.size() / 2], before[before.size() / 2]);  // HDF5 reads the flipped value

  EXPECT_EQ(run(out, sets + " --restart " + bad), 2);
  std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("restart file '" + bad + "' is damaged: dataset 'model/x' fails its checksum"),
            std::string::npos)
      << log;

  // the header: the time attribute changed through HDF5 (a valid file otherwise)
  const std::string hdr = out + "/header.h5";
  fs::copy_file(good, hdr);
  {
    hid_t f = H5Fopen(hdr.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    hid_t a = H5Aopen(f, "time", H5P_DEFAULT);
    double t = 0;
    H5Aread(a, H5T_NATIVE_DOUBLE, &t);
    t *= 1.5;
    H5Awrite(a, H5T_NATIVE_DOUBLE, &t);
    H5Aclose(a);
    H5Fclose(f);
  }
  EXPECT_EQ(run(out, sets + " --restart " + hdr), 2);
  log = slurp(out + ".log");
  EXPECT_NE(log.find("restart file '" + hdr + "' is damaged: the header"), std::string::npos) << log;

  // a checkpoint of format version 2 (no checksums) is refused, saying why
  const std::string v2 = out + "/version2.h5";
  fs::copy_file(good, v2);
  {
    hid_t f = H5Fopen(v2.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    hid_t a = H5Aopen(f, "version", H5P_DEFAULT);
    const int version = 2;
    H5Awrite(a, H5T_NATIVE_INT, &version);
    H5Aclose(a);
    H5Fclose(f);
  }
  EXPECT_EQ(run(out, sets + " --restart " + v2), 2);
  log = slurp(out + ".log");
  EXPECT_NE(log.find("restart file '" + v2 +
                     "' is a checkpoint of format version 2; this fdem reads versions 3 to 4 "
                     "(earlier versions carry no checksum"),
            std::string::npos)
      << log;

  // the checkpoint as written restarts
  EXPECT_EQ(run(out, sets + " --restart " + good), 0) << slurp(out + ".log");
  fs::remove_all(out);
  fs::remove(out + ".log");
}

}  // namespace
