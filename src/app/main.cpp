// fdem: command line front end. Exit status: 0 ok, 1 unexpected error, 2 bad input, 3 numerical
// failure (instability, non-finite state), 130 / 143 a run stopped by SIGINT / SIGTERM (128 +
// the signal's number) after it wrote a checkpoint and summary.json (stop reason "interrupted").
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <Kokkos_Core.hpp>
#if defined(_OPENMP)
#include <omp.h>
#endif

#include "common/error.hpp"
#include "common/huge_pages.hpp"
#include "common/kernel_times.hpp"
#include "common/view_memory.hpp"
#include "fdem_version.hpp"
#include "parallel/comm.hpp"
#include "parallel/partition.hpp"
#include "solver/ensemble.hpp"
#include "solver/run.hpp"
#ifdef FDEM_HAVE_MPI
#include "parallel/mpi/comm_mpi.hpp"
#endif

namespace {

// The processes of an MPI run (an MPI build under mpirun; null otherwise).
std::shared_ptr<fdem::Comm> g_comm;

// The cores of all OpenMP places into `set` (false: none known, or no OpenMP): the runtime took them
// from the mask the program started with (mpirun's binding of a process included), before it bound
// this thread to the first place, so they are the cores this process may use, where the mask of
// this thread may by now be one core.
bool places_mask(cpu_set_t& set) {
  CPU_ZERO(&set);
#if defined(_OPENMP)
  const int places = omp_get_num_places();
  for (int p = 0; p < places; ++p) {
    std::vector<int> ids(static_cast<size_t>(std::max(omp_get_place_num_procs(p), 0)));
    if (!ids.empty()) omp_get_place_proc_ids(p, ids.data());
    for (int id : ids)
      if (id >= 0 && id < CPU_SETSIZE) CPU_SET(id, &set);
  }
#endif
  return CPU_COUNT(&set) > 0;
}

void print_info() {
  std::printf("fdem %s\n", FDEM_VERSION_STRING);
#ifdef FDEM_HAVE_MPI
  std::printf("MPI: %s\n", fdem::mpi_description(*g_comm).c_str());
#else
  std::printf("MPI: not in this build (cmake -DFDEM_ENABLE_MPI=ON; docs/parallel.md); processes: 1\n");
#endif
  std::printf("Kokkos %d.%d.%d\n", KOKKOS_VERSION / 10000, (KOKKOS_VERSION / 100) % 100,
              KOKKOS_VERSION % 100);
  std::printf("default execution space: %s\n", Kokkos::DefaultExecutionSpace::name());
  std::printf("concurrency: %d\n", static_cast<int>(Kokkos::DefaultExecutionSpace().concurrency()));
  {
    cpu_set_t mask;
    CPU_ZERO(&mask);
    const int cores = places_mask(mask) || sched_getaffinity(0, sizeof(mask), &mask) == 0 ? CPU_COUNT(&mask) : 0;
    const char* bind = std::getenv("OMP_PROC_BIND");
    const char* places = std::getenv("OMP_PLACES");
    std::printf("cores available: %d; thread binding: OMP_PROC_BIND=%s OMP_PLACES=%s\n", cores,
                bind ? bind : "(unset)", places ? places : "(unset)");
    std::printf("huge pages for the heap: %s\n", fdem::huge_pages_state().c_str());
  }
  std::printf("enabled backends:");
#ifdef KOKKOS_ENABLE_SERIAL
  std::printf(" Serial");
#endif
#ifdef KOKKOS_ENABLE_OPENMP
  std::printf(" OpenMP");
#endif
#ifdef KOKKOS_ENABLE_CUDA
  std::printf(" CUDA");
#endif
#ifdef KOKKOS_ENABLE_HIP
  std::printf(" HIP");
#endif
  std::printf("\n");
  std::fflush(stdout);
  Kokkos::print_configuration(std::cout, false);
}

// The number of threads this process will run: --kokkos-threads=N / --kokkos-num-threads=N, else
// the leading number of OMP_NUM_THREADS, else 0 (all the cores it may use).
int requested_threads(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    for (const char* key : {"--kokkos-threads=", "--kokkos-num-threads="})
      if (a.rfind(key, 0) == 0) return std::atoi(a.c_str() + std::string(key).size());
  }
  const char* env = std::getenv("OMP_NUM_THREADS");
  return env ? std::atoi(env) : 0;
}

// OpenMP reads its binding settings when the program loads: if the user set none and the run uses
// every core it may use, its threads are spread over them (what Kokkos recommends), else Kokkos
// warns and threads may migrate. A run with fewer threads than cores is not pinned
// (OMP_PROC_BIND=false, which also keeps Kokkos quiet): pinned, its threads would sit on the first
// cores, and runs started side by side (a parameter study of one-thread runs) would all share core
// 0. True when the settings changed so that the program must start again for OpenMP to read them.
bool bind_threads(int argc, char** argv) {
  if (std::getenv("OMP_PROC_BIND")) return false;
  cpu_set_t mask;
  CPU_ZERO(&mask);
  const int cores = sched_getaffinity(0, sizeof(mask), &mask) == 0 ? CPU_COUNT(&mask) : 0;
  const int threads = requested_threads(argc, argv);
  if (threads > 0 && cores > 0 && threads < cores) {
    setenv("OMP_PROC_BIND", "false", 1);
    return false;
  }
  setenv("OMP_PROC_BIND", "spread", 1);
  setenv("OMP_PLACES", "threads", 1);
  return true;
}

// Where the user set a binding (OMP_PROC_BIND=spread, say), the OpenMP runtime has already bound
// this thread, when the program loaded, to its first place (one core), and a program started again
// by exec keeps that mask: its OpenMP would then see one core and put every thread on it (a run on
// two threads as slow as on one). Before the exec the thread gets back the cores of all the places.
void restore_affinity() {
  cpu_set_t set;
  if (places_mask(set)) sched_setaffinity(0, sizeof(set), &set);
}

// The settings read when the program loads (the thread binding; glibc's tunable for huge pages,
// common/huge_pages.hpp): where they change, start again once with them.
void reexec_with_settings(int argc, char** argv) {
  if (std::getenv("FDEM_NO_REEXEC")) return;
  if (argc > 1 && std::string(argv[1]) == "ensemble") return;  // (its realisations choose for themselves)
  bool again = bind_threads(argc, argv);
  again = fdem::ask_for_huge_pages() || again;
  if (!again) return;
  setenv("FDEM_NO_REEXEC", "1", 1);
  restore_affinity();
  execv("/proc/self/exe", argv);  // returns only on failure: then go on as we are
}

// The signal that asks a run to stop (0: none). The handler only sets it; the run loop reads it
// once per step (RunOptions::interrupt).
volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void on_interrupt(int sig) { g_interrupt = sig; }

// SIGINT and SIGTERM end a run after its current step with a checkpoint and summary.json. The
// handler is reset by its first signal, so a second one stops the process at once. A signal the
// process was started with ignored (SIGINT of a background job of a script) stays ignored.
void watch_interrupts() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART | SA_RESETHAND;
  for (int sig : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaction(sig, &sa, nullptr);
  }
}

const char* const kExitStatusHelp =
    "Exit status: 0 ok, 1 unexpected error, 2 bad input (the message names the file), 3 numerical "
    "failure, 130 / 143 a run stopped by SIGINT / SIGTERM: it finished its step and wrote "
    "OUT/checkpoint.h5 and OUT/summary.json (go on with --restart OUT/checkpoint.h5); a second "
    "signal stops it at once.";

// What the command line asks for.
struct CliOptions {
  std::string case_path, out_dir;
  std::vector<std::string> sets;
  bool quiet = false;
  bool kernel_times = false;
  bool moduli = false;
  double checkpoint_every = -1;
  std::string restart;
  int parts = 0;                 // partition
  std::string method = "metis";  // partition
  std::string snapshot;          // partition
  fdem::EnsembleOptions ensemble;
  std::string vary;              // ensemble: comma-separated sources
};

// A finite time >= 0 in seconds, with a short message (CLI11's NonNegativeNumber prints the whole
// range of a double).
CLI::Validator seconds_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < 0)
          return "'" + text + "' is not a time in seconds (give a finite number >= 0; 0: no checkpoints)";
        return "";
      },
      "SECONDS");
}

// `fdem ensemble` (src/solver/ensemble.hpp, docs/ensembles.md).
void add_ensemble_subcommand(CLI::App& app, CliOptions& o) {
  auto* ens = app.add_subcommand("ensemble",
                                 "run N realisations of a case that differ in named random sources; "
                                 "OUT/ensemble.csv and OUT/ensemble.json (docs/ensembles.md)");
  fdem::EnsembleOptions& e = o.ensemble;
  ens->add_option("case", o.case_path, "case file (JSON)")->required();
  ens->add_option("--realisations,-n", e.realisations, "number of realisations N, 1 to 100000")->required();
  ens->add_option("--out", o.out_dir, "output folder: OUT/r0000 ... and the report (required)")->required();
  ens->add_option("--vary", o.vary,
                  "comma-separated random sources: strength (the case's fracture.scatter seed), orientation "
                  "(a random rotation of the mesh), mesh (interior node jitter), velocity (the initial "
                  "velocity times 1 + size z); default: strength when the case has a scatter, else velocity");
  ens->add_option("--seed", e.seed, "ensemble seed S (each realisation's seeds derive from S and its index)");
  ens->add_option("--jobs,-j", e.jobs, "realisations run at once, each with its share of the cores (default 1)");
  ens->add_option("--threads", e.threads,
                  "threads per realisation (default: the cores available shared among the jobs; 1 makes "
                  "the ensemble reproducible bit for bit)");
  ens->add_option("--velocity-size", e.velocity_size,
                  "velocity: relative standard deviation of the speed factor, in (0, 0.1] (default 1e-6)");
  ens->add_option("--jitter", e.jitter, "mesh: node jitter amplitude in element edges, in (0, 0.5] (default 0.2)");
  ens->add_option("--set", o.sets, "override a case field in every realisation: key.path=value (repeatable)");
  ens->add_flag("--quiet", o.quiet, "no progress output");
  ens->footer("Exit status: 0 every realisation done, 1 a realisation ended with an unexpected error, 2 bad "
              "input (nothing written), 3 some realisations failed numerically (the report lists them), "
              "130 / 143 stopped by SIGINT / SIGTERM: each running realisation wrote its checkpoint, and the "
              "same command goes on from there.");
}

// The subcommands run, check and info with their options, stored into `o`.
void add_subcommands(CLI::App& app, CliOptions& o) {
  auto* run = app.add_subcommand("run", "run a case");
  run->add_option("case", o.case_path, "case file (JSON)")->required();
  run->add_option("--out", o.out_dir, "output folder (default: out/<case name>)");
  run->add_option("--set", o.sets, "override a case field: key.path=value (repeatable)");
  run->add_flag("--quiet", o.quiet, "no progress output");
  run->add_flag("--kernel-times", o.kernel_times,
                "time every Kokkos kernel by name (host backends); table at the end and in summary.json");
  run->add_option("--checkpoint-every", o.checkpoint_every,
                  "write OUT/checkpoint.h5 every this many seconds of simulated time (overrides "
                  "output.checkpoint_every; 0: none)")
      ->check(seconds_validator());
  run->add_option("--restart", o.restart,
                  "go on from a checkpoint written by --checkpoint-every or by a run stopped by SIGINT / "
                  "SIGTERM (same case and --set options)");
  run->footer(kExitStatusHelp);

  auto* check = app.add_subcommand("check", "validate a case file and its mesh without running");
  check->add_option("case", o.case_path, "case file (JSON)")->required();
  check->add_option("--set", o.sets, "override a case field: key.path=value (repeatable)");
  check->add_flag("--moduli", o.moduli,
                  "also the effective elastic moduli of the mesh with its interfaces (a static solve; "
                  "docs/case-format.md)");

  auto* part = app.add_subcommand("partition",
                                  "partition a case's elements into parts (docs/parallel.md): "
                                  "statistics, OUT/partition.json and OUT/partition.vtk");
  part->add_option("case", o.case_path, "case file (JSON)")->required();
  part->add_option("--parts", o.parts, "number of parts, in [1, number of elements]")->required();
  part->add_option("--method", o.method, "metis (default), rcb or block");
  part->add_option("--set", o.sets, "override a case field: key.path=value (repeatable)");
  part->add_option("--out", o.out_dir, "output folder (default: out/<case name>)");
  part->add_option("--snapshot", o.snapshot,
                   "also the rebalance at the last frame of this snapshots.h5 of a run of the case");

  add_ensemble_subcommand(app, o);
  app.add_subcommand("info", "print version, Kokkos version, backends and threads");
}

// A run over several processes that fails on one must end them all (the others would wait for it
// at the next exchange): MPI_Abort with the exit status. One process: the status.
int stop_all(int status) {
  if (g_comm && g_comm->size() > 1) g_comm->abort(status);
  return status;
}
std::string process_prefix() {
  return g_comm && g_comm->size() > 1 ? "process " + std::to_string(g_comm->rank()) + ": " : "";
}

// `fdem ensemble`: one process (it starts the realisations' processes itself).
int run_ensemble_command(const CliOptions& o) {
  const char* world = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!world) world = std::getenv("PMI_SIZE");
  if (world && std::atoi(world) > 1)
    throw fdem::InputError("fdem ensemble runs on one process: it starts its realisations itself; run it "
                           "without mpirun");
  fdem::EnsembleOptions e = o.ensemble;
  e.case_path = o.case_path;
  e.out_dir = o.out_dir;
  e.sets = o.sets;
  e.progress = !o.quiet;
  e.interrupt = &g_interrupt;
  std::stringstream vs(o.vary);
  for (std::string v; std::getline(vs, v, ',');)
    if (!v.empty()) e.vary.push_back(v);
  char self[4096];
  const ssize_t len = readlink("/proc/self/exe", self, sizeof self - 1);
  if (len <= 0) throw std::runtime_error("cannot find the fdem executable (/proc/self/exe)");
  e.binary.assign(self, static_cast<size_t>(len));
  return fdem::run_ensemble(e);
}

// Runs the chosen subcommand; returns the exit status (see the top of this file).
int dispatch(const CLI::App& app, const CliOptions& o) {
  try {
    if (app.got_subcommand("info")) {
      print_info();
    } else if (app.got_subcommand("ensemble")) {
      return run_ensemble_command(o);
    } else if (app.got_subcommand("check")) {
      auto report = fdem::check_case(o.case_path, o.sets, o.moduli);
      std::cout << report.dump(2) << "\n" << "case OK: " << o.case_path << "\n";
    } else if (app.got_subcommand("partition")) {
      if (g_comm && g_comm->size() > 1)  // (each process would write the same files)
        throw fdem::InputError("fdem partition runs on one process: it partitions the mesh for --parts N "
                               "processes without MPI; run it without mpirun");
      const auto r = fdem::partition_case(o.case_path, o.sets, o.parts, o.method, o.out_dir, o.snapshot);
      std::cout << fdem::partition_report_text(r) << "wrote " << r["files"][0].get<std::string>() << ", "
                << r["files"][1].get<std::string>() << "\n";
    } else if (app.got_subcommand("run")) {
      fdem::RunOptions opt;
      opt.out_dir = o.out_dir;
      opt.overrides = o.sets;
      opt.progress = !o.quiet;
      opt.checkpoint_every = o.checkpoint_every;
      opt.restart = o.restart;
      opt.interrupt = &g_interrupt;
      if (g_comm && g_comm->size() > 1) opt.comm = g_comm;
      if (o.kernel_times) fdem::kernel_times::enable();
      fdem::view_memory::enable();  // summary.json memory.views (one hook per allocation)
      const auto summary = fdem::run_case(o.case_path, opt);
      if (o.kernel_times) fdem::kernel_times::print();
      if (summary.value("stop_reason", "") == "interrupted") return 128 + summary.value("signal", 0);
    }
  } catch (const fdem::InputError& e) {
    // Name the case file in every message (mesh generator errors, for one, do not).
    std::string msg = e.what();
    if (!o.case_path.empty() && msg.find(o.case_path) == std::string::npos)
      msg = o.case_path + ": " + msg;
    // Over several processes every one reads the same input and usually fails alike: process 0
    // says it and ends them all. The others wait a moment first (their MPI_Abort would kill process
    // 0 before it has printed); one that fails alone then says it itself.
    if (g_comm && g_comm->size() > 1 && g_comm->rank() != 0) {
      std::this_thread::sleep_for(std::chrono::seconds(2));
      std::cerr << process_prefix() << "error: " << msg << "\n";
    } else {
      std::cerr << "error: " << msg << "\n";
    }
    return stop_all(2);
  } catch (const fdem::NumericalError& e) {
    std::cerr << process_prefix() << "numerical failure: " << e.what() << "\n";
    return stop_all(3);
  } catch (const std::exception& e) {
    std::cerr << process_prefix() << "unexpected error: " << e.what() << "\n";
    return stop_all(1);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  reexec_with_settings(argc, argv);
  CLI::App app{"fdem: combined continuous-discontinuous fracture simulator (2D/3D, explicit)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("fdem ") + FDEM_VERSION_STRING);
  app.footer(kExitStatusHelp);
  CliOptions opts;
  add_subcommands(app, opts);

  // Kokkos options (--kokkos-threads=N, ...) are taken out before CLI11 parses the rest.
  std::vector<char*> rest;
  rest.push_back(argv[0]);
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]).rfind("--kokkos-", 0) != 0) rest.push_back(argv[i]);
  try {
    app.parse(static_cast<int>(rest.size()), rest.data());
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  // An ensemble runs no kernel itself and starts its realisations as processes of their own: no
  // MPI and no Kokkos threads in it.
  if (app.got_subcommand("ensemble")) {
    watch_interrupts();
    return dispatch(app, opts);
  }
#ifdef FDEM_HAVE_MPI
  g_comm = fdem::mpi_start(&argc, &argv);  // before Kokkos, which may pick a GPU per process
#endif
  int status = 0;
  {
    Kokkos::ScopeGuard guard(argc, argv);
    if (app.got_subcommand("run")) watch_interrupts();
    status = dispatch(app, opts);
  }
#ifdef FDEM_HAVE_MPI
  g_comm.reset();
  fdem::mpi_finish();  // after Kokkos
#endif
  return status;
}
