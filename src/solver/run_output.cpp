#include "solver/run_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "solver/fragment_bodies.hpp"
#include "solver/interface_materials.hpp"
#include "solver/model_builder.hpp"

namespace fdem {

// ---- OutputSchedule ----

OutputSchedule::OutputSchedule(const Case& c, double checkpoint_every)
    : hist_dt_(c.history_interval > 0 ? c.history_interval : c.end_time / 200),
      snap_dt_(c.snapshot_interval),
      ckpt_dt_(checkpoint_every),
      check_every_(c.check_interval),
      next_snap_(c.snapshot_interval),
      next_ckpt_(checkpoint_every) {}

void OutputSchedule::stepped(bool row) {
  last_was_row_ = row;
  if (row) next_hist_ += hist_dt_;
}

bool OutputSchedule::take_snapshot(double t) {
  if (!(snap_dt_ > 0 && t >= next_snap_ * (1 - 1e-12))) return false;
  next_snap_ += snap_dt_;
  return true;
}

bool OutputSchedule::take_checkpoint(double t) {
  if (!(ckpt_dt_ > 0 && t >= next_ckpt_ * (1 - 1e-12))) return false;
  while (next_ckpt_ <= t * (1 + 1e-12)) next_ckpt_ += ckpt_dt_;
  return true;
}

void OutputSchedule::check_checkpoint_interval(double dt, const std::string& source,
                                               const std::string& file) const {
  if (ckpt_dt_ == 0 || (std::isfinite(ckpt_dt_) && ckpt_dt_ >= dt)) return;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "%s = %.4g s is not 0 (no checkpoints) or a finite time of at least one step "
                "(dt = %.4g s)",
                source.c_str(), ckpt_dt_, dt);
  throw InputError(file + ": " + buf);
}

void OutputSchedule::save(RunState& s) const {
  s.next_history = next_hist_;
  s.next_snapshot = next_snap_;
  s.next_checkpoint = next_ckpt_;
  s.checkpoint_every = ckpt_dt_;
  s.last_was_row = last_was_row_;
}

void OutputSchedule::restore(const RunState& s, double t) {
  next_hist_ = s.next_history;
  next_snap_ = s.next_snapshot;
  if (ckpt_dt_ > 0) {  // the next checkpoint after the restart point
    next_ckpt_ = s.next_checkpoint;
    if (!(next_ckpt_ > 0) || s.checkpoint_every != ckpt_dt_) {
      next_ckpt_ = ckpt_dt_ * std::floor(t / ckpt_dt_);
      while (next_ckpt_ <= t * (1 + 1e-12)) next_ckpt_ += ckpt_dt_;
    }
  }
  last_was_row_ = s.last_was_row != 0;
}

// ---- RunFragments ----

namespace {
std::vector<std::string> fragment_columns() {
  std::vector<std::string> fc = {"time [s]", "step", "fragments", "largest_fraction",
                                 "largest_mass [kg]", "total_mass [kg]", "single_element_fragments"};
  for (int b = 0; b < kFragmentBins; ++b) fc.push_back("count_" + FragmentStats::bin_name(b));
  for (int b = 0; b < kFragmentBins; ++b) fc.push_back("mass_" + FragmentStats::bin_name(b));
  return fc;
}

// The ten largest fragments where their material was at the start: share of the mass, the
// mass-weighted centroid and the box of their elements' centroids in the reference configuration
// (a fracture pattern is read from these: halves split through an axis, caps, cones).
// frag: each element's fragment id; masses: each fragment's.
nlohmann::json largest_fragments(const std::vector<int>& frag, const std::vector<double>& masses,
                                 const std::vector<double>& emass, const std::vector<double>& centroid, int dim) {
  std::vector<int> order(masses.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&masses](int a, int b) { return masses[a] > masses[b]; });
  if (order.size() > 10) order.resize(10);
  std::vector<int> rank(masses.size(), -1);
  for (size_t r = 0; r < order.size(); ++r) rank[order[r]] = static_cast<int>(r);
  const size_t n = order.size(), d = static_cast<size_t>(dim);
  std::vector<double> m(n, 0.0), c(n * d, 0.0), lo(n * d, std::numeric_limits<double>::infinity()),
      hi(n * d, -std::numeric_limits<double>::infinity());
  double total = 0;
  for (size_t e = 0; e < frag.size(); ++e) {
    total += emass[e];
    const int r = frag[e] >= 0 ? rank[frag[e]] : -1;
    if (r < 0) continue;
    m[r] += emass[e];
    for (size_t k = 0; k < d; ++k) {
      const double x = centroid[e * d + k];
      c[r * d + k] += emass[e] * x;
      lo[r * d + k] = std::min(lo[r * d + k], x);
      hi[r * d + k] = std::max(hi[r * d + k], x);
    }
  }
  nlohmann::json out = nlohmann::json::array();
  for (size_t r = 0; r < n; ++r) {
    std::vector<double> cr(d), lr(d), hr(d);
    for (size_t k = 0; k < d; ++k) {
      cr[k] = m[r] > 0 ? c[r * d + k] / m[r] : 0.0;
      lr[k] = lo[r * d + k];
      hr[k] = hi[r * d + k];
    }
    out.push_back({{"fraction", total > 0 ? m[r] / total : 0.0},
                   {"reference_centroid", cr},
                   {"reference_box_min", lr},
                   {"reference_box_max", hr}});
  }
  return out;
}
}  // namespace

template <int D>
RunFragments<D>::RunFragments(const Model<D>& m, const std::string& out, const RunState* restart,
                              const std::string& file)
    : analysis_(std::make_unique<FragmentAnalysis<D>>(m)), out_(out) {
  bodies_ = initial_bodies<D>(m, body_);
  open_csv(restart, file, true);
}

// out/fragments.csv: a new one, or a restart's: the checkpoint's rows (those a killed run wrote
// after the checkpoint are dropped), then on.
template <int D>
void RunFragments<D>::open_csv(const RunState* restart, const std::string& file, bool writes) {
  const std::vector<std::string> cols = fragment_columns();
  if (restart) {
    rows_ = restart->fragment_rows;
    if (rows_.size() % cols.size() != 0)
      throw InputError("checkpoint '" + file + "': run/fragment_rows has " + std::to_string(rows_.size()) +
                       " values, not whole rows of the " + std::to_string(cols.size()) +
                       " fragments.csv columns (the file is damaged)");
  }
  if (!writes) return;
  const std::string path = out_ + "/fragments.csv";
  csv_ = restart ? std::make_unique<HistoryWriter>(path, cols, rows_) : std::make_unique<HistoryWriter>(path, cols);
}

template <int D>
RunFragments<D>::RunFragments(const Simulation<D>& sim, const Case& c, const HostMesh& whole, const std::string& out,
                              bool writes, const RunState* restart, const std::string& file)
    : comm_(&sim.parts().comm()), out_(out) {
  open_csv(restart, file, writes);
  if (!writes) return;
  // the whole mesh's elements, masses and interfaces (the arrays the labelling reads)
  whole_ = std::make_unique<Model<D>>();
  Model<D>& w = *whole_;
  w.nn = whole.num_nodes();
  w.ne = whole.num_elems();
  w.ni = whole.num_ifaces();
  w.thickness = sim.m.thickness;
  const MaterialTable mats = build_materials<D>(c, whole, w);
  build_elements<D>(c, whole, mats, w);
  w.iface = Kokkos::View<int* [2 * D]>("fdem::fragments::iface", w.ni);
  w.ihist = Kokkos::View<double* [D][kPointHistory]>("fdem::fragments::ihist", w.ni);
  // reference positions: the per-body statistics (several initial bodies) place the fragments
  w.X = Kokkos::View<double* [D]>("fdem::fragments::X", w.nn);
  auto Xh = Kokkos::create_mirror_view(w.X);
  for (int n = 0; n < w.nn; ++n)
    for (int k = 0; k < D; ++k) Xh(n, k) = whole.X[static_cast<size_t>(n) * D + k];
  Kokkos::deep_copy(w.X, Xh);
  auto fc = Kokkos::create_mirror_view(w.iface);
  for (int q = 0; q < w.ni; ++q)
    for (int k = 0; k < 2 * D; ++k) fc(q, k) = whole.ifaces[static_cast<size_t>(q) * 2 * D + k];
  Kokkos::deep_copy(w.iface, fc);
  analysis_ = std::make_unique<FragmentAnalysis<D>>(w);
  bodies_ = initial_bodies<D>(w, body_);
}

// Every process's counted interfaces' histories (with their whole-mesh indices) into whole_ on
// process 0.
template <int D>
void RunFragments<D>::gather_histories(const Simulation<D>& sim) {
  const size_t own = static_cast<size_t>(sim.m.owned_ifaces()), w = kPointHistory * D;
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  Kokkos::deep_copy(h, sim.m.ihist);
  std::vector<double> rows(own * w);
  for (size_t q = 0; q < own; ++q)
    for (int k = 0; k < D; ++k)
      for (int a = 0; a < kPointHistory; ++a) rows[q * w + kPointHistory * k + a] = h(q, k, a);
  const std::vector<double> all =
      gather_rows(*comm_, rows.data(), own, w, sim.ifaces_global(), whole_ ? static_cast<size_t>(whole_->ni) : 0);
  if (!whole_) return;
  auto wh = Kokkos::create_mirror_view(whole_->ihist);
  for (int q = 0; q < whole_->ni; ++q)
    for (int k = 0; k < D; ++k)
      for (int a = 0; a < kPointHistory; ++a) wh(q, k, a) = all[q * w + kPointHistory * k + a];
  Kokkos::deep_copy(whole_->ihist, wh);
}

template <int D>
const FragmentStats& RunFragments<D>::now(const Simulation<D>& sim) {
  if (step_ != sim.step_count) {
    if (comm_) gather_histories(sim);
    if (analysis_) analysis_->compute(whole_ ? *whole_ : sim.m);
    step_ = sim.step_count;
  }
  return analysis_ ? analysis_->last() : none_;
}

template <int D>
void RunFragments<D>::write_row(const Simulation<D>& sim, const Energies& e) {
  const FragmentStats& fs = now(sim);  // the interface history is that of x(n), the instant of the row
  std::vector<double> fr = {e.time, static_cast<double>(e.step), double(fs.count),
                            fs.largest_fraction, fs.largest_mass, fs.total_mass,
                            double(fs.single_element)};
  for (int b = 0; b < kFragmentBins; ++b) fr.push_back(fs.bin_count[b]);
  for (int b = 0; b < kFragmentBins; ++b) fr.push_back(fs.bin_mass_fraction[b]);
  if (csv_) csv_->row(fr);  // only process 0 writes (a run over several processes)
  rows_.insert(rows_.end(), fr.begin(), fr.end());
}

template <int D>
void RunFragments<D>::element_ids(const Simulation<D>& sim, std::vector<int>& ids) {
  now(sim);
  if (analysis_) analysis_->element_ids(ids);  // the whole mesh's, on process 0 of several
}

template <int D>
nlohmann::json RunFragments<D>::summary(const Simulation<D>& sim) {
  const FragmentStats& fs = now(sim);
  if (!analysis_) return nullptr;  // a process that does not write
  std::vector<double> masses = analysis_->masses();
  std::sort(masses.begin(), masses.end(), [](double a, double b) { return a > b; });
  std::vector<double> top;
  for (size_t i = 0; i < masses.size() && i < 10; ++i)
    top.push_back(fs.total_mass > 0 ? masses[i] / fs.total_mass : 0.0);
  std::vector<std::string> edges;
  for (int b = 0; b < kFragmentBins; ++b) edges.push_back(FragmentStats::bin_name(b));
  // The cumulative mass distribution on a fixed grid, so that an ensemble can average it
  // (src/solver/ensemble_report.cpp): the share of the mass in fragments of at least x of it, at
  // x = 10^(-k/4), k = 0 ... 28 (1 down to 1e-7).
  std::vector<double> at_least, held;
  double sum = 0;
  for (int k = 0, i = 0; k <= 28; ++k) {
    const double x = std::pow(10.0, -0.25 * k);
    for (; i < static_cast<int>(masses.size()) && masses[i] >= x * fs.total_mass; ++i) sum += masses[i];
    at_least.push_back(x);
    held.push_back(fs.total_mass > 0 ? sum / fs.total_mass : 0.0);
  }
  std::vector<int> frag;
  element_ids(sim, frag);
  std::vector<double> emass, centroid;
  element_mass_centroids<D>(whole_ ? *whole_ : sim.m, emass, centroid);
  const nlohmann::json largest = largest_fragments(frag, analysis_->masses(), emass, centroid, D);
  nlohmann::json pb = per_body(frag, emass, centroid);
  nlohmann::json out = {
      {"count", fs.count},
      {"largest_fraction", fs.largest_fraction},
      {"largest_mass_kg", fs.largest_mass},
      {"total_mass_kg", fs.total_mass},
      {"single_element_fragments", fs.single_element},
      {"largest_fractions", top},
      {"largest", largest},
      {"distribution",
       {{"bin_lower_edge", edges},
        {"count", std::vector<double>(fs.bin_count.begin(), fs.bin_count.end())},
        {"mass_fraction", std::vector<double>(fs.bin_mass_fraction.begin(), fs.bin_mass_fraction.end())}}},
      {"cumulative_mass", {{"fragment_fraction_at_least", at_least}, {"mass_fraction", held}}}};
  if (!pb.is_null()) out["per_body"] = pb;
  return out;
}

template <int D>
nlohmann::json RunFragments<D>::per_body(const std::vector<int>& frag, const std::vector<double>& emass,
                                         const std::vector<double>& centroid) {
  if (bodies_ < 2 || !analysis_) return nullptr;  // (over several processes: process 0's)
  const auto b = body_fragments(body_, bodies_, frag, analysis_->masses(), emass, centroid);
  write_bodies_csv(out_ + "/bodies.csv", b, D);
  return body_fragments_summary(b, out_ + "/bodies.csv");
}

// ---- RunSnapshots ----

template <int D>
RunSnapshots<D>::RunSnapshots(const Case& c, const std::string& out, const HostMesh& mesh,
                              const RunState* restart, bool writes)
    : out_(out) {
  if (restart) last_step_ = static_cast<long>(restart->last_snapshot_step);
  if (!(c.snapshot_interval > 0)) return;
  if (!writes) {
    gathers_ = true;
    return;
  }
  if (restart) {
    const std::vector<long> steps(restart->snapshot_steps.begin(), restart->snapshot_steps.end());
    std::string note;
    writer_ = std::make_unique<SnapshotWriter>(out, mesh, steps, restart->snapshot_times, note);
    if (!note.empty()) std::fprintf(stderr, "fdem: warning: %s\n", note.c_str());
  } else {
    writer_ = std::make_unique<SnapshotWriter>(out, mesh);
  }
  const InterfaceMaterialMap map = interface_material_map(c, mesh);
  if (!map.material.empty()) {
    std::vector<std::string> names;
    for (const auto& im : c.interface_materials) names.push_back(im.name);
    writer_->add_interface_fields(names, map.material, map.scale);
  }
}

bool gather_outputs() {
  const char* g = std::getenv("FDEM_GATHER_OUTPUT");
  return g && std::string(g) == "1";
}

template <int D>
bool RunSnapshots<D>::parallel(const Simulation<D>& sim) {
  if (parallel_ >= 0) return parallel_ == 1;
  parallel_ = 0;
  if (!sim.parts().many()) return false;
  if (gather_outputs()) return false;
  const long long fapl = sim.parts().comm().h5_parallel_access();  // (collective)
  if (fapl < 0) return false;
  frames_ = std::make_unique<ParallelFrames>(fapl);
  parallel_ = 1;
  return true;
}

template <int D>
void RunSnapshots<D>::take(Simulation<D>& sim, RunFragments<D>* frag) {
  if ((!writer_ && !gathers_) || sim.step_count == last_step_) return;
  last_step_ = sim.step_count;
  const bool own_rows = parallel(sim);
  sim.download(x_, u_, v_, stress_, damage_, !own_rows);  // else gathered on process 0
  if (frag) frag->element_ids(sim, fragment_);  // (over several processes: on process 0)
  if (own_rows) {
    if (writer_) writer_->close_file();  // (after its /mesh; a no-op from the second frame on)
    const auto w = sim.whole_rows();
    FramePart p;
    p.time = sim.t;
    p.step = sim.step_count;
    p.dim = D;
    p.whole_nodes = w.nn;
    p.whole_elems = w.ne;
    p.whole_ifaces = w.ni;
    p.node_ids = w.nodes.data();
    p.elem_ids = w.elems.data();
    p.iface_ids = w.ifaces.data();
    p.nodes = static_cast<size_t>(sim.m.owned_nodes());
    p.elems = static_cast<size_t>(sim.m.owned_elems());
    p.ifaces = static_cast<size_t>(sim.m.owned_ifaces());
    p.x = x_.data();
    p.u = u_.data();
    p.v = v_.data();
    p.stress = stress_.data();
    p.damage = damage_.data();
    p.has_fragment = frag != nullptr;
    p.fragment = frag && writer_ ? fragment_.data() : nullptr;
    frames_->write(out_, p);
    if (writer_) writer_->frame_written(sim.t, sim.step_count, frag != nullptr);
    return;
  }
  if (!writer_) return;
  SnapshotFrame fr;
  fr.time = sim.t;
  fr.step = sim.step_count;
  fr.x = x_.data();
  fr.u = u_.data();
  fr.v = v_.data();
  fr.stress = stress_.data();
  fr.damage = damage_.data();
  if (frag) fr.fragment = fragment_.data();
  writer_->write(fr);
}

template <int D>
void RunSnapshots<D>::save(RunState& s) const {
  s.last_snapshot_step = last_step_;
  s.snapshot_steps.clear();
  s.snapshot_times.clear();
  if (writer_) {
    for (long x : writer_->steps()) s.snapshot_steps.push_back(x);
    s.snapshot_times = writer_->times();
  }
}

template class RunFragments<2>;
template class RunFragments<3>;
template class RunSnapshots<2>;
template class RunSnapshots<3>;

}  // namespace fdem
