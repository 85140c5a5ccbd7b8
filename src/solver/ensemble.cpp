// `fdem ensemble` (ensemble.hpp): the options checked before anything is written, each
// realisation's seeds and settings, the realisations run J at a time as child processes of the
// fdem binary (each in its own folder, its own process group, stopped with a checkpoint when the
// ensemble is), and what a second invocation of the same command finds done and goes on from.
#include "solver/ensemble.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "common/error.hpp"
#include "common/random.hpp"
#include "io/case.hpp"
#include "io/output.hpp"

namespace fdem {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string fixed3(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

// A standard normal number from a stream (Box-Muller; the project's own uniforms, so every
// machine draws the same).
double normal(SplitMixStream& rng) {
  const double u1 = 1 - rng.uniform(), u2 = rng.uniform();
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

// A uniformly distributed rotation: 2D an angle in [-180, 180); 3D Shoemake's random unit
// quaternion as an axis and an angle in [0, 180].
json random_rotation(std::uint64_t seed, int dim, double& angle_deg) {
  SplitMixStream rng(seed);
  if (dim == 2) {
    angle_deg = 360 * rng.uniform() - 180;
    return {{"angle_deg", angle_deg}};
  }
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  double q[4] = {std::sqrt(1 - u1) * std::sin(2 * M_PI * u2), std::sqrt(1 - u1) * std::cos(2 * M_PI * u2),
                 std::sqrt(u1) * std::sin(2 * M_PI * u3), std::sqrt(u1) * std::cos(2 * M_PI * u3)};
  if (q[3] < 0)
    for (double& v : q) v = -v;
  const double s = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
  angle_deg = 2 * std::atan2(s, q[3]) * 180 / M_PI;
  json axis = s > 0 ? json::array({q[0] / s, q[1] / s, q[2] / s}) : json::array({0, 0, 1});
  return {{"angle_deg", angle_deg}, {"axis", axis}};
}

const std::vector<std::string> kSources = {"strength", "orientation", "mesh", "velocity"};

}  // namespace

const std::vector<std::string>& ensemble_sources() { return kSources; }

std::uint64_t ensemble_seed(std::uint64_t S, long i, const std::string& source) {
  const auto tag = static_cast<std::uint64_t>(
      std::find(kSources.begin(), kSources.end(), source) - kSources.begin() + 1);
  return splitmix64(splitmix64(S) ^ splitmix64(tag << 40 ^ static_cast<std::uint64_t>(i))) & 0xffffffffULL;
}

Realisation plan_realisation(const EnsembleOptions& o, long i, int dim) {
  Realisation r;
  r.index = i;
  for (const std::string& src : kSources) {
    if (std::find(o.vary.begin(), o.vary.end(), src) == o.vary.end()) continue;
    const std::uint64_t s = ensemble_seed(o.seed, i, src);
    r.seeds.emplace_back(src, s);
    if (src == "strength") {
      r.sets.push_back("fracture.scatter.seed=" + std::to_string(s));
    } else if (src == "orientation") {
      double angle = 0;
      r.sets.push_back("mesh.rotation=" + random_rotation(s, dim, angle).dump());
      r.values.emplace_back("rotation_deg", angle);
    } else if (src == "mesh") {
      r.sets.push_back("mesh.jitter=" + json{{"amplitude", o.jitter}, {"seed", s}}.dump());
    } else {
      SplitMixStream rng(s);
      const double f = 1 + o.velocity_size * normal(rng);
      r.sets.push_back("boundary.initial_velocity_factor=" + exact_number(f));
      r.values.emplace_back("velocity_factor", f);
    }
  }
  return r;
}

namespace {

// ---- checks before anything is written ----

void check_options(EnsembleOptions& o, const Case& c) {
  if (o.realisations < 1 || o.realisations > 100000)
    throw InputError("--realisations: " + std::to_string(o.realisations) +
                     " is out of range (allowed: 1 to 100000)");
  if (o.jobs < 1 || o.jobs > 1024)
    throw InputError("--jobs: " + std::to_string(o.jobs) + " is out of range (allowed: 1 to 1024)");
  if (o.threads < 0 || o.threads > 4096)
    throw InputError("--threads: " + std::to_string(o.threads) + " is out of range (allowed: 1 to 4096; 0: the "
                     "cores available shared among the jobs)");
  if (!(o.velocity_size > 0 && o.velocity_size <= 0.1))
    throw InputError("--velocity-size: " + exact_number(o.velocity_size) + " is out of range (allowed: > 0 and <= 0.1)");
  if (!(o.jitter > 0 && o.jitter <= 0.5))
    throw InputError("--jitter: " + exact_number(o.jitter) + " is out of range (allowed: > 0 and <= 0.5)");
  if (o.vary.empty()) o.vary = {c.scatter.distribution.empty() ? "velocity" : "strength"};
  for (size_t k = 0; k < o.vary.size(); ++k) {
    const std::string& v = o.vary[k];
    if (std::find(kSources.begin(), kSources.end(), v) == kSources.end())
      throw InputError("--vary: unknown source '" + v + "' (allowed: strength, orientation, mesh, velocity)");
    if (std::find(o.vary.begin(), o.vary.begin() + k, v) != o.vary.begin() + k)
      throw InputError("--vary: '" + v + "' is named twice");
  }
  auto varies = [&](const char* s) { return std::find(o.vary.begin(), o.vary.end(), s) != o.vary.end(); };
  if (varies("strength") && c.scatter.distribution.empty())
    throw InputError(o.case_path + ": --vary strength needs a strength scatter in the case (fracture.scatter, "
                     "docs/case-format.md), which this case does not have; add one, e.g. --set "
                     "'fracture.scatter={\"distribution\": \"weibull\", \"modulus\": 5}'");
  if (varies("velocity") && c.initial_velocities.empty())
    throw InputError(o.case_path + ": --vary velocity perturbs the initial velocity "
                     "(boundary.initial_velocity), which this case does not have");
}

// What makes the ensemble: the case as resolved and every option but N. A second invocation must
// give the same to go on in the same folder.
json plan_of(const EnsembleOptions& o, const Case& c) {
  json sets = o.sets;
  return {{"case_file", fs::absolute(o.case_path).lexically_normal().string()},
          {"case", c.resolved},
          {"sets", sets},
          {"vary", o.vary},
          {"seed", o.seed},
          {"velocity_size", o.velocity_size},
          {"jitter", o.jitter}};
}

// The folder: new, empty, or an ensemble of the same plan (then it goes on).
void prepare_folder(const EnsembleOptions& o, const json& plan) {
  const std::string path = o.out_dir + "/ensemble_plan.json";
  std::error_code ec;
  if (fs::exists(o.out_dir, ec) && !fs::is_empty(o.out_dir, ec)) {
    const json old = read_json_file(path);
    if (old.is_null())
      throw InputError("--out " + o.out_dir + ": the folder holds files but no ensemble_plan.json: not an "
                       "ensemble's folder (give a new or empty folder)");
    for (const auto& [k, v] : plan.items())
      if (!old.contains(k) || old[k] != v)
        throw InputError("--out " + o.out_dir + ": the folder holds an ensemble of another command (its '" + k +
                         "' differs: " + path + "); give the same case, --set, --vary, --seed, "
                         "--velocity-size and --jitter to go on with it, or another folder");
    return;
  }
  ensure_output_dir(o.out_dir);
  write_file_atomic(path, plan.dump(2) + "\n");
}

// ---- the realisations as child processes ----

struct Child {
  pid_t pid = 0;
  long index = 0;
  std::chrono::steady_clock::time_point start;
  bool restarted = false;
};

int cores_available() {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  return sched_getaffinity(0, sizeof(mask), &mask) == 0 ? std::max(1, CPU_COUNT(&mask)) : 1;
}

// Starts `fdem run` for realisation r in its folder (from its checkpoint when `restart`), output
// to run.log there. The child has its own process group (a terminal's Ctrl-C reaches only the
// ensemble, which passes one signal on) and gets SIGTERM if the ensemble dies.
pid_t start_child(const EnsembleOptions& o, const Realisation& r, int threads, bool restart) {
  const std::string dir = realisation_folder(o.out_dir, r.index);
  fs::create_directories(dir);
  std::vector<std::string> args = {o.binary, "run", o.case_path, "--out", dir, "--quiet",
                                   "--kokkos-threads=" + std::to_string(threads)};
  for (const auto& s : o.sets) args.insert(args.end(), {"--set", s});
  for (const auto& s : r.sets) args.insert(args.end(), {"--set", s});
  if (restart) args.insert(args.end(), {"--restart", dir + "/checkpoint.h5"});
  const std::string log = dir + "/run.log";
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed: cannot start realisation " + std::to_string(r.index));
  if (pid > 0) return pid;
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (getppid() != parent) _exit(143);
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | (restart ? O_APPEND : O_TRUNC), 0644);
  if (fd >= 0) {
    dup2(fd, 1);
    dup2(fd, 2);
    close(fd);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(o.binary.c_str(), argv.data());
  _exit(127);
}

// A realisation's record (DIR/rNNNN/realisation.json) once its run has ended.
void record(const EnsembleOptions& o, const Realisation& r, int status, double wall) {
  json seeds = json::object(), values = json::object();
  for (const auto& [k, v] : r.seeds) seeds[k] = v;
  for (const auto& [k, v] : r.values) values[k] = v;
  const std::string st = status == 0 ? "done" : status == 3 ? "failed" : "error";
  write_file_atomic(realisation_folder(o.out_dir, r.index) + "/realisation.json",
                    json{{"index", r.index}, {"status", st}, {"exit_status", status},
                         {"seeds", seeds}, {"values", values}, {"sets", r.sets},
                         {"wall_seconds", wall}}.dump(2) + "\n");
}

std::string finished(const EnsembleOptions& o, long i) {
  const json rec = read_json_file(realisation_folder(o.out_dir, i) + "/realisation.json");
  const std::string st = rec.is_object() ? rec.value("status", "") : "";
  return st == "error" ? "" : st;  // (an error is run again)
}

struct Progress {
  long total = 0, done_before = 0, done = 0;
  double wall_sum = 0;
};

void report_progress(const EnsembleOptions& o, const Progress& p, long index, int status, double wall,
                     long running, long left) {
  if (!o.progress) return;
  std::string what = status == 0 ? "done" : status == 3 ? "FAILED (numerical failure)" : "ERROR";
  const json s = read_json_file(realisation_folder(o.out_dir, index) + "/summary.json");
  if (status == 0 && s.is_object() && s.contains("fragments") && s["fragments"].is_object())
    what += ": " + std::to_string(s["fragments"].value("count", 0L)) + " fragments, largest " +
            fixed3(s["fragments"].value("largest_fraction", 0.0));
  const double eta = p.done > 0 ? p.wall_sum / p.done * static_cast<double>(left + running) /
                                      std::max(1, o.jobs) : 0;
  std::printf("[%ld/%ld] r%04ld %s in %.1f s; %ld running, %ld waiting%s\n", p.done_before + p.done,
              p.total, index, what.c_str(), wall, running, left,
              left + running > 0 ? (", about " + exact_number(std::round(eta)) + " s more").c_str() : "");
  std::fflush(stdout);
}

// Passes the ensemble's stop signal on to each running child once.
void stop_children(const std::vector<Child>& running, int sig, bool& passed) {
  if (passed) return;
  for (const Child& c : running) kill(c.pid, sig);
  passed = true;
}

// Runs the realisations not done yet; returns false when a realisation ended with bad input or an
// unexpected error (the others would too: the ensemble stops).
bool run_children(const EnsembleOptions& o, int dim) {
  std::vector<long> todo;
  for (long i = 0; i < o.realisations; ++i) {
    if (!finished(o, i).empty()) continue;
    // A run that ended before the ensemble could record it (killed in between): its summary says so.
    const json s = read_json_file(realisation_folder(o.out_dir, i) + "/summary.json");
    const std::string why = s.is_object() ? s.value("stop_reason", "") : "";
    if (why == "end_time" || why == "max_steps" || why == "load_drop")
      record(o, plan_realisation(o, i, dim), 0, s.value("wall_seconds", 0.0));
    else
      todo.push_back(i);
  }
  Progress p;
  p.total = o.realisations;
  p.done_before = o.realisations - static_cast<long>(todo.size());
  const int threads = o.threads > 0 ? o.threads : std::max(1, cores_available() / o.jobs);
  if (o.progress)
    std::printf("ensemble %s: %ld realisations (%ld done before), %d at a time, %d thread%s each\n",
                o.out_dir.c_str(), o.realisations, p.done_before, o.jobs, threads, threads > 1 ? "s" : "");
  std::vector<Child> running;
  size_t next = 0;
  bool ok = true, passed = false;
  while (next < todo.size() || !running.empty()) {
    const int sig = o.interrupt ? *o.interrupt : 0;
    if (sig) stop_children(running, sig, passed);
    while (!sig && ok && next < todo.size() && static_cast<int>(running.size()) < o.jobs) {
      const long i = todo[next++];
      const bool restart = fs::exists(realisation_folder(o.out_dir, i) + "/checkpoint.h5");
      running.push_back({start_child(o, plan_realisation(o, i, dim), threads, restart), i,
                         std::chrono::steady_clock::now(), restart});
    }
    if ((sig || !ok) && running.empty()) break;
    int st = 0;
    const pid_t pid = waitpid(-1, &st, WNOHANG);
    if (pid <= 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const auto it = std::find_if(running.begin(), running.end(), [&](const Child& c) { return c.pid == pid; });
    if (it == running.end()) continue;
    const Child c = *it;
    running.erase(it);
    const int status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - c.start).count();
    if (status == 2 && c.restarted && !sig) {  // a checkpoint it could not go on from: start afresh
      fs::remove(realisation_folder(o.out_dir, c.index) + "/checkpoint.h5");
      todo.push_back(c.index);
      continue;
    }
    if (status >= 128) continue;  // stopped by a signal: goes on at the next invocation
    record(o, plan_realisation(o, c.index, dim), status, wall);
    if (status != 0 && status != 3) {
      ok = false;
      std::fprintf(stderr, "error: realisation %ld ended with exit status %d; its log: %s/run.log\n", c.index,
                   status, realisation_folder(o.out_dir, c.index).c_str());
    }
    ++p.done;
    p.wall_sum += wall;
    report_progress(o, p, c.index, status, wall, static_cast<long>(running.size()),
                    static_cast<long>(todo.size() - next));
  }
  return ok;
}

}  // namespace

int run_ensemble(EnsembleOptions o) {
  const Case c = load_case(o.case_path, o.sets);
  check_options(o, c);
  {
    std::vector<std::string> all = o.sets;  // realisation 0's settings must make a valid case too
    for (const auto& s : plan_realisation(o, 0, c.dim).sets) all.push_back(s);
    load_case(o.case_path, all);
  }
  const json plan = plan_of(o, c);
  prepare_folder(o, plan);
  const bool ok = run_children(o, c.dim);
  const json report = write_ensemble_report(o.out_dir, o.realisations, plan);
  const long done = report.value("done", 0L), failed = report.value("failed", 0L);
  if (o.progress)
    std::printf("ensemble: %ld of %ld realisations done, %ld failed\n  table:      %s/ensemble.csv\n"
                "  statistics: %s/ensemble.json\n",
                done, o.realisations, failed, o.out_dir.c_str(), o.out_dir.c_str());
  if (!ok) return 1;
  const int sig = o.interrupt ? *o.interrupt : 0;
  if (sig) {
    std::fprintf(stderr, "ensemble stopped by signal %d: %ld of %ld realisations done; the same command goes "
                         "on from there\n", sig, done, o.realisations);
    return 128 + sig;
  }
  return failed > 0 ? 3 : 0;
}

}  // namespace fdem
