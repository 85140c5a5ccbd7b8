#include "solver/run_loop.hpp"

#include <cmath>
#include <csignal>
#include <cstdio>
#include <stdexcept>
#include <tuple>

#include "common/huge_pages.hpp"
#include "common/setup_times.hpp"
#include "io/output.hpp"
#include "solver/kept_mesh.hpp"
#include "solver/stable_step.hpp"
#include "solver/summary.hpp"
#include "solver/whole_state.hpp"

namespace fdem {

namespace {
double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }
}  // namespace

template <int D>
RunLoop<D>::RunLoop(const Case& c, std::shared_ptr<const HostMesh> mesh, const std::string& out, const RunOptions& opt,
                    const RunIdentity& id, const StateArrays* restart, const SubMesh* part, CutHistory* cuts)
    : c_(c),
      mesh_(std::move(mesh)),
      out_(out),
      opt_(opt),
      id_(id),
      restart_(restart),
      cuts_(cuts ? cuts : &no_cuts_),
      wall0_(Clock::now()),
      loop0_(wall0_),
      snaps_(early_snapshots(part)),
      sim_(c, model_source(part)),
      boundary_nodes_(sim_.m.nb),
      schedule_(c, opt.checkpoint_every >= 0 ? opt.checkpoint_every : c.checkpoint_every) {
  parts_ = make_run_parts(sim_, opt, part, *cuts_, restart);
  writes_ = sim_.parts().root();
  schedule_.check_checkpoint_interval(
      sim_.dt, opt.checkpoint_every >= 0 ? "--checkpoint-every" : "output.checkpoint_every", c.file);
  setup_times::Phase outputs("output_setup");  // with the first snapshot (run())
  if (!part) counts_ = whole_counts(part);  // (over processes: before the model)
  whole_ifaces_ = counts_.at("interfaces").get<long>();
  if (restart) parts_->load(*restart);
  history_ = std::make_unique<HistoryTable<D>>(c, part ? part->mesh : *mesh_, sim_, history_part(part));
  // the part's mesh is read again only by the snapshots' first frame (when they write /mesh from
  // the parts): let go now, before the rest of the set-up adds its arrays, or after that frame
  // (take_snapshot)
  if (part && cuts_->part && !(snaps_ && snaps_->needs_part())) {
    setup_times::Phase released("part_mesh_released");
    release_part_mesh(*cuts_->part);
  }
  if (restart) {
    restore(*restart);
  } else {
    if (writes_) history_->open(out, false);
    if (fragments_on()) frag_ = parts_->fragments(out, nullptr, "");
    if (frag_) frag_->count_from(cuts_->labellings, cuts_->label_seconds);
    if (!snaps_) snaps_ = std::make_unique<RunSnapshots<D>>(c, out, *mesh_, nullptr, writes_);
  }
  mesh_.reset();  // about 350 B per tetrahedron with interfaces (docs/performance-impact.md, section 4)
  {  // its pages, and the set-up's other freed ones, back to the kernel (the run's growth, as its
     // contact lists', then adds to the Views alone: docs/performance-impact.md, section 4)
    setup_times::Phase released("heap_released");
    release_free_heap();
  }
  progress_ = std::make_unique<Progress>(opt.progress, sim_.step_count, sim_.t);
  announce();
  // quiet or not, on process 0 (a restart says it again)
  const std::string step_warning = contact_step_warning(sim_.stable, c.safety_factor, c.dt);
  if (writes_ && !began_at_cut() && !step_warning.empty())
    std::fprintf(stderr, "fdem: warning: %s\n", step_warning.c_str());
  // precision "mixed" has floats only in the host's fused force pass (kernels/forces.hpp)
  if (writes_ && !began_at_cut() && c.mixed_precision &&
      !Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible)
    std::fprintf(stderr, "fdem: warning: %s: precision \"mixed\" applies to host backends only; this build's "
                 "device computes in double\n", c.file.c_str());
  // the whole state of the cut these parts began at is taken: freed (every process received all
  // of it; the next cut gathers a new one)
  if (began_at_cut()) cuts_->state = StateArrays{};
}

// For summary.json and the checkpoint header. A process of several that holds no whole mesh (not
// process 0) takes the counts from its part, for the summary it does not write.
template <int D>
nlohmann::json RunLoop<D>::whole_counts(const SubMesh* part) const {
  if (!cuts_->mesh_report.is_null()) return cuts_->mesh_report;  // (summed over the processes)
  if (!part || opt_.comm->rank() == 0) return mesh_report(*mesh_);
  return {{"nodes", part->whole_nodes}, {"elements", part->whole_elems}, {"interfaces", part->whole_ifaces}};
}

template <int D>
std::unique_ptr<RunSnapshots<D>> RunLoop<D>::early_snapshots(const SubMesh* part) const {
  if (!part) return nullptr;
  setup_times::Phase outputs("output_setup");
  const bool root = opt_.comm->rank() == 0;
  if (cuts_->mesh_by_parts) return std::make_unique<RunSnapshots<D>>(c_, out_, *part, root);
  if (!restart_) return std::make_unique<RunSnapshots<D>>(c_, out_, *mesh_, nullptr, root);
  RunState s;  // (the snapshots' entries of the checkpoint)
  s.load(*restart_, static_cast<int>(c_.platens.size()));
  return std::make_unique<RunSnapshots<D>>(c_, out_, *mesh_, &s, root);
}

template <int D>
const HostMesh& RunLoop<D>::model_source(const SubMesh* part) {
  if (!part) return *mesh_;
  counts_ = whole_counts(part);
  mesh_.reset();  // (process 0: freed here unless the run over processes keeps it for its cuts)
  return part->mesh;
}

// The run loop's state from the checkpoint (every process of several: the same); history.csv,
// fragments.csv and snapshots.h5 (process 0's) cut back to it.
template <int D>
void RunLoop<D>::restore(const StateArrays& r) {
  RunState s;
  s.load(r, sim_.m.platens.count);
  history_->restore(s, r.file);
  schedule_.restore(s, sim_.t);
  prior_wall_ = s.wall_seconds;
  prior_loop_wall_ = s.loop_wall_seconds;
  ckpt_wall_ = s.checkpoint_seconds;
  ckpt_written_ = static_cast<long>(s.checkpoints_written);
  if (writes_) history_->open(out_, true);
  if (fragments_on()) frag_ = parts_->fragments(out_, &s, r.file);
  if (frag_) frag_->count_from(cuts_->labellings, cuts_->label_seconds);
  if (!snaps_) snaps_ = std::make_unique<RunSnapshots<D>>(c_, out_, *mesh_, &s, writes_);
}

template <int D>
void RunLoop<D>::announce() const {
  if (!opt_.progress || began_at_cut()) return;  // (a cut: said at the start)
  std::fprintf(stderr,
               "fdem: %s: %d nodes, %d elements, %d interfaces; dt = %.3e s (%.2f x critical %.3e s); "
               "%.0f steps to end_time\n",
               c_.name.c_str(), sim_.m.nn, sim_.m.ne, sim_.m.ni, sim_.dt, sim_.dt / sim_.stable.critical,
               sim_.stable.critical, std::ceil(c_.end_time / sim_.dt));
  parts_->announce();
  if (sim_.stable.contact_pending)
    std::fprintf(stderr,
                 "fdem: contact springs act once surfaces can meet (first failed interface); the critical "
                 "step is then %.3e s\n",
                 sim_.stable.critical_contact);
}

template <int D>
LoopEnd RunLoop<D>::run() {
  if (!restart_) {
    setup_times::Phase outputs("output_setup");
    take_snapshot();
  } else if (opt_.progress && began_at_cut()) {
    progress_->note("fdem: step " + std::to_string(sim_.step_count) + ": the parts cut anew at the current "
                    "positions (" + std::to_string(cuts_->recuts) + (cuts_->recuts == 1 ? " cut" : " cuts") +
                    " so far; " + cuts_->last_cut_reason + ")");
  } else if (opt_.progress) {
    std::fprintf(stderr,
                 "fdem: restarting from %s at step %ld, t = %.6e s (%zu history rows, %d snapshots kept)\n",
                 restart_->file.c_str(), sim_.step_count, sim_.t, history_->rows(), snaps_->frames());
  }
  setup_times::finish();
  if (opt_.progress && !began_at_cut()) std::fprintf(stderr, "fdem: %s\n", setup_times::line().c_str());
  std::string stop_reason = "end_time";
  loop0_ = Clock::now();
  pace_step0_ = sim_.step_count;
  pace_t0_ = sim_.t;
  while (next_tenth_ <= 10 && sim_.t >= 0.1 * next_tenth_ * c_.end_time) ++next_tenth_;  // (a restart)
  while (sim_.t < c_.end_time * (1 - 1e-12)) {
    if (const int sig = interrupt_signal()) {  // a signal (SIGINT, SIGTERM): stop after this step
      signal_ = sig;
      return interrupted();
    }
    if (c_.max_steps > 0 && sim_.step_count >= c_.max_steps) {
      stop_reason = "max_steps";
      break;
    }
    const bool row = schedule_.history_due(sim_.t);  // sampled at the start of the step
    const double t0 = sim_.t;
    step(row, row || schedule_.check_due(sim_.step_count));
    schedule_.stepped(row);
    if (row) history_row();
    if (history_->sample_loads(sim_, t0)) {  // on its own cadence, not the rows'
      stop_reason = "load_drop";
      break;
    }
    if (schedule_.take_snapshot(sim_.t)) take_snapshot();
    if (schedule_.take_checkpoint(sim_.t)) save_checkpoint();
    progress_->update(sim_.step_count, sim_.t, c_.end_time);
    mark_pace();
    if (sim_.recut_due()) return recut();
  }
  const double loop_wall = prior_loop_wall_ + seconds(Clock::now() - loop0_);
  progress_->update(sim_.step_count, sim_.t, c_.end_time, true);
  progress_->done();
  if (!schedule_.last_was_row()) final_row();
  take_snapshot();
  return {LoopEnd::Kind::finished, finish(stop_reason, loop_wall), {}};
}

// The run stopped by a signal after a step: a checkpoint of this moment (a restart goes on as if
// the run had not stopped), a snapshot (dropped by such a restart), summary.json, a message. No
// final history row: it would take one more step.
template <int D>
int RunLoop<D>::interrupt_signal() const {
  const int here = opt_.interrupt ? static_cast<int>(*opt_.interrupt) : 0;
  // (over several processes they look together, every few steps: RunParts::interrupt_poll; the
  // minimum over one process is its own)
  const long every = parts_->interrupt_poll();
  if (sim_.step_count % every != 0) return 0;
  double v = -static_cast<double>(here);
  sim_.parts().min(&v, 1);
  return static_cast<int>(-v);
}

// A snapshot. The first of a run whose whole mesh no process holds writes /mesh from the part's
// mesh, which is let go after it.
template <int D>
void RunLoop<D>::take_snapshot() {
  const bool first = snaps_->needs_part();
  snaps_->take(sim_, frag_.get());
  if (first && cuts_->part && !snaps_->needs_part()) release_part_mesh(*cuts_->part);
}

template <int D>
LoopEnd RunLoop<D>::interrupted() {
  const double loop_wall = prior_loop_wall_ + seconds(Clock::now() - loop0_);
  progress_->update(sim_.step_count, sim_.t, c_.end_time, true);
  progress_->done();
  const char* name = signal_ == SIGINT ? "SIGINT" : signal_ == SIGTERM ? "SIGTERM" : "a signal";
  save_checkpoint();
  take_snapshot();
  const std::string ck = out_ + "/checkpoint.h5";
  if (writes_)
    std::fprintf(stderr,
                 "fdem: interrupted by %s at step %ld, t = %.6e s; checkpoint %s written; go on with: fdem "
                 "run %s --restart %s (and the same --set options%s)\n",
                 name, sim_.step_count, sim_.t, ck.c_str(), c_.file.c_str(), ck.c_str(),
                 parts_->restart_note());
  if (writes_) std::fputs(parts_->exit_note(), stderr);
  return {LoopEnd::Kind::interrupted, finish("interrupted", loop_wall), {}};
}

// One step; `row`: sampled for a history row (reactions too), `check`: energies sampled and the
// stability checked after it.
template <int D>
void RunLoop<D>::step(bool row, bool check) {
  sim_.set_sample_reactions(row);
  if (history_->has_srf()) sim_.set_strength_reduction(history_->srf_at(sim_.t));
  if (c_.damping_change_time >= 0 && sim_.t >= c_.damping_change_time * (1 - 1e-12))
    sim_.set_damping(c_.damping_change_local, c_.damping_change_mass);
  sim_.step(check);
  if (check) {
    sim_.check_stability();
    history_->check_balance(sim_.energies());
  }
  if (sim_.dt_changed_at() == sim_.step_count - 1) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "fdem: step %ld, t = %.4e s: surfaces can meet, contact springs act: dt = %.3e -> %.3e s "
                  "(critical %.3e s)",
                  sim_.dt_changed_at(), sim_.t, sim_.dt_before_change(), sim_.dt, sim_.stable.critical);
    progress_->note(line);
  }
}

template <int D>
void RunLoop<D>::history_row() {
  history_->write_row(sim_);
  if (frag_) frag_->write_row(sim_, history_->last());
}

// The run ended between rows: one more sampled step for a row at its end.
template <int D>
void RunLoop<D>::final_row() {
  sim_.set_sample_reactions(true);
  sim_.step(true);
  sim_.check_stability();
  history_row();
}

template <int D>
bool RunLoop<D>::collect_state(StateArrays& st, Clock::time_point c0, long written,
                               std::vector<RowPart>* rows) {
  if (!parts_->save(st, rows)) return false;
  RunState s;
  history_->save(s);
  if (frag_) frag_->save(s);
  schedule_.save(s);
  snaps_->save(s);
  s.wall_seconds = prior_wall_ + seconds(c0 - wall0_);
  s.loop_wall_seconds = prior_loop_wall_ + seconds(c0 - loop0_);
  s.checkpoint_seconds = ckpt_wall_;
  s.checkpoints_written = written;
  s.save(st);
  return true;
}

template <int D>
double RunLoop<D>::cut_setup_seconds() const {
  return began_at_cut() ? seconds(loop0_ - wall0_) : 0.0;
}

template <int D>
LoopEnd RunLoop<D>::recut() {
  const auto c0 = Clock::now();
  const double busy = seconds(c0 - loop0_) - sim_.phase_times().exchange;
  StateArrays& st = cuts_->state;
  st = StateArrays{};
  collect_state(st, c0, ckpt_written_);
  st.f64["recut/mass_momentum"] = whole_mass_momentum(sim_);
  st.f64["recut/node_work"] = sim_.node_work_whole();  // (process 0: the weights of the cut)
  if (frag_) std::tie(cuts_->labellings, cuts_->label_seconds) = frag_->labelling();
  const auto& b = sim_.balance();
  // the cut's time: gathering the state here, the partition and the sending (solver/run.cpp), the
  // new parts' set-up (the next RunLoop's, until its loop starts); this part's own set-up if it
  // began at a cut
  LoopEnd end;
  end.kind = LoopEnd::Kind::cut_due;
  CutRequest& cut = end.cut;
  cut.reason = sim_.recut_reason();
  cut.excess = b.excess;
  cut.after_cut = b.after_cut;
  cut.largest = b.largest;
  cut.busy = busy;
  cut.gather_seconds = seconds(Clock::now() - c0);
  cut.setup_seconds = cut_setup_seconds();
  return end;
}

template <int D>
void RunLoop<D>::save_checkpoint() {
  const auto c0 = Clock::now();
  StateArrays st;
  std::vector<RowPart> rows;  // with the parallel HDF5: this process's rows, which it writes
  const Parts<D>& parts = sim_.parts();
  const long long fapl = parts_->checkpoint_access();  // >= 0: each process writes its rows (collective)
  if (!collect_state(st, c0, ckpt_written_ + 1, fapl >= 0 ? &rows : nullptr) && fapl < 0) {
    ++ckpt_written_;  // (process 0 writes the one file)
    ckpt_wall_ += seconds(Clock::now() - c0);
    return;
  }
  CheckpointHeader h;
  h.dim = D;
  h.nodes = counts_.at("nodes").get<long long>();  // the whole mesh's (over several processes too)
  h.elements = counts_.at("elements").get<long long>();
  h.interfaces = counts_.at("interfaces").get<long long>();
  h.case_hash = id_.case_hash;
  h.mesh_hash = id_.mesh_hash;
  h.time = sim_.t;
  h.step = sim_.step_count;
  if (fapl >= 0)
    write_checkpoint_rows(out_ + "/checkpoint.h5", h, st, rows,
                          {fapl, writes_, [&parts](double* v, int n) { parts.sum(v, n); }});
  else
    write_checkpoint(out_ + "/checkpoint.h5", h, st);
  ++ckpt_written_;
  ckpt_wall_ += seconds(Clock::now() - c0);
}

template <int D>
void RunLoop<D>::mark_pace() {
  // (the last tenth within the loop's own end test: the loop stops at end_time (1 - 1e-12))
  while (next_tenth_ <= 10 && sim_.t >= (next_tenth_ == 10 ? c_.end_time * (1 - 1e-12) : 0.1 * next_tenth_ * c_.end_time)) {
    pace_.push_back({next_tenth_, sim_.step_count, seconds(Clock::now() - loop0_)});
    ++next_tenth_;
  }
}

template <int D>
nlohmann::json RunLoop<D>::finish(const std::string& stop_reason, double loop_wall) {
  RunRecord r;
  r.out = out_;
  r.boundary_nodes = boundary_nodes_;
  r.stop_reason = stop_reason;
  r.wall_seconds = prior_wall_ + seconds(Clock::now() - wall0_);
  r.loop_wall_seconds = loop_wall;
  r.snapshots = snaps_->on();
  r.checkpoint_file = out_ + "/checkpoint.h5";
  r.checkpoint_every = schedule_.checkpoint_every();
  r.checkpoint_seconds = ckpt_wall_;
  r.checkpoints_written = ckpt_written_;
  r.restart = cuts_->recuts > 0 ? cuts_->restarted : restart_;
  r.signal = signal_;
  nlohmann::json summary = run_summary(c_, counts_, sim_, *history_, frag_.get(), r);
  if (!pace_.empty()) {
    nlohmann::json marks = nlohmann::json::array();
    for (const PaceMark& p : pace_)
      marks.push_back({{"fraction", p.tenth / 10.0}, {"step", p.step}, {"loop_seconds", p.loop_seconds}});
    summary["pace"] = {{"from_step", pace_step0_}, {"from_time", pace_t0_}, {"marks", marks}};
  }
  parts_->report(summary, c_, loop0_, cut_setup_seconds());  // (over processes: collective)
  if (writes_) write_file_atomic(out_ + "/summary.json", summary.dump(2) + "\n");
  if (writes_) print_run_end(summary, r, sim_.step_count, opt_.progress);
  return summary;
}

template <int D>
LoopEnd run_dim(const Case& c, std::shared_ptr<const HostMesh> mesh, const std::string& out,
                const RunOptions& opt, const RunIdentity& id, const StateArrays* restart, const SubMesh* part,
                CutHistory* cuts) {
  RunLoop<D> run(c, std::move(mesh), out, opt, id, restart, part, cuts);
  return run.run();
}

template class RunLoop<2>;
template class RunLoop<3>;
template LoopEnd run_dim<2>(const Case&, std::shared_ptr<const HostMesh>, const std::string&, const RunOptions&,
                            const RunIdentity&, const StateArrays*, const SubMesh*, CutHistory*);
template LoopEnd run_dim<3>(const Case&, std::shared_ptr<const HostMesh>, const std::string&, const RunOptions&,
                            const RunIdentity&, const StateArrays*, const SubMesh*, CutHistory*);

}  // namespace fdem
