#pragma once
// Set-up of a run (`fdem run` to its first step), phase by phase, and the peak host memory: what
// summary.json's "setup" and "memory" report and what `fdem run` prints in one line before the
// first step. Phases are recorded from the host thread that sets the run up (run_case and what it
// calls); Gmsh's own times come from its child process (gmsh_io.cpp). No Kokkos: the mesh module
// uses it too.
#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

namespace fdem::setup_times {

// Forget every phase and the Gmsh child's peak memory, and start the clock of a new run's set-up.
void reset();
// The set-up is over (the first step begins): its total time and the peak memory so far are kept.
void finish();
// Add `wall` seconds of wall time and `cpu` seconds of CPU time (all threads) to the phase `name`;
// phases keep the order of their first record.
void add(const std::string& name, double wall, double cpu = 0);
// Seconds of CPU time used by this process so far (all threads, and its children that ended).
double process_cpu_seconds();
// Peak resident memory of this process so far (VmHWM in /proc/self/status), bytes; -1 if unknown.
double peak_rss_bytes();
// Resident memory now (VmRSS), bytes; -1 if unknown.
double rss_bytes();
// The largest peak resident memory of a Gmsh child process (bytes) seen so far.
void note_gmsh_peak(double bytes);
double gmsh_peak_bytes();

// {"phases": [{"name", "wall_seconds", "cpu_seconds", "rss_bytes" (resident memory at its end)}...],
// "wall_seconds", "cpu_seconds": from reset() to finish() (what no phase covers is the phase "other"),
// "peak_rss_bytes": this process's peak at finish(), "gmsh_peak_rss_bytes"}
nlohmann::json report();
// One line: "set-up 12.3 s (wall): gmsh_meshing 5.1, ... s; peak memory ... MB" (phases of at
// least 2 % of the total).
std::string line();

// Times its scope (or until stop()) into phase `name`, less what phases recorded meanwhile (a
// phase inside another counts once).
class Phase {
 public:
  explicit Phase(std::string name);
  ~Phase() { stop(); }
  void stop();
  Phase(const Phase&) = delete;
  Phase& operator=(const Phase&) = delete;

 private:
  std::string name_;
  bool outer_;  // opened outside every Folded scope
  std::chrono::steady_clock::time_point wall0_;
  double cpu0_;
  double inner_wall0_, inner_cpu0_;  // what all phases had recorded at the start
  bool open_ = true;
};

// While one lives, the phases opened in its scope record nothing: the phase around it counts
// their time (a cut of the parts anew that builds the mesh again with the set-up's functions
// records it as one phase, not under the set-up's names).
class Folded {
 public:
  Folded();
  ~Folded();
  Folded(const Folded&) = delete;
  Folded& operator=(const Folded&) = delete;
};

}  // namespace fdem::setup_times
