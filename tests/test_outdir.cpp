// The output folder through the real command line: input files are never written to, a folder
// belongs to one run at a time (flock on OUT/.fdem.lock), a new run leaves only its own results
// there, and a full disk (a file size limit, RLIMIT_FSIZE) ends the run with an error naming the
// file, not a crash, and with only complete rows in history.csv.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/output.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kBar = std::string(FDEM_TEST_DATA) + "/cases/bar.json";
const std::string kEnv = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ";

using fdem::test::slurp;

std::string tmpdir(const std::string& name) { return fdem::test::scratch_dir("outdir", name); }

// Exit status of `sh -c cmd`; -(signal) when a signal ended it. file_limit > 0: the command runs
// with RLIMIT_FSIZE = file_limit bytes and SIGXFSZ ignored, so that a write past the limit fails
// with EFBIG as on a full disk.
int sh(const std::string& cmd, long file_limit = 0) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (file_limit > 0) {
      std::signal(SIGXFSZ, SIG_IGN);
      const rlimit r{static_cast<rlim_t>(file_limit), static_cast<rlim_t>(file_limit)};
      if (::setrlimit(RLIMIT_FSIZE, &r) != 0) ::_exit(120);
    }
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -WTERMSIG(st);
}

std::string fdem_run(const std::string& args) { return kEnv + FDEM_BINARY + " run " + args + " --quiet"; }

// Removes the folders and their logs (when the test passed: else they are left to look at).
void clean(const std::vector<std::string>& dirs) {
  if (::testing::Test::HasFailure()) return;
  for (const auto& d : dirs) {
    fs::remove_all(d);
    fs::remove(d + ".log");
    fs::remove(d + ".first.log");
  }
}

// Names of the entries of `dir`.
std::set<std::string> listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// Checks that `path` is a CSV of whole rows: every line ends with a newline and has as many
// numeric fields as the header; returns the number of data rows.
int complete_rows(const std::string& path) {
  const std::string text = slurp(path);
  EXPECT_FALSE(text.empty()) << path;
  EXPECT_EQ(text.back(), '\n') << path << " ends in a cut row";
  std::stringstream in(text);
  std::string header, line;
  std::getline(in, header);
  const long cols = std::count(header.begin(), header.end(), ',') + 1;
  int rows = 0;
  while (std::getline(in, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ',') + 1, cols) << path << " row " << rows;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) {
      size_t used = 0;
      EXPECT_NO_THROW(std::stod(cell, &used)) << cell;
      EXPECT_EQ(used, cell.size()) << path << ": '" << cell << "'";
    }
    ++rows;
  }
  return rows;
}

// ---- input files are never written to ----

// `cd cases/uniaxial_compression && fdem run case.json --out . --set parameters.cell=0.01` wrote
// the resolved case over the user's case.json.
TEST(OutDir, CaseFileInTheOutputFolderIsRefused) {
  const std::string dir = tmpdir("incase");
  fs::create_directories(dir);
  fs::copy_file(std::string(FDEM_SOURCE_DIR) + "/cases/uniaxial_compression/case.json", dir + "/case.json");
  const std::string before = slurp(dir + "/case.json");
  const int rc = sh("cd " + dir + " && " + fdem_run("case.json --out . --set parameters.cell=0.01") + " > " +
                    dir + ".log 2>&1");
  const std::string log = slurp(dir + ".log");
  EXPECT_EQ(rc, 2) << log;
  EXPECT_NE(log.find("input file 'case.json'"), std::string::npos) << log;
  EXPECT_NE(log.find("--out"), std::string::npos) << log;
  EXPECT_EQ(slurp(dir + "/case.json"), before);
  EXPECT_FALSE(fs::exists(dir + "/history.csv"));

  // the same file under another name (a link in the output folder): refused too
  const std::string out = tmpdir("inlink");
  fs::create_directories(out);
  fs::create_symlink(dir + "/case.json", out + "/case.json");
  EXPECT_EQ(sh(fdem_run(dir + "/case.json --out " + out + " --set parameters.cell=0.01") + " > " + out +
               ".log 2>&1"),
            2)
      << slurp(out + ".log");
  EXPECT_EQ(slurp(dir + "/case.json"), before);

  // a case file of another name in the output folder: the run writes its case.json beside it
  fs::remove(dir + "/case.json");
  fs::copy_file(kBar, dir + "/bar.json");
  const std::string bar = slurp(dir + "/bar.json");
  ASSERT_EQ(sh("cd " + dir + " && " + fdem_run("bar.json --out . --set time.end_time=1e-4") + " > " + dir +
               ".log 2>&1"),
            0)
      << slurp(dir + ".log");
  EXPECT_EQ(slurp(dir + "/bar.json"), bar);
  EXPECT_TRUE(fs::exists(dir + "/case.json"));
  EXPECT_TRUE(fs::exists(dir + "/summary.json"));
  clean({dir, out});
}

// ---- one run per folder ----

// The lock as another fdem run holds it: a second run is refused (exit 2) naming the folder and
// the holder's pid and leaves the folder as it was; once the holder is gone it runs.
TEST(OutDir, FolderHeldByAnotherRunIsRefused) {
  const std::string out = tmpdir("held");
  fs::create_directories(out);
  { std::ofstream(out + "/history.csv") << "earlier run\n"; }
  const int fd = ::open((out + "/.fdem.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const std::string pid = std::to_string(::getpid());
  ASSERT_EQ(::write(fd, (pid + "\n").data(), pid.size() + 1), static_cast<ssize_t>(pid.size() + 1));
  EXPECT_EQ(sh(fdem_run(kBar + " --out " + out) + " > " + out + ".log 2>&1"), 2);
  const std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("'" + out + "' is in use by another fdem run (pid " + pid + ","), std::string::npos)
      << log;
  EXPECT_EQ(slurp(out + "/history.csv"), "earlier run\n");
  EXPECT_FALSE(fs::exists(out + "/case.json"));
  ::close(fd);  // the holder ends
  EXPECT_EQ(sh(fdem_run(kBar + " --out " + out + " --set time.end_time=1e-4") + " > " + out + ".log 2>&1"), 0)
      << slurp(out + ".log");
  EXPECT_NE(slurp(out + "/history.csv"), "earlier run\n");
  clean({out});
}

// Two real runs: the second is refused while the first runs; the first, killed, leaves no stale
// lock, so a third runs.
TEST(OutDir, SecondRunIsRefusedWhileTheFirstRuns) {
  const std::string out = tmpdir("two");
  fs::create_directories(out);
  const std::string cmd = "exec " + fdem_run(kBar + " --out " + out + " --set time.end_time=0.1") + " > " +
                          out + ".first.log 2>&1";
  const pid_t first = ::fork();
  if (first == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  struct Reaper {  // the first run does not outlive the test, whatever fails
    pid_t pid;
    ~Reaper() {
      if (pid <= 0) return;
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  } reaper{first};
  // until the first run holds the folder (it writes its pid into the lock file)
  const std::string pid = std::to_string(first);
  for (int i = 0; i < 200 && slurp(out + "/.fdem.lock") != pid + "\n"; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(slurp(out + "/.fdem.lock"), pid + "\n") << slurp(out + ".first.log");
  EXPECT_EQ(sh(fdem_run(kBar + " --out " + out) + " > " + out + ".log 2>&1"), 2);
  const std::string log = slurp(out + ".log");
  EXPECT_NE(log.find("'" + out + "' is in use by another fdem run (pid " + pid + ","), std::string::npos)
      << log;
  ::kill(first, SIGKILL);
  int st = 0;
  ::waitpid(first, &st, 0);
  reaper.pid = -1;
  ASSERT_TRUE(WIFSIGNALED(st)) << "the first run ended before the second was tried";
  EXPECT_EQ(sh(fdem_run(kBar + " --out " + out + " --set time.end_time=1e-4") + " > " + out + ".log 2>&1"), 0)
      << slurp(out + ".log");
  EXPECT_GT(complete_rows(out + "/history.csv"), 50);
  clean({out});
}

// ---- a new run leaves only its own results ----

TEST(OutDir, NewRunRemovesTheResultsOfAnEarlierRunOnly) {
  const std::string out = tmpdir("rerun");
  // a run writing every kind of result
  ASSERT_EQ(sh(fdem_run(kBar + " --out " + out + " --set output.snapshot_count=2 --checkpoint-every 1e-3") +
               " > " + out + ".log 2>&1"),
            0)
      << slurp(out + ".log");
  const std::set<std::string> all = {".fdem.lock",    "case.json",    "summary.json",   "history.csv",
                                     "fragments.csv", "snapshots.h5", "snapshots.xdmf", "checkpoint.h5"};
  EXPECT_EQ(listing(out), all);
  // every file a run writes is one fdem::remove_old_outputs knows
  const auto& known = fdem::output_file_names();
  for (const auto& n : listing(out)) {
    if (n == fdem::OutputLock::kName) continue;
    EXPECT_NE(std::find(known.begin(), known.end(), n), known.end()) << n;
  }
  // leftovers of a killed run, and files that are not fdem's
  { std::ofstream(out + "/checkpoint.h5.tmp") << "partial"; }
  { std::ofstream(out + "/notes.txt") << "mine"; }
  { std::ofstream(out + "/history.csv.bak") << "mine"; }
  fs::create_directories(out + "/plots");

  // a restart keeps the results and continues them
  ASSERT_EQ(sh(fdem_run(kBar + " --out " + out + " --set output.snapshot_count=2 --restart " + out +
                        "/checkpoint.h5") +
               " > " + out + ".log 2>&1"),
            0)
      << slurp(out + ".log");
  EXPECT_TRUE(fs::exists(out + "/snapshots.h5"));
  EXPECT_TRUE(fs::exists(out + "/fragments.csv"));
  // a link under the name of a result is the user's: left alone
  fs::remove(out + "/fragments.csv");
  fs::create_symlink(out + "/notes.txt", out + "/fragments.csv");

  // a new run without snapshots, fragments or checkpoints
  ASSERT_EQ(sh(fdem_run(kBar + " --out " + out + " --set output.fragments=false --set time.end_time=1e-4") +
               " > " + out + ".log 2>&1"),
            0)
      << slurp(out + ".log");
  const std::set<std::string> now = {".fdem.lock", "case.json",       "summary.json", "history.csv",
                                     "notes.txt",  "history.csv.bak", "plots",        "fragments.csv"};
  EXPECT_EQ(listing(out), now);
  EXPECT_EQ(slurp(out + "/notes.txt"), "mine");
  EXPECT_TRUE(fs::is_symlink(out + "/fragments.csv"));
  clean({out});
}

// A new run refused before its first step (a mesh that would not fit in memory) leaves the results of
// the earlier run in the folder as they were: nothing is removed before the mesh is there.
TEST(OutDir, RefusedRunKeepsTheResultsOfAnEarlierRun) {
  const std::string out = tmpdir("refused");
  ASSERT_EQ(sh(fdem_run(kBar + " --out " + out + " --set time.end_time=1e-4") + " > " + out + ".log 2>&1"), 0)
      << slurp(out + ".log");
  const std::string history = slurp(out + "/history.csv"), summary = slurp(out + "/summary.json");
  // a memory budget of 1 kB: the mesh estimate is refused (before meshing)
  EXPECT_EQ(sh("FDEM_MEMORY_LIMIT_GB=1e-6 " + fdem_run(kBar + " --out " + out) + " > " + out + ".log 2>&1"), 2)
      << slurp(out + ".log");
  EXPECT_NE(slurp(out + ".log").find("GiB"), std::string::npos) << slurp(out + ".log");
  EXPECT_EQ(slurp(out + "/history.csv"), history);
  EXPECT_EQ(slurp(out + "/summary.json"), summary);
  clean({out});
}

// ---- a full disk ----

// Snapshots, a checkpoint, then history.csv cannot be written (file size limit): exit 2, not a
// signal (HDF5's exit handler crashed with SIGSEGV after the message), the message names the
// file, history.csv holds whole rows only.
TEST(OutDir, FullDiskIsAnErrorNamingTheFile) {
  struct Case {
    const char* name;
    std::string args;
    long limit;
    const char* file;
  };
  const std::vector<Case> cases = {
      {"snapshots", "--set output.snapshot_count=50", 200000, "/snapshots.h5'"},
      {"checkpoint", "--set output.history_rows=20 --checkpoint-every 5e-4", 30000, "/checkpoint.h5'"},
      {"history", "--set output.fragments=false", 5000, "/history.csv'"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string out = tmpdir(std::string("full_") + c.name);
    const int rc = sh(fdem_run(kBar + " --out " + out + " " + c.args) + " > " + out + ".log 2>&1", c.limit);
    const std::string log = slurp(out + ".log");
    EXPECT_EQ(rc, 2) << log;
    EXPECT_NE(log.find("'" + out + c.file), std::string::npos) << log;
    EXPECT_NE(log.find("File too large"), std::string::npos) << log;
    EXPECT_EQ(log.find("\n", log.find("error: ")), log.size() - 1) << "one line:\n" << log;
    EXPECT_GE(complete_rows(out + "/history.csv"), 3);
    if (fs::exists(out + "/fragments.csv")) complete_rows(out + "/fragments.csv");
    EXPECT_FALSE(fs::exists(out + "/summary.json"));
    EXPECT_FALSE(fs::exists(out + "/checkpoint.h5.tmp"));
    clean({out});
  }
}

}  // namespace
