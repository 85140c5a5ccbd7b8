#pragma once
// The run loop's part of a checkpoint (datasets "run/..."): what the time loop needs besides the
// simulation's own state (Simulation::save_state) to go on as if it had not stopped. One field
// list serves both the checkpoint write and the restart read. And the cuts of a run over several
// processes (CutHistory, datasets "processes/..."): what the run over processes (solver/run.cpp)
// and its run loops know of the parts cut anew so far.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/checkpoint.hpp"

namespace fdem {

struct SubMesh;  // parallel/decompose.hpp

// What identifies a run for a restart (checkpoint header).
struct RunIdentity {
  std::string case_hash, mesh_hash;
};

struct RunState {
  std::string history_columns;        // one column name per line
  std::vector<double> history_rows;   // every history row so far (row-major)
  std::vector<double> fragment_rows;  // every fragments.csv row so far (row-major; empty without)
  double next_history = 0, next_snapshot = 0, next_checkpoint = 0;
  double checkpoint_every = 0;        // the interval the checkpoint was written with
  std::vector<double> peak_load, peak_displacement;  // per platen
  double max_relative_balance_error = 0;
  std::vector<double> last_row_energies;  // Energies of the last row (energies_to_vector)
  long long last_was_row = 0;         // the last step was sampled for a history row
  long long last_snapshot_step = -1;
  std::vector<long long> snapshot_steps;  // frames in snapshots.h5
  std::vector<double> snapshot_times;
  double wall_seconds = 0, loop_wall_seconds = 0, checkpoint_seconds = 0;  // all processes so far
  long long checkpoints_written = 0;
  // HistoryTable's load sampling (next sample, first sample, smoothed peak, stop time, then the
  // window's (time, load) pairs) and balance warning (time, step, error); optional on load
  // (empty when the checkpoint has none).
  std::vector<double> load_samples, balance_warning;

  void save(StateArrays& s) const;
  // Reads every field; `platens`: the case's platen count (sizes of the peak arrays). Throws
  // InputError naming the checkpoint when a field is missing or has another size.
  void load(const StateArrays& s, int platens);

 private:
  // Calls f(name, field, expected size) for every field (expected < 0: any size).
  template <class Self, class F>
  static void fields(Self& s, F&& f, long long platens);
};

// The cuts of the parts anew in a run over several processes with contact (solver/run.cpp: the
// run over processes owns it and hands it to each RunLoop; one process has none). The run loop
// leaves the whole state in `state` when the parts are to be cut anew (Simulation::recut_due);
// the next parts start from it.
struct CutHistory {
  StateArrays state;  // the whole state at the last cut (on process 0; every process's after the sending)
  // The checkpoint the run first went on from (null: none).
  const StateArrays* restarted = nullptr;
  int recuts = 0;  // the cuts so far (a checkpoint holds them)
  // Of those cuts, the ones the balance asked for (Simulation::recut_reason "work"), the excess of
  // the most loaded process's work over the mean that asked for each, and the excess at the first
  // check after each cut (docs/parallel.md "Rebalancing"); and on process 0 each element's part at
  // the last cut (a checkpoint holds it: a restart on as many processes cuts its parts the same).
  int rebalances = 0;
  std::vector<double> excess_at_rebalances, excess_after_cuts;
  double excess_largest = 0;
  std::string last_cut_reason;  // for the progress note of the cut
  // Each cut of this invocation: why ("work", "zones", "test"; Simulation::recut_reason) and, on
  // process 0, how many elements changed process; and the elements moved by all the run's cuts
  // (a checkpoint holds it).
  std::vector<std::string> cut_reasons;
  std::vector<long long> elements_moved_at_cuts;
  long long elements_moved = 0;
  // This process's time in the loop outside the exchange (which includes waiting for the others)
  // in the parts before the last cut: the measured side of the balance.
  double busy_seconds = 0;
  // The wall time of the cuts so far (process 0's; the others wait for it): the whole state
  // gathered, the partition, the parts and state sent, the new parts set up and checked.
  double cut_seconds = 0;
  std::vector<int> cut_parts;
  // The fragment labellings of the parts before the last cut and their wall time (RunFragments:
  // summary.json fragments.labelling counts the whole invocation's).
  long labellings = 0;
  double label_seconds = 0;
  // A run whose whole mesh no process holds (solver/local_setup.hpp): summary.json's mesh report,
  // summed over the processes (every process the same; null otherwise: the run loop takes it from
  // process 0's whole mesh); and whether process 0 still holds no whole mesh (until the first cut
  // rebuilds it from the coarse mesh): the snapshots' /mesh then comes from every process's rows.
  nlohmann::json mesh_report;
  bool mesh_by_parts = false;
  // This process's part, whose mesh the run loop lets go once its set-up and the snapshots' first
  // frame have read it (release_part_mesh, solver/kept_mesh.hpp; the run over processes owns it).
  SubMesh* part = nullptr;

  // Checkpoint (process 0's whole state): the cuts, rebalances and elements moved so far, and the
  // parts of the last cut when there was one. load takes the counts of a checkpoint that has them
  // (one written by one process, or before they were kept, has not).
  void save(StateArrays& s) const;
  void load(const StateArrays& s);
};

}  // namespace fdem
