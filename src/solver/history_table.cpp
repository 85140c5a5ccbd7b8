#include "solver/history_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/error.hpp"

namespace fdem {

namespace {
const char* const kAxes[3] = {"x", "y", "z"};
}  // namespace

template <int D>
HistoryTable<D>::HistoryTable(const Case& c, const HostMesh& mesh, const Simulation<D>& sim, const HostMesh* part)
    : c_(c) {
  const int np = sim.m.platens.count;
  peak_.assign(np, 0.0);
  peak_disp_.assign(np, 0.0);
  srf_ = c.srf_initial != 1.0 || c.srf_rate > 0;
  for (int p = 0; p < np; ++p)
    if (sim.platen_names()[p] == c.stop_platen) stop_platen_ = p;
  add_columns(sim, mesh, part);
  set_load_window(c, part ? *part : mesh, &sim.parts().comm());
}

// The load window: the P-wave transit time across the body along the stop platen's normal (the
// largest extent along any platen's normal without a stop rule), in the slowest material of the
// case, at most end_time / 10; 32 load samples per window. comm: the extent over every process's
// nodes (their union is the whole mesh's: the same window on each; one process: its own).
template <int D>
void HistoryTable<D>::set_load_window(const Case& c, const HostMesh& mesh, const Comm* comm) {
  double c_min = std::numeric_limits<double>::infinity();
  for (const auto& rm : c.region_material) {
    if (rm.second < 0 || rm.second >= static_cast<int>(c.materials.size())) continue;
    const BulkMaterial& m = c.materials[rm.second];
    const double nu = m.nu;
    const double modulus =
        (D == 2 && c.plane_stress) ? m.E / (1 - nu * nu) : m.E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    if (m.density > 0 && modulus > 0) c_min = std::min(c_min, std::sqrt(modulus / m.density));
  }
  double extent = 0;
  for (const auto& P : c.platens) {
    if (stop_platen_ >= 0 && P.name != c.stop_platen) continue;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      double s = 0;
      for (int k = 0; k < D; ++k) s += mesh.X[static_cast<size_t>(i) * D + k] * P.normal[k];
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    double v[2] = {lo, -hi};
    comm->min(v, 2);
    lo = v[0];
    hi = -v[1];
    if (hi > lo) extent = std::max(extent, hi - lo);
  }
  window_ = c.end_time / 10;
  if (extent > 0 && std::isfinite(c_min)) window_ = std::min(window_, extent / c_min);
  sample_dt_ = window_ / 32;
}

template <int D>
void HistoryTable<D>::add_columns(const Simulation<D>& sim, const HostMesh& mesh, const HostMesh* part) {
  cols_ = {"time [s]", "step"};
  sim.platens().add_columns(cols_);
  sim.loads().add_columns(cols_);
  for (const auto& name : c_.monitors) {
    monitor_count_.push_back(part ? part->whole_set_size.at(name) : static_cast<long>(mesh.node_sets.at(name).size()));
    const auto& nodes = (part ? *part : mesh).node_sets.at(name);
    Kokkos::View<int*> v("fdem::monitor", nodes.size());
    auto vh = Kokkos::create_mirror_view(v);
    for (size_t j = 0; j < nodes.size(); ++j) vh(j) = nodes[j];
    Kokkos::deep_copy(v, vh);
    monitor_nodes_.push_back(v);
    for (int k = 0; k < D; ++k) cols_.push_back(name + "_u" + kAxes[k] + " [m]");
  }
  if (srf_) cols_.push_back("strength_reduction_factor");
  for (int k = 0; k < D; ++k) cols_.push_back(std::string("momentum_") + kAxes[k] + " [N s]");
  for (const std::string& e : energy_columns()) cols_.push_back(e);  // the ledger's (solver/ledger.hpp)
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
std::vector<double> HistoryTable<D>::make_row(const Simulation<D>& sim) {
  std::vector<double> row = {last_.time, static_cast<double>(last_.step)};
  sim.platens().append_row(sim.m, sim.platen_forces(), last_.time, row);
  sim.loads().append_row(row);
  for (size_t i = 0; i < monitor_nodes_.size(); ++i) {
    double u[3];
    node_list_displacement<D>(sim.m, monitor_nodes_[i], u);
    if (sim.parts().many()) {  // each process's own nodes of the set: the mean over all
      const double here = static_cast<double>(monitor_nodes_[i].extent(0));
      for (int k = 0; k < 3; ++k) u[k] *= here;
      sim.parts().sum(u, 3);
      for (int k = 0; k < 3; ++k) u[k] /= static_cast<double>(std::max(1L, monitor_count_[i]));
    }
    for (int k = 0; k < D; ++k) row.push_back(u[k]);
  }
  if (srf_) row.push_back(srf_at(last_.time));
  for (int k = 0; k < D; ++k) row.push_back(last_.momentum[k]);
  append_energy_row(last_, row);
  return row;
}

template <int D>
void HistoryTable<D>::write_row(const Simulation<D>& sim) {
  last_ = sim.energies();
  const std::vector<double> row = make_row(sim);
  if (file_) file_->row(row);  // not opened on the processes that do not write (a run over several)
  rows_.insert(rows_.end(), row.begin(), row.end());
  check_balance(last_);
}

template <int D>
bool HistoryTable<D>::sample_loads(const Simulation<D>& sim, double t0) {
  if (!(sample_dt_ > 0) || t0 < next_sample_ * (1 - 1e-12)) return false;
  // the next sample: the first step at or after the next multiple of the interval
  next_sample_ = sample_dt_ * (std::floor(t0 / sample_dt_ * (1 + 1e-12)) + 1);
  bool stop = false;
  const auto forces = sim.platen_forces();  // one copy from the device for all platens
  for (int p = 0; p < sim.m.platens.count; ++p) {
    const auto& F = forces[p];
    const auto& P = sim.m.platens.p[p];
    const double load = Platens<D>::load(P, F);
    if (load > peak_[p]) {
      peak_[p] = load;
      peak_disp_[p] = sim.platen_displacement(p, t0);
    }
    if (p != stop_platen_) continue;
    if (first_sample_ < 0) first_sample_ = t0;
    recent_.emplace_back(t0, load);
    while (recent_.front().first <= t0 - window_ * (1 - 1e-12)) recent_.pop_front();
    if (t0 - first_sample_ < window_ * (1 - 1e-12)) continue;  // the first window is not full yet
    double sum = 0;
    for (const auto& s : recent_) sum += s.second;
    const double mean = sum / static_cast<double>(recent_.size());
    smooth_peak_ = std::max(smooth_peak_, mean);
    if (smooth_peak_ > 0 && mean < (1 - c_.stop_drop_fraction) * smooth_peak_) {
      stop = true;
      stop_at_ = t0;
    }
  }
  return stop;
}

template <int D>
void HistoryTable<D>::check_balance(const Energies& e) {
  // (the first steps are left out, as by Simulation::check_stability: the energy scale is then
  // the round-off floor and the start-up of the work accounting is not a balance error)
  if (!(e.scale > 0) || e.step < 10) return;
  const double rel = std::fabs(e.balance_error) / e.scale;
  max_rel_error_ = std::max(max_rel_error_, rel);
  if (warn_time_ >= 0 || !(rel > kBalanceWarning)) return;
  warn_time_ = e.time;
  warn_step_ = e.step;
  warn_error_ = rel;
  std::fprintf(stderr,
               "fdem: warning: energy balance error %.3g %% of the energy scale (%.3e J) at step %ld, "
               "t = %.4e s (warning above %.0f %%; the run stops at 50 %%). Energy appears or vanishes "
               "without work: check the mesh (duplicate nodes, overlapping bodies), the time step and "
               "the contact and platen stiffnesses.\n",
               100 * rel, e.scale, e.step, e.time, 100 * kBalanceWarning);
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
  s.load_samples = {next_sample_, first_sample_, smooth_peak_, stop_at_};
  for (const auto& r : recent_) s.load_samples.insert(s.load_samples.end(), {r.first, r.second});
  s.balance_warning = {warn_time_, static_cast<double>(warn_step_), warn_error_};
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
  last_ = energies_from_vector(s.last_row_energies, "run/last_row_energies");
  // (checkpoints written before the load sampling and the balance warning lack them: the
  // sampling then starts afresh and the warning is taken as given when the error is above it)
  const std::vector<double>& ls = s.load_samples;
  if (ls.size() >= 4 && ls.size() % 2 == 0) {
    next_sample_ = ls[0];
    first_sample_ = ls[1];
    smooth_peak_ = ls[2];
    stop_at_ = ls[3];
    recent_.clear();
    for (size_t k = 4; k < ls.size(); k += 2) recent_.emplace_back(ls[k], ls[k + 1]);
  } else {
    next_sample_ = sample_dt_ * (std::floor(last_.time / sample_dt_) + 1);
  }
  if (s.balance_warning.size() == 3) {
    warn_time_ = s.balance_warning[0];
    warn_step_ = static_cast<long>(s.balance_warning[1]);
    warn_error_ = s.balance_warning[2];
  } else if (max_rel_error_ > kBalanceWarning) {
    warn_time_ = 0;
    warn_error_ = max_rel_error_;
  }
}

template class HistoryTable<2>;
template class HistoryTable<3>;

}  // namespace fdem
