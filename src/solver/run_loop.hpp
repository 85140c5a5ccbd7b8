#pragma once
// The time loop of a run (run_case in solver/run.hpp prepares the case, mesh and restart file):
// step, the outputs that are due, the stability checks, checkpoints; then a final history row,
// the last snapshot and summary.json.
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"
#include "parallel/decompose.hpp"
#include "solver/history_table.hpp"
#include "solver/run.hpp"
#include "solver/run_output.hpp"
#include "solver/run_parts.hpp"
#include "solver/run_progress.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

// The parts of a run over several processes are to be cut anew (Simulation::recut_due): why, the
// balance then, and the times of the parts that end (the run over processes, solver/run.cpp,
// records them in its CutHistory and cuts the parts).
struct CutRequest {
  std::string reason;  // Simulation::recut_reason
  // Simulation::Balance: the excess at the last check, at the first check after the last cut, and
  // the largest seen
  double excess = 0, after_cut = 0, largest = 0;
  double busy = 0;  // this process's time in the loop outside the exchange
  // the cut's time so far: the whole state gathered; the set-up of the parts that end, when they
  // began at a cut (RunLoop::cut_setup_seconds)
  double gather_seconds = 0, setup_seconds = 0;
};

// How RunLoop::run ended: the run finished (at the end time, the step limit or the stop rule) or a
// signal interrupted it (summary: what out/summary.json holds), or the parts are to be cut anew
// (cut; the whole state is in the CutHistory's state, solver/run_state.hpp).
struct LoopEnd {
  enum class Kind { finished, interrupted, cut_due };
  Kind kind = Kind::finished;
  nlohmann::json summary;
  CutRequest cut;
};

template <int D>
class RunLoop {
 public:
  // restart: the checkpoint to go on from (checked against the case by the caller), or null. The
  // mesh is freed once the model and the outputs are set up (the run does not need it).
  // part: this process's part of a run over several processes (opt.comm), the model built from
  // it; mesh is then the whole mesh on process 0 (outputs, counts) and an empty one with the
  // dimension and body count on the others. cuts: that run's cuts of the parts anew so far, owned
  // by the run over processes (solver/run.cpp); restart is &cuts->state when the parts begin at a
  // cut. Both null: one process. The loop lets go of the mesh once it is set up (the caller may
  // keep it: process 0 of a run that cuts its parts anew).
  RunLoop(const Case& c, std::shared_ptr<const HostMesh> mesh, const std::string& out, const RunOptions& opt,
          const RunIdentity& id, const StateArrays* restart, const SubMesh* part = nullptr,
          CutHistory* cuts = nullptr);
  // Runs to the end time (or the step limit, or the stop rule, or a signal; the summary written to
  // out/summary.json) or to a cut of the parts anew.
  LoopEnd run();

 private:
  using Clock = std::chrono::steady_clock;
  // The whole mesh's counts (mesh_report on the process that holds it, else the part's).
  nlohmann::json whole_counts(const SubMesh* part) const;
  // A run over processes: the snapshots set up from process 0's whole mesh before the model is
  // built (one process: null, they are set up after it).
  std::unique_ptr<RunSnapshots<D>> early_snapshots(const SubMesh* part) const;
  // The mesh the model is built from: one process's whole mesh, or the part; over processes the
  // counts are taken from the whole mesh here and then it is let go of (process 0's peak holds the
  // whole mesh or its model, not both).
  const HostMesh& model_source(const SubMesh* part);
  void restore(const StateArrays& r);
  void announce() const;
  void step(bool row, bool check);
  void history_row();
  void final_row();
  void save_checkpoint();
  // The whole run's state (simulation and run loop) into st; over several processes on process 0
  // only (false elsewhere: it holds nothing). written: the checkpoints written with this one.
  // rows: see save_whole_state (solver/whole_state.hpp).
  bool collect_state(StateArrays& st, Clock::time_point c0, long written,
                     std::vector<RowPart>* rows = nullptr);
  // The parts are to be cut anew (Simulation::recut_due): the whole state to cuts_->state; the
  // run over processes goes on with the new parts.
  LoopEnd recut();
  // Whether this run loop's parts began at a cut (their state is the cut's, not a checkpoint's).
  bool began_at_cut() const { return restart_ && restart_ == &cuts_->state; }
  void take_snapshot();  // (the part's mesh taken back for the first frame where it writes /mesh)
  LoopEnd interrupted();
  // The signal that asks the run to stop (0: none); over several processes the same on each.
  int interrupt_signal() const;
  // (the whole mesh's interfaces: a part of a run over several processes may have none)
  bool fragments_on() const { return c_.output_fragments && whole_ifaces_ > 0; }
  nlohmann::json finish(const std::string& stop_reason, double loop_wall);

  const Case& c_;
  std::shared_ptr<const HostMesh> mesh_;  // null after the set-up (over processes: from the model's build)
  nlohmann::json counts_;           // mesh_report of the mesh, for summary.json
  const std::string out_;
  const RunOptions& opt_;
  const RunIdentity id_;
  const StateArrays* restart_;
  CutHistory no_cuts_;      // (one process: none)
  CutHistory* const cuts_;  // the run over processes' cuts, or no_cuts_
  const Clock::time_point wall0_;
  Clock::time_point loop0_;
  std::unique_ptr<RunSnapshots<D>> snaps_;  // (over processes: set up before the model)
  // A part that began at a cut (began_at_cut()): its set-up's wall time, from the construction to
  // the loop's start (a share of the cut's time; 0 otherwise).
  double cut_setup_seconds() const;
  Simulation<D> sim_;
  std::unique_ptr<RunParts<D>> parts_;  // the decomposition (one process: the trivial one)
  const int boundary_nodes_;  // before contact adds crack faces to the platens' nodes
  OutputSchedule schedule_;
  std::unique_ptr<HistoryTable<D>> history_;
  std::unique_ptr<RunFragments<D>> frag_;  // null without fragment analysis
  std::unique_ptr<Progress> progress_;
  // wall times of the processes before this one (restart), checkpoint writing
  double prior_wall_ = 0, prior_loop_wall_ = 0, ckpt_wall_ = 0;
  long ckpt_written_ = 0;
  int signal_ = 0;  // the signal that stopped the run (0: none)
  bool writes_ = true;  // this process writes the outputs (Parts::root: process 0 of several)
  long whole_ifaces_ = 0;  // the whole mesh's interfaces
  // the pace of the loop: at each tenth of the end time that this loop crosses, the step and the
  // loop's wall seconds so far (summary.json "pace": how the step rate changes as a run fragments,
  // docs/performance.md section 9b). A restart, or a cut of the parts anew, starts a new loop: its
  // pace begins there (from_step, from_time).
  struct PaceMark {
    int tenth;
    long step;
    double loop_seconds;
  };
  std::vector<PaceMark> pace_;
  int next_tenth_ = 1;
  long pace_step0_ = 0;
  double pace_t0_ = 0;
  void mark_pace();
};

// run_case's run of a prepared case in dimension D (the arguments: RunLoop's).
template <int D>
LoopEnd run_dim(const Case& c, std::shared_ptr<const HostMesh> mesh, const std::string& out, const RunOptions& opt,
                const RunIdentity& id, const StateArrays* restart, const SubMesh* part = nullptr,
                CutHistory* cuts = nullptr);

extern template class RunLoop<2>;
extern template class RunLoop<3>;

}  // namespace fdem
