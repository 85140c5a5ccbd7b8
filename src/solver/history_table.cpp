#include "solver/history_table.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"

namespace fdem {

namespace {
const char* const kAxes[3] = {"x", "y", "z"};
}  // namespace

template <int D>
HistoryTable<D>::HistoryTable(const Case& c, const HostMesh& mesh, const Simulation<D>& sim)
    : c_(c) {
  const int np = sim.m.platens.count;
  peak_.assign(np, 0.0);
  peak_disp_.assign(np, 0.0);
  srf_ = c.srf_initial != 1.0 || c.srf_rate > 0;
  for (int p = 0; p < np; ++p)
    if (sim.platen_names()[p] == c.stop_platen) stop_platen_ = p;
  add_columns(sim, mesh);
}

template <int D>
void HistoryTable<D>::add_columns(const Simulation<D>& sim, const HostMesh& mesh) {
  cols_ = {"time [s]", "step"};
  for (const auto& name : sim.platen_names()) {
    cols_.push_back(name + "_displacement [m]");
    for (int k = 0; k < D; ++k) cols_.push_back(name + "_force_" + kAxes[k] + " [N]");
    cols_.push_back(name + "_load [N]");
  }
  for (const auto& name : sim.bc_names())
    for (int k = 0; k < D; ++k) cols_.push_back(name + "_reaction_" + kAxes[k] + " [N]");
  for (const auto& name : c_.monitors) {
    const auto& nodes = mesh.node_sets.at(name);
    Kokkos::View<int*> v("fdem::monitor", nodes.size());
    auto vh = Kokkos::create_mirror_view(v);
    for (size_t j = 0; j < nodes.size(); ++j) vh(j) = nodes[j];
    Kokkos::deep_copy(v, vh);
    monitor_nodes_.push_back(v);
    for (int k = 0; k < D; ++k) cols_.push_back(name + "_u" + kAxes[k] + " [m]");
  }
  if (srf_) cols_.push_back("strength_reduction_factor");
  for (int k = 0; k < D; ++k) cols_.push_back(std::string("momentum_") + kAxes[k] + " [N s]");
  for (const char* e : {"E_kinetic [J]", "E_strain [J]", "E_interface [J]", "E_contact [J]",
                        "D_fracture [J]", "D_damping [J]", "D_friction [J]", "W_external [J]",
                        "energy_error [J]", "interfaces_damaged", "interfaces_failed"})
    cols_.push_back(e);
}

template <int D>
double HistoryTable<D>::srf_at(double t) const {
  return c_.srf_initial + c_.srf_rate * std::max(0.0, t - c_.srf_start);
}

template <int D>
void HistoryTable<D>::open(const std::string& out, bool restarted) {
  file_ = restarted ? std::make_unique<HistoryWriter>(out + "/history.csv", cols_, rows_)
                    : std::make_unique<HistoryWriter>(out + "/history.csv", cols_);
}

template <int D>
std::vector<double> HistoryTable<D>::make_row(const Simulation<D>& sim, bool& stop) {
  std::vector<double> row = {last_.time, static_cast<double>(last_.step)};
  for (int p = 0; p < sim.m.platens.count; ++p) {
    const auto F = sim.platen_force(p);
    const auto& P = sim.m.platens.p[p];
    const double load = F[0] * P.n[0] + F[1] * P.n[1] + F[2] * P.n[2];
    const double disp = sim.platen_displacement(p, last_.time);
    row.push_back(disp);
    for (int k = 0; k < D; ++k) row.push_back(F[k]);
    row.push_back(load);
    if (load > peak_[p]) {
      peak_[p] = load;
      peak_disp_[p] = disp;
    }
    if (p == stop_platen_ && peak_[p] > 0 && load < (1 - c_.stop_drop_fraction) * peak_[p]) stop = true;
  }
  for (const auto& r : sim.reactions())
    for (int k = 0; k < D; ++k) row.push_back(r[k]);
  for (const auto& nodes : monitor_nodes_) {
    double u[3];
    node_list_displacement<D>(sim.m, nodes, u);
    for (int k = 0; k < D; ++k) row.push_back(u[k]);
  }
  if (srf_) row.push_back(srf_at(last_.time));
  for (int k = 0; k < D; ++k) row.push_back(last_.momentum[k]);
  for (double e : {last_.kinetic, last_.strain, last_.interface_elastic, last_.contact_elastic,
                   last_.fracture, last_.damping, last_.friction, last_.work_external,
                   last_.balance_error, static_cast<double>(last_.damaged),
                   static_cast<double>(last_.failed)})
    row.push_back(e);
  return row;
}

template <int D>
bool HistoryTable<D>::write_row(const Simulation<D>& sim) {
  last_ = sim.energies();
  bool stop = false;
  const std::vector<double> row = make_row(sim, stop);
  file_->row(row);
  rows_.insert(rows_.end(), row.begin(), row.end());
  if (last_.scale > 0)
    max_rel_error_ = std::max(max_rel_error_, std::fabs(last_.balance_error) / last_.scale);
  return stop;
}

template <int D>
std::string HistoryTable<D>::joined_columns() const {
  std::string joined;
  for (const auto& col : cols_) joined += col + "\n";
  return joined;
}

template <int D>
void HistoryTable<D>::save(RunState& s) const {
  s.history_columns = joined_columns();
  s.history_rows = rows_;
  s.peak_load = peak_;
  s.peak_displacement = peak_disp_;
  s.max_relative_balance_error = max_rel_error_;
  s.last_row_energies = energies_to_vector(last_);
}

template <int D>
void HistoryTable<D>::restore(const RunState& s, const std::string& file) {
  if (s.history_columns != joined_columns())
    throw InputError("restart file '" + file + "': its history columns differ from this case's");
  if (s.history_rows.size() % cols_.size() != 0)
    throw InputError("restart file '" + file + "': history rows do not fit the columns");
  rows_ = s.history_rows;
  peak_ = s.peak_load;
  peak_disp_ = s.peak_displacement;
  max_rel_error_ = s.max_relative_balance_error;
  last_ = energies_from_vector(s.last_row_energies);
}

template class HistoryTable<2>;
template class HistoryTable<3>;

}  // namespace fdem
