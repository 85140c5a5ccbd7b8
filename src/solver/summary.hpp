#pragma once
// summary.json of a run, and the reports `fdem check` shares with it.
#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"
#include "solver/history_table.hpp"
#include "solver/run_output.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

// Counts and quality of a prepared mesh.
nlohmann::json mesh_report(const HostMesh& mesh);
// The same from the whole mesh's counts and quality (a run whose whole mesh no process holds sums
// them over its processes: src/solver/local_setup.hpp).
nlohmann::json mesh_report(long nodes, long elems, long ifaces, const MeshQuality& q,
                           const std::vector<std::string>& regions, const std::vector<std::string>& warnings,
                           int bodies);

// The time step: used, critical, and its parts (and its change when contact's springs applied).
template <int D>
nlohmann::json stable_report(const Simulation<D>& sim);

// Wall time of each phase of the time step in this process (seconds and share of their sum),
// estimated from the timed (sampled) steps: "estimated" and "note" say so.
nlohmann::json phases_report(const PhaseTimes& p);

// What the run loop knows at the end besides the simulation, its history and fragments.
struct RunRecord {
  std::string out;  // output folder
  int boundary_nodes = 0;  // before contact adds crack faces to the platens' nodes
  std::string stop_reason;
  int signal = 0;                                  // stop reason "interrupted": the signal's number
  double wall_seconds = 0, loop_wall_seconds = 0;  // all processes of the run
  bool snapshots = false;
  // checkpoints: an entry when they are written or the run restarted
  std::string checkpoint_file;
  double checkpoint_every = 0, checkpoint_seconds = 0;
  long checkpoints_written = 0;
  const StateArrays* restart = nullptr;  // the checkpoint the run went on from
};

// The summary of a finished run (counts: mesh_report of its mesh, taken before the mesh was freed;
// frag: null without fragment analysis).
template <int D>
nlohmann::json run_summary(const Case& c, const nlohmann::json& counts, Simulation<D>& sim,
                           const HistoryTable<D>& history, RunFragments<D>* frag, const RunRecord& r);

// summary.json "processes" of a run over several processes (collective: every process calls it, at
// the end of the run): the processes' exchange, memory and measured balance (each one's time in the
// loop since loop_start outside the exchange, with that of the parts before the last cut), the cuts
// of the parts anew (cuts; cut_setup: the set-up of the parts that end, when they began at a cut)
// and, once the balance was checked, the work model and the excesses.
template <int D>
nlohmann::json processes_report(const Case& c, const Simulation<D>& sim, const CutHistory& cuts,
                                std::chrono::steady_clock::time_point loop_start, double cut_setup);

// The key results of a run from its summary (nothing else): a heading, then the strength or the
// platens' peak loads, the failed interfaces and the fragments, the energies and their balance,
// each of what the summary holds; lines that end in '\n'.
std::string key_results(const nlohmann::json& summary);

// The closing lines: steps and throughput on stderr (with progress on), where the results are
// on stdout, then (with progress on) key_results on stderr, the last lines a person sees.
void print_run_end(const nlohmann::json& summary, const RunRecord& r, long steps, bool progress);

}  // namespace fdem
