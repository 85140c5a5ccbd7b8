#pragma once
// What the run loop does that depends on how the run is decomposed (docs/parallel.md), in one
// object the loop always calls: the state a checkpoint holds and a restart or a cut takes, how a
// checkpoint file is written, the fragments' labelling, how often the processes look for a
// signal, and the lines of the progress and the summary that only a run over processes has. Two
// implementations, chosen once by make_run_parts: one process (its Simulation's state as it is)
// and the parts of a run over processes (the whole run's state gathered and given back:
// solver/whole_state.hpp). The step's side of the decomposition is Parts (src/parallel/parts.hpp).
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"
#include "parallel/decompose.hpp"
#include "solver/run.hpp"
#include "solver/run_output.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
class RunParts {
 public:
  virtual ~RunParts() = default;
  // The simulation's state to go on from: a checkpoint's, or over processes the whole state at a
  // cut (then checked: nothing lost).
  virtual void load(const StateArrays& r) = 0;
  // The simulation's state (over processes with the cuts so far and the balance) into st. Over
  // processes on process 0 only: false elsewhere, which holds nothing (rows: see save_whole_state).
  virtual bool save(StateArrays& st, std::vector<RowPart>* rows) const = 0;
  // The file access of a checkpoint written by every process, each its own rows (the parallel
  // HDF5); -1: one file written by the process that writes.
  virtual long long checkpoint_access() const = 0;
  virtual std::unique_ptr<RunFragments<D>> fragments(const std::string& out, const RunState* restart,
                                                     const std::string& file) const = 0;
  // Every how many steps the processes look together for a signal that asks them to stop.
  virtual long interrupt_poll() const = 0;
  // What the message of an interrupted run adds to its restart command, and a line on its exit
  // status (empty on one process, which exits with 128 + the signal).
  virtual const char* restart_note() const = 0;
  virtual const char* exit_note() const = 0;
  // The progress line of the decomposition at the start (none on one process).
  virtual void announce() const = 0;
  // summary.json "processes" (collective; none on one process).
  virtual void report(nlohmann::json& summary, const Case& c, std::chrono::steady_clock::time_point loop_start,
                      double cut_setup) const = 0;
};

// The decomposition of a run: `part` null, one process; else this process's part of a run over
// processes (opt.comm), which joins it here (Simulation::set_decomposition). cuts: the run's cuts
// so far; restart: the state the loop goes on from (&cuts.state when the parts begin at a cut).
template <int D>
std::unique_ptr<RunParts<D>> make_run_parts(Simulation<D>& sim, const RunOptions& opt, const SubMesh* part,
                                            CutHistory& cuts, const StateArrays* restart);

// The mesh a process's model is built from: its part's over processes, else the whole mesh; and
// the part the history table reads (null: one process).
inline const HostMesh& model_mesh(const HostMesh& whole, const SubMesh* part) { return part ? part->mesh : whole; }
inline const HostMesh* history_part(const SubMesh* part) { return part ? &part->mesh : nullptr; }

}  // namespace fdem
