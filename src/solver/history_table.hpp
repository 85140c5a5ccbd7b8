#pragma once
// history.csv of a run: its columns (time, platens, velocity-BC reactions, monitored node sets,
// strength reduction factor, momentum, energies), every row so far (kept for checkpoints), the
// platens' peak loads and the stop rule (the load of the stop platen drops below a fraction of
// its peak), and the energy-balance warning.
//
// The peaks and the stop rule do not use the rows: the platens' loads are sampled on a cadence of
// their own in simulated time, 32 samples per "load window", the time a P wave takes to cross
// the body along the stop platen's normal (the slowest material of the case; at most a tenth of
// end_time). The stop rule compares the load averaged over the last window with the largest such
// average so far, once a full window has been sampled: the ringing of the platens' first contact
// (contact springs on single nodes, periods of a few steps) averages out, and the result does not
// depend on output.history_rows.
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
class HistoryTable {
 public:
  // part: a run over several processes (sim built from part's mesh): the monitors' node lists are
  // the part's own nodes, their mean taken over all processes (the sets' whole sizes from
  // part->whole_set_size), and the load window is taken over every process's nodes; `mesh` is
  // then not read (the whole mesh is on process 0 only).
  HistoryTable(const Case& c, const HostMesh& mesh, const Simulation<D>& sim, const HostMesh* part = nullptr);

  const std::vector<std::string>& columns() const { return cols_; }
  // Strength reduction: the case has a schedule, and the factor at time t.
  bool has_srf() const { return srf_; }
  double srf_at(double t) const;

  // Opens out/history.csv: a new file, or (after restore) one rewritten with the rows so far.
  void open(const std::string& out, bool restarted);
  // Appends the row of the last sampled step (sim.energies() and the forces of that step).
  void write_row(const Simulation<D>& sim);
  // After a step that started at time t0: samples the platens' loads (that step's forces) when a
  // load sample is due, updates the peaks and the stop rule; returns true when the rule is met.
  bool sample_loads(const Simulation<D>& sim, double t0);
  // After a step whose energies were sampled (a row or a stability check; from step 10 on): the
  // largest relative balance error so far, and a warning on stderr (once per run) when it first exceeds
  // kBalanceWarning.
  void check_balance(const Energies& e);
  static constexpr double kBalanceWarning = 0.05;

  const Energies& last() const { return last_; }  // of the last row
  double max_relative_balance_error() const { return max_rel_error_; }
  const std::vector<double>& peak_load() const { return peak_; }
  const std::vector<double>& peak_displacement() const { return peak_disp_; }
  size_t rows() const { return rows_.size() / cols_.size(); }
  // The load sampling and the stop rule (summary.json): window and sample interval (s), the
  // largest window-averaged load of the stop platen (N), the time the rule was met (-1: not).
  double load_window() const { return window_; }
  double load_sample_interval() const { return sample_dt_; }
  double smoothed_peak() const { return smooth_peak_; }
  double stop_met_at() const { return stop_at_; }
  // The first sampled step whose relative balance error exceeded kBalanceWarning: time, step,
  // error (time < 0: none).
  double balance_warned_at() const { return warn_time_; }
  long balance_warned_step() const { return warn_step_; }
  double balance_warned_error() const { return warn_error_; }

  // Checkpoint: the columns, rows, peaks and last energies into / out of the run state. restore
  // throws InputError naming `file` when the checkpoint's columns or rows do not fit this case.
  void save(RunState& s) const;
  void restore(const RunState& s, const std::string& file);

 private:
  void add_columns(const Simulation<D>& sim, const HostMesh& mesh, const HostMesh* part);
  std::vector<double> make_row(const Simulation<D>& sim);
  std::string joined_columns() const;
  void set_load_window(const Case& c, const HostMesh& mesh, const Comm* comm);

  const Case& c_;
  std::vector<std::string> cols_;
  std::vector<Kokkos::View<int*>> monitor_nodes_;
  std::vector<long> monitor_count_;  // nodes in each monitored set (the whole mesh's)
  bool srf_ = false;
  int stop_platen_ = -1;
  std::unique_ptr<HistoryWriter> file_;
  std::vector<double> rows_;  // row-major
  std::vector<double> peak_, peak_disp_;
  double max_rel_error_ = 0;
  Energies last_{};
  // load sampling and stop rule
  double window_ = 0, sample_dt_ = 0, next_sample_ = 0, first_sample_ = -1;
  double smooth_peak_ = 0, stop_at_ = -1;
  std::deque<std::pair<double, double>> recent_;  // (time, load) of the stop platen in the window
  // energy-balance warning
  double warn_time_ = -1, warn_error_ = 0;
  long warn_step_ = -1;
};

extern template class HistoryTable<2>;
extern template class HistoryTable<3>;

}  // namespace fdem
