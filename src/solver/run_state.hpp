#pragma once
// The run loop's part of a checkpoint (datasets "run/..."): what the time loop needs besides the
// simulation's own state (Simulation::save_state) to go on as if it had not stopped. One field
// list serves both the checkpoint write and the restart read.
#include <string>
#include <vector>

#include "io/checkpoint.hpp"

namespace fdem {

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

}  // namespace fdem
