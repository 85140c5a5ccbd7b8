#pragma once
// history.csv of a run: its columns (time, platens, velocity-BC reactions, monitored node sets,
// strength reduction factor, momentum, energies), every row so far (kept for checkpoints), the
// platens' peak loads and the stop rule (the load of the stop platen drops below a fraction of
// its peak).
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
  HistoryTable(const Case& c, const HostMesh& mesh, const Simulation<D>& sim);

  const std::vector<std::string>& columns() const { return cols_; }
  // Strength reduction: the case has a schedule, and the factor at time t.
  bool has_srf() const { return srf_; }
  double srf_at(double t) const;

  // Opens out/history.csv: a new file, or (after restore) one rewritten with the rows so far.
  void open(const std::string& out, bool restarted);
  // Appends the row of the last sampled step (sim.energies() and the forces of that step) and
  // updates the peaks; returns true when the stop rule is met.
  bool write_row(const Simulation<D>& sim);

  const Energies& last() const { return last_; }  // of the last row
  double max_relative_balance_error() const { return max_rel_error_; }
  const std::vector<double>& peak_load() const { return peak_; }
  const std::vector<double>& peak_displacement() const { return peak_disp_; }
  size_t rows() const { return rows_.size() / cols_.size(); }

  // Checkpoint: the columns, rows, peaks and last energies into / out of the run state. restore
  // throws InputError naming `file` when the checkpoint's columns or rows do not fit this case.
  void save(RunState& s) const;
  void restore(const RunState& s, const std::string& file);

 private:
  void add_columns(const Simulation<D>& sim, const HostMesh& mesh);
  std::vector<double> make_row(const Simulation<D>& sim, bool& stop);
  std::string joined_columns() const;

  const Case& c_;
  std::vector<std::string> cols_;
  std::vector<Kokkos::View<int*>> monitor_nodes_;
  bool srf_ = false;
  int stop_platen_ = -1;
  std::unique_ptr<HistoryWriter> file_;
  std::vector<double> rows_;  // row-major
  std::vector<double> peak_, peak_disp_;
  double max_rel_error_ = 0;
  Energies last_{};
};

extern template class HistoryTable<2>;
extern template class HistoryTable<3>;

}  // namespace fdem
