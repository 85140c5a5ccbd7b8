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
#include "solver/run_progress.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
class RunLoop {
 public:
  // restart: the checkpoint to go on from (checked against the case by the caller), or null. The
  // mesh is freed once the model and the outputs are set up (the run does not need it).
  // part: this process's part of a run over several processes (opt.comm), the model built from
  // it; mesh is then the whole mesh on process 0 (outputs, counts) and an empty one with the
  // dimension and body count on the others. Null: one process.
  RunLoop(const Case& c, HostMesh&& mesh, const std::string& out, const RunOptions& opt,
          const RunIdentity& id, const StateArrays* restart, const SubMesh* part = nullptr);
  // Runs to the end time (or the step limit, or the stop rule); returns the summary written to
  // out/summary.json.
  nlohmann::json run();

 private:
  using Clock = std::chrono::steady_clock;
  void restore(const StateArrays& r, bool parts);
  void announce() const;
  void step(bool row, bool check);
  void history_row();
  void final_row();
  void save_checkpoint();
  // The whole run's state (simulation and run loop) into st; over several processes on process 0
  // only (false elsewhere: it holds nothing). written: the checkpoints written with this one.
  // rows: see Simulation::save_state_whole.
  bool collect_state(StateArrays& st, Clock::time_point c0, long written,
                     std::vector<RowPart>* rows = nullptr);
  // The parts are to be cut anew (Simulation::recut_due): the whole state to opt.recut; returns
  // {"recut": true} instead of a summary (run_case goes on with the new parts).
  nlohmann::json recut();
  void check_recut(const StateArrays& given);
  nlohmann::json interrupted();
  // The signal that asks the run to stop (0: none); over several processes the same on each.
  int interrupt_signal() const;
  static constexpr long kInterruptPoll = 64;
  // (the whole mesh's interfaces: a part of a run over several processes may have none)
  bool fragments_on() const { return c_.output_fragments && whole_ifaces_ > 0; }
  nlohmann::json finish(const std::string& stop_reason, double loop_wall);

  const Case& c_;
  std::unique_ptr<HostMesh> mesh_;  // null after the set-up
  nlohmann::json counts_;           // mesh_report of the mesh, for summary.json
  const std::string out_;
  const RunOptions& opt_;
  const RunIdentity id_;
  const StateArrays* restart_;
  const Clock::time_point wall0_;
  Clock::time_point loop0_;
  // A part that began at a cut (the restart state is opt.recut): its set-up's wall time, from the
  // construction to the loop's start (a share of the cut's time; 0 otherwise).
  double cut_setup_seconds() const;
  Simulation<D> sim_;
  const int boundary_nodes_;  // before contact adds crack faces to the platens' nodes
  OutputSchedule schedule_;
  std::unique_ptr<HistoryTable<D>> history_;
  std::unique_ptr<RunFragments<D>> frag_;  // null without fragment analysis
  std::unique_ptr<RunSnapshots<D>> snaps_;
  std::unique_ptr<Progress> progress_;
  // wall times of the processes before this one (restart), checkpoint writing
  double prior_wall_ = 0, prior_loop_wall_ = 0, ckpt_wall_ = 0;
  long ckpt_written_ = 0;
  int signal_ = 0;  // the signal that stopped the run (0: none)
  bool writes_ = true;  // this process writes the outputs (process 0 of a run over several)
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

// run_case's run of a prepared case in dimension D.
template <int D>
nlohmann::json run_dim(const Case& c, HostMesh&& mesh, const std::string& out, const RunOptions& opt,
                       const RunIdentity& id, const StateArrays* restart, const SubMesh* part = nullptr);

extern template class RunLoop<2>;
extern template class RunLoop<3>;

}  // namespace fdem
