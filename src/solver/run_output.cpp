#include "solver/run_output.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "solver/fragment_bodies.hpp"
#include "solver/fragment_parts.hpp"
#include "solver/interface_materials.hpp"
#include "solver/local_setup.hpp"
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
RunFragments<D>::RunFragments(const Simulation<D>& sim, const std::string& out, bool writes,
                              const RunState* restart, const std::string& file)
    : parts_(std::make_unique<PartFragments<D>>(sim)), comm_(&sim.parts().comm()), out_(out) {
  open_csv(restart, file, writes);
}

template <int D>
const FragmentStats& RunFragments<D>::now(const Simulation<D>& sim) {
  if (step_ != sim.step_count) {
    const auto t0 = std::chrono::steady_clock::now();
    if (parts_) parts_->compute(sim);  // (collective)
    if (analysis_) analysis_->compute(sim.m);
    label_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++labellings_;
    step_ = sim.step_count;
  }
  return parts_ ? parts_->last() : analysis_->last();
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
void RunFragments<D>::element_ids(const Simulation<D>& sim, std::vector<int>& ids, bool whole) {
  now(sim);
  if (analysis_) return analysis_->element_ids(ids);
  parts_->element_ids(ids);  // (collective) the own elements'
  if (!whole) return;
  std::vector<double> v(ids.begin(), ids.end());
  sim.parts().gather_to_root(v, ids.size(), 1, sim.parts().elem_global(), sim.parts().whole_elems());
  ids.assign(v.begin(), v.end());  // process 0: the whole mesh's; the others: none
}

template <int D>
nlohmann::json RunFragments<D>::summary(const Simulation<D>& sim) {
  const FragmentStats& fs = now(sim);
  nlohmann::json largest, pb;
  std::vector<double> masses;
  if (parts_) {
    typename PartFragments<D>::Ends ends = parts_->ends(sim);  // (collective)
    if (!sim.parts().root()) return nullptr;  // a process that does not write
    masses = parts_->masses();
    largest = std::move(ends.largest);
    if (!ends.bodies.empty()) pb = bodies_summary(ends.bodies);
  } else {
    masses = analysis_->masses();
    std::vector<int> frag;
    analysis_->element_ids(frag);
    std::vector<double> emass, centroid;
    element_mass_centroids<D>(sim.m, emass, centroid);
    FragmentPieces pieces;
    for (size_t e = 0; e < frag.size(); ++e) {
      double mc[3];
      for (int k = 0; k < 3; ++k) mc[k] = emass[e] * centroid[3 * e + k];
      pieces.add(frag[e], emass[e], mc, &centroid[3 * e], &centroid[3 * e]);
    }
    largest = largest_fragments(pieces, masses, D);
    if (bodies_ >= 2) pb = bodies_summary(body_fragments(body_, bodies_, frag, masses, emass, centroid));
  }
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
nlohmann::json RunFragments<D>::labelling_report() const {
  return {{"count", labellings_},
          {"wall_seconds", label_seconds_},
          {"gathered_bytes_last", parts_ ? parts_->gathered_bytes() : 0.0}};
}

// More than one initial body: out/bodies.csv and summary.json fragments.per_body.
template <int D>
nlohmann::json RunFragments<D>::bodies_summary(const std::vector<BodyFragments>& b) const {
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

namespace {
// The rows this process writes: its model's own items, with their whole-mesh indices.
template <int D>
OwnRows rows_written(const Simulation<D>& sim) {
  const auto w = sim.whole_rows();  // (references to the decomposition's lists)
  return {D,
          w.nn,
          w.ne,
          w.ni,
          w.nodes.data(),
          w.elems.data(),
          w.ifaces.data(),
          static_cast<size_t>(sim.m.owned_nodes()),
          static_cast<size_t>(sim.m.owned_elems()),
          static_cast<size_t>(sim.m.owned_ifaces())};
}
}  // namespace

template <int D>
RunSnapshots<D>::RunSnapshots(const Case& c, const std::string& out, const SubMesh& part, bool writes)
    : case_(&c), out_(out) {
  if (!(c.snapshot_interval > 0)) return;
  rows_ = &part;
  if (!writes) {
    gathers_ = true;
    return;
  }
  MeshShell shell;
  shell.dim = D;
  shell.nodes = part.whole_nodes;
  shell.elems = part.whole_elems;
  shell.ifaces = part.whole_ifaces;
  shell.region_names = part.mesh.region_names;
  writer_ = std::make_unique<SnapshotWriter>(out, shell);
}

template <int D>
void RunSnapshots<D>::mesh_from_parts(const Simulation<D>& sim, bool own_rows) {
  const SubMesh& s = *rows_;
  rows_ = nullptr;
  const Case& c = *case_;
  if (!own_rows) {  // (the serial HDF5, or FDEM_GATHER_OUTPUT=1)
    const HostMesh whole = gather_whole_mesh(sim.parts().comm(), s);
    if (!writer_) return;
    writer_->write_mesh(whole);
    const InterfaceMaterialMap map = interface_material_map(c, whole);
    std::vector<std::string> names;
    for (const auto& im : c.interface_materials) names.push_back(im.name);
    if (!map.material.empty()) writer_->add_interface_fields(names, map.material, map.scale);
    return;
  }
  // (the same choice on every process, from the case: the datasets are created together)
  const bool fields = s.whole_ifaces > 0 && interface_fields_wanted(c);
  const bool strength = fields && !c.scatter.distribution.empty();
  if (writer_) {
    std::vector<std::string> names;
    for (const auto& im : c.interface_materials) names.push_back(im.name);
    if (fields) writer_->interface_fields_by_rows(names, strength);
    writer_->close_file();
  }
  const HostMesh& m = s.mesh;
  const int npe = D + 1;
  std::vector<int> elems(static_cast<size_t>(m.owned_elems) * npe), ifaces(static_cast<size_t>(m.owned_ifaces) * D);
  for (size_t i = 0; i < elems.size(); ++i) elems[i] = s.node_global[m.elems[i]];
  for (int q = 0; q < m.owned_ifaces; ++q)
    for (int k = 0; k < D; ++k)
      ifaces[static_cast<size_t>(q) * D + k] = s.node_global[m.ifaces[static_cast<size_t>(q) * 2 * D + k]];
  std::vector<int> region(static_cast<size_t>(m.owned_elems), 0);
  if (m.elem_region.size() >= region.size()) std::copy_n(m.elem_region.begin(), region.size(), region.begin());
  std::vector<int> material;
  std::vector<double> factor;
  if (fields) {
    const InterfaceMaterialMap map = interface_material_map(c, m);
    material.assign(static_cast<size_t>(m.owned_ifaces), c.fracture_material);
    if (!map.material.empty()) std::copy_n(map.material.begin(), material.size(), material.begin());
    if (strength) factor.assign(map.scale.begin(), map.scale.begin() + m.owned_ifaces);
  }
  MeshPart p;
  static_cast<OwnRows&>(p) = rows_written(sim);  // (the model's items are the part's, in its order)
  p.X = m.X.data();
  p.elements = elems.data();
  p.region = region.data();
  p.interfaces = ifaces.data();
  p.with_material = fields;
  p.material = material.data();
  p.with_strength = strength;
  p.strength = factor.data();
  frames_->write_mesh(out_, p);
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
  if (rows_) mesh_from_parts(sim, own_rows);
  sim.download(x_, u_, v_, stress_, damage_, !own_rows);  // else gathered on process 0
  if (frag) frag->element_ids(sim, fragment_, !own_rows);  // (collective)
  if (own_rows) {
    if (writer_) writer_->close_file();  // (after its /mesh; a no-op from the second frame on)
    FramePart p;
    static_cast<OwnRows&>(p) = rows_written(sim);
    p.time = sim.t;
    p.step = sim.step_count;
    p.x = x_.data();
    p.u = u_.data();
    p.v = v_.data();
    p.stress = stress_.data();
    p.damage = damage_.data();
    p.has_fragment = frag != nullptr;
    p.fragment = frag ? fragment_.data() : nullptr;
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
