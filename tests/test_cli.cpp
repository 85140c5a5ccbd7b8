// End to end through the real command line: a small case runs, and what it wrote (history.csv,
// summary.json, snapshots.h5/.xdmf) is read back and checked; `fdem check` accepts a good case and
// rejects a bad one with exit status 2.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include "common/huge_pages.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;

int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

using fdem::test::slurp;

std::string tmpdir(const std::string& name) { return fdem::test::scratch_dir("cli", name); }

const std::string kBar = std::string(FDEM_TEST_DATA) + "/cases/bar.json";

TEST(Cli, RunWritesHistorySummaryAndSnapshots) {
  const std::string out = tmpdir("bar");
  const std::string cmd = std::string(FDEM_BINARY) + " run " + kBar + " --out " + out +
                          " --quiet --set output.snapshot_count=4 > " + out + ".log 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out + ".log");

  // summary: counts of a 10 x 1 crossed rectangle with interfaces everywhere
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(s["counts"]["elements"], 40);
  EXPECT_EQ(s["counts"]["nodes"], 120);
  EXPECT_EQ(s["counts"]["interfaces"], 4 * 10 + 10 * 0 + 1 * 9);
  EXPECT_GT(s["steps"].get<long>(), 100);
  EXPECT_NEAR(s["end_time_s"].get<double>(), 2e-3, 1e-5);
  EXPECT_GT(s["time_step"]["dt_s"].get<double>(), 0.0);
  EXPECT_LE(s["time_step"]["dt_s"].get<double>(), 0.5 * s["time_step"]["dt_critical_s"].get<double>() * (1 + 1e-12));

  // history: header with units, about 100 rows, time increasing, energy balance small
  std::ifstream h(out + "/history.csv");
  std::string header, line;
  std::getline(h, header);
  EXPECT_NE(header.find("time [s]"), std::string::npos);
  EXPECT_NE(header.find("right_reaction_x [N]"), std::string::npos);
  EXPECT_NE(header.find("energy_error [J]"), std::string::npos);
  int rows = 0;
  double tprev = -1, tlast = 0, werr = 0, wext = 0;
  while (std::getline(h, line)) {
    std::vector<double> v;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_GE(v.size(), 10u);
    EXPECT_GT(v[0], tprev);
    tprev = tlast = v[0];
    werr = v[v.size() - 3];
    wext = v[v.size() - 4];
    ++rows;
  }
  EXPECT_GE(rows, 95);
  EXPECT_LE(rows, 105);
  EXPECT_NEAR(tlast, 2e-3, 5e-5);
  EXPECT_GT(wext, 0.0);
  EXPECT_LT(std::fabs(werr), 0.01 * wext);

  // snapshots: the checker script validates every XDMF reference against the HDF5 file
  ASSERT_TRUE(fs::exists(out + "/snapshots.xdmf"));
  ASSERT_TRUE(fs::exists(out + "/snapshots.h5"));
  if (run("/usr/bin/python3 -c 'import h5py' > /dev/null 2>&1") == 0) {
    EXPECT_EQ(run("/usr/bin/python3 " + std::string(FDEM_SOURCE_DIR) + "/scripts/check_snapshots.py " + out +
                  " > " + out + ".check 2>&1"), 0)
        << slurp(out + ".check");
  }
  fs::remove_all(out);
  fs::remove(out + ".check");
  fs::remove(out + ".log");
}

// A run with progress on ends with its key results, taken from its summary, after the paths of its
// outputs (issue 51, item 18: they were only inside summary.json); its summary's phases say they
// are estimates (item 8).
TEST(Cli, RunWithProgressEndsWithItsKeyResults) {
  const std::string out = tmpdir("key_results");
  ASSERT_EQ(run(std::string(FDEM_BINARY) + " run " + kBar + " --out " + out + " > " + out + ".log 2>&1"), 0)
      << slurp(out + ".log");
  const std::string log = slurp(out + ".log");
  const size_t paths = log.find("  summary:   " + out + "/summary.json\n");
  const size_t key = log.find("fdem: key results of bar:\n");
  ASSERT_NE(paths, std::string::npos) << log;
  ASSERT_NE(key, std::string::npos) << log;
  EXPECT_LT(paths, key) << log;
  // after the heading only its lines, to the end: the interfaces and fragments, the energies
  const std::string tail = log.substr(key);
  const auto s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const std::string failed =
      "\n  interfaces: " + std::to_string(s["interfaces_failed"].get<long>()) + " failed";
  const std::string fragments =
      "; fragments: " + std::to_string(s["fragments"]["count"].get<long>()) + ", the largest ";
  EXPECT_NE(tail.find(failed), std::string::npos) << tail;
  EXPECT_NE(tail.find(fragments), std::string::npos) << tail;
  EXPECT_NE(tail.find("\n  energy: external work "), std::string::npos) << tail;
  std::stringstream lines(tail.substr(tail.find('\n') + 1));
  for (std::string line; std::getline(lines, line);) EXPECT_EQ(line.rfind("  ", 0), 0u) << tail;
  EXPECT_TRUE(s["phases"].value("estimated", false)) << s["phases"].dump();
  fs::remove_all(out);
  fs::remove(out + ".log");
}

TEST(Cli, CheckAcceptsGoodCaseAndRejectsBadOne) {
  const std::string dir = tmpdir("check");
  fs::create_directories(dir);
  EXPECT_EQ(run(std::string(FDEM_BINARY) + " check " + kBar + " > " + dir + "/ok.log 2>&1"), 0);
  EXPECT_NE(slurp(dir + "/ok.log").find("case OK"), std::string::npos);
  // nu = 0.5 is out of range: exit 2 and a message naming the file, the key and the range
  EXPECT_EQ(run(std::string(FDEM_BINARY) + " check " + kBar +
                " --set materials.concrete.nu=0.5 > " + dir + "/bad.log 2>&1"), 2);
  const std::string msg = slurp(dir + "/bad.log");
  EXPECT_NE(msg.find("bar.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("materials.concrete.nu"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.5"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(Cli, UnstableRunStopsWithExitStatus3) {
  const std::string out = tmpdir("unstable");
  // far above the stable step: the solver's own check must stop it
  const int rc = run(std::string(FDEM_BINARY) + " run " + kBar + " --out " + out +
                     " --quiet --set time.safety_factor=2 --set damping.local=0 > " + out + ".log 2>&1");
  EXPECT_EQ(rc, 3) << slurp(out + ".log");
  EXPECT_NE(slurp(out + ".log").find("step"), std::string::npos);
  fs::remove_all(out);
  fs::remove(out + ".log");
}

// Thread binding (src/app/main.cpp): with no OMP_PROC_BIND of the user's, a run that uses every
// core it may use spreads its threads over them (pinned); a run with fewer threads than cores is
// not pinned, so that one-thread runs started side by side do not all share core 0. Checked in one
// process's affinity of a single core (taskset), where one thread is every core, and of all cores.
TEST(Cli, OneThreadRunsAreNotAllPinnedToTheFirstCore) {
  const std::string out = tmpdir("binding");
  fs::create_directories(out);
  // every run gets a known set of cores with taskset (this test process's threads may be pinned:
  // the test preset binds them, and a child inherits its parent thread's cores)
  const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  const std::string all = "taskset -c 0-" + std::to_string(cores - 1);
  const std::string info = " env -u OMP_PROC_BIND -u OMP_PLACES -u FDEM_NO_REEXEC ";
  ASSERT_EQ(run(all + info + "OMP_NUM_THREADS=1 " + FDEM_BINARY + " info > " + out + "/one.txt 2>&1"), 0);
  const std::string one = slurp(out + "/one.txt");
  EXPECT_NE(one.find("cores available: " + std::to_string(cores) + ";"), std::string::npos) << one;
  if (cores > 1) {
    EXPECT_NE(one.find("OMP_PROC_BIND=false"), std::string::npos) << one;
  }
  ASSERT_EQ(
      run("taskset -c 0" + info + "OMP_NUM_THREADS=1 " + FDEM_BINARY + " info > " + out + "/pinned.txt 2>&1"),
      0);
  const std::string pinned = slurp(out + "/pinned.txt");
  EXPECT_NE(pinned.find("cores available: 1;"), std::string::npos) << pinned;
  EXPECT_NE(pinned.find("OMP_PROC_BIND=spread OMP_PLACES=threads"), std::string::npos) << pinned;
  ASSERT_EQ(run(all + info + "OMP_NUM_THREADS=" + std::to_string(cores) + " " + FDEM_BINARY + " info > " +
                out + "/all.txt 2>&1"),
            0);
  const std::string all_txt = slurp(out + "/all.txt");
  EXPECT_NE(all_txt.find("OMP_PROC_BIND=spread OMP_PLACES=threads"), std::string::npos) << all_txt;
  EXPECT_EQ(all_txt.find("OMP_PROC_BIND environment variable not set"), std::string::npos) << all_txt;
  EXPECT_EQ(one.find("OMP_PROC_BIND environment variable not set"), std::string::npos) << one;
  fs::remove_all(out);
}

// A binding of the user's (OMP_PROC_BIND=spread) survives the start again for huge pages: the
// OpenMP runtime binds the first thread to one core when the program loads, and the program
// started again used to inherit that one core, so that all its threads ran on it (two threads as
// slow as one). `fdem info` counts the cores of the OpenMP places it sees.
TEST(Cli, AUsersBindingKeepsEveryCoreThroughTheStartAgain) {
  const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  if (cores < 2) GTEST_SKIP() << "one core";
  const std::string out = tmpdir("userbinding");
  fs::create_directories(out);
  const std::string all = "taskset -c 0-" + std::to_string(cores - 1);
  const std::string env = " env -u FDEM_NO_REEXEC -u GLIBC_TUNABLES -u FDEM_HUGE_PAGES OMP_PROC_BIND=spread "
                          "OMP_PLACES=threads OMP_NUM_THREADS=" + std::to_string(cores) + " ";
  ASSERT_EQ(run(all + env + FDEM_BINARY + " info > " + out + "/spread.txt 2>&1"), 0);
  const std::string txt = slurp(out + "/spread.txt");
  EXPECT_NE(txt.find("cores available: " + std::to_string(cores) + ";"), std::string::npos) << txt;
  fs::remove_all(out);
}

// Huge pages for the heap (src/common/huge_pages.hpp): where the kernel gives transparent huge
// pages on request (mode madvise), fdem asks for them through glibc's tunable and starts again with
// it; not with FDEM_HUGE_PAGES=0, nor over the user's own setting of the tunable. `fdem info` says
// which.
TEST(Cli, HugePagesAskedWhereTheKernelGivesThemOnRequest) {
  const std::string out = tmpdir("hugepages");
  fs::create_directories(out);
  const std::string mode = fdem::transparent_huge_pages_mode();
  const std::string clean = "env -u GLIBC_TUNABLES -u FDEM_NO_REEXEC -u FDEM_HUGE_PAGES ";
  auto info = [&](const std::string& env, const std::string& name) {
    EXPECT_EQ(run(clean + env + " " + FDEM_BINARY + " info > " + out + "/" + name + " 2>&1"), 0);
    return slurp(out + "/" + name);
  };
  const std::string asked = info("", "asked.txt"), off = info("FDEM_HUGE_PAGES=0", "off.txt"),
                    own = info("GLIBC_TUNABLES=glibc.malloc.hugetlb=0", "own.txt");
  if (mode == "madvise") {
    EXPECT_NE(asked.find("huge pages for the heap: on (glibc.malloc.hugetlb=1, kernel mode madvise)"),
              std::string::npos)
        << asked;
    EXPECT_NE(off.find("huge pages for the heap: off (kernel mode madvise"), std::string::npos) << off;
    EXPECT_NE(own.find("huge pages for the heap: off (kernel mode madvise"), std::string::npos) << own;
  } else if (mode == "always") {
    EXPECT_NE(asked.find("huge pages for the heap: on (kernel mode always)"), std::string::npos) << asked;
  } else {
    EXPECT_NE(asked.find("huge pages for the heap: off"), std::string::npos) << asked;
  }
  fs::remove_all(out);
}

// The heap's free pages back to the kernel (release_free_heap, src/common/huge_pages.hpp), as the
// run does once the set-up has freed its mesh: freed blocks below one still in use stay resident
// (free() trims only the top of the heap) until it is called.
TEST(Cli, FreedHeapGivenBackToTheKernel) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator: glibc's malloc_trim does not see its heap";
#elif defined(__GLIBC__)
  constexpr int kBlocks = 48 * 1024;  // 48 MB in blocks of 1 kB, kept in the heap (below mmap's threshold)
  std::vector<char*> blocks(kBlocks);
  for (char*& b : blocks) {
    b = new char[1024];
    for (int i = 0; i < 1024; i += 64) b[i] = static_cast<char>(i);  // resident
  }
  char* pin = new char[1024];  // above them: the top of the heap stays in use
  pin[0] = 1;
  for (char* b : blocks) delete[] b;
  const double released = fdem::release_free_heap();
  delete[] pin;
  EXPECT_GT(released, 24e6) << "bytes given back";
  EXPECT_LT(released, 1e9);
#else
  GTEST_SKIP() << "not glibc: nothing to give back";
#endif
}

}  // namespace
