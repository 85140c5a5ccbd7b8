#include "solver/run.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "common/error.hpp"
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "solver/fragment_analysis.hpp"
#include "solver/simulation.hpp"

namespace fdem {

namespace {

using Clock = std::chrono::steady_clock;

// Mesh of a case, ready for the solver: built or read, checked, renumbered, interfaces inserted.
HostMesh prepare_mesh(const Case& c) {
  HostMesh mesh = build_mesh(c.mesh, c.dim);
  const std::string source = c.mesh.kind == "file" ? c.mesh.file : c.file + ": mesh";
  check_elements(mesh, source);
  check_case_against_mesh(c, mesh);
  reorder_for_locality(mesh);
  if (!c.fracturable_regions.empty()) {
    std::vector<bool> frac(mesh.region_names.size(), false);
    for (const auto& r : c.fracturable_regions) frac[mesh.region_index(r)] = true;
    insert_interfaces(mesh, frac);
  }
  return mesh;
}

std::string fmt_time(double s) {
  char buf[64];
  if (!std::isfinite(s)) return "?";
  if (s < 120) std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%.1f min", s / 60);
  else std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

// Progress: a line rewritten in place on a terminal; on a log, a line every 10 % or 60 s.
class Progress {
 public:
  // step0, t0: where this process started (a restart goes on from there)
  Progress(bool on, long step0, double t0)
      : on_(on), tty_(isatty(fileno(stderr))), start_(Clock::now()), step0_(step0), t0_(t0) {}
  void update(long step, double t, double end_time, bool force = false) {
    if (!on_) return;
    const auto now = Clock::now();
    const double wall = std::chrono::duration<double>(now - start_).count();
    const double since = std::chrono::duration<double>(now - last_).count();
    const double frac = end_time > 0 ? t / end_time : 0;
    const int decile = static_cast<int>(frac * 10);
    const bool due = tty_ ? since > 0.5 : (since > 60 || decile > last_decile_);
    if (!due && !force) return;
    last_ = now;
    last_decile_ = decile;
    const double rate = wall > 0 ? (step - step0_) / wall : 0;
    const double done = end_time > 0 ? (t - t0_) / end_time : 0;
    const double eta = done > 0 ? wall * (1 - frac) / done : NAN;
    std::fprintf(stderr, "%sstep %ld  t = %.4e s (%5.1f %%)  %.3g steps/s  elapsed %s  left %s%s",
                 tty_ ? "\r" : "", step, t, 100 * frac, rate, fmt_time(wall).c_str(),
                 fmt_time(eta).c_str(), tty_ ? "   " : "\n");
    std::fflush(stderr);
  }
  void done() {
    if (on_ && tty_) std::fprintf(stderr, "\n");
  }
  // A line of its own between progress updates.
  void note(const std::string& line) {
    if (!on_) return;
    std::fprintf(stderr, "%s%s\n", tty_ ? "\r" : "", line.c_str());
    std::fflush(stderr);
  }

 private:
  bool on_, tty_;
  Clock::time_point start_, last_{};
  int last_decile_ = -1;
  long step0_;
  double t0_;
};

nlohmann::json mesh_report(const HostMesh& mesh) {
  const auto q = mesh_quality(mesh);
  return {{"nodes", mesh.num_nodes()},
          {"elements", mesh.num_elems()},
          {"interfaces", mesh.num_ifaces()},
          {"regions", mesh.region_names},
          {"quality",
           {{"min_angle_deg", q.min_angle_deg},
            {"max_aspect", q.max_aspect},
            {"min_altitude_m", q.min_size},
            {"mean_edge_m", q.mean_size}}}};
}

template <int D>
nlohmann::json stable_report(const Simulation<D>& sim) {
  nlohmann::json j = {{"dt_s", sim.dt},
                      {"dt_critical_s", sim.stable.critical},
                      {"dt_bulk_s", sim.stable.bulk},
                      {"dt_springs_s", std::isfinite(sim.stable.springs) ? sim.stable.springs : 0.0}};
  // with contact that cannot act yet: the step once surfaces can meet
  if (sim.stable.contact_pending) j["dt_critical_with_contact_s"] = sim.stable.critical_contact;
  // the step changed during the run (contact's springs applied)
  if (sim.dt_changed_at() >= 0) {
    j["dt_before_contact_s"] = sim.dt_before_change();
    j["dt_changed_at_step"] = sim.dt_changed_at();
  }
  return j;
}

// What identifies a run for a restart (checkpoint header).
struct RunIdentity {
  std::string case_hash, mesh_hash;
};

template <int D>
nlohmann::json run_dim(const Case& c, const HostMesh& mesh, const std::string& out,
                       const RunOptions& opt, const RunIdentity& id, const StateArrays* restart) {
  const auto wall0 = Clock::now();
  Simulation<D> sim(c, mesh);
  const int boundary_nodes = sim.m.nb;  // before contact adds crack faces to the platens' nodes
  if (restart) sim.load_state(*restart);
  const int np = sim.m.platens.count;
  const char* axes[3] = {"x", "y", "z"};

  std::vector<std::string> cols = {"time [s]", "step"};
  for (const auto& name : sim.platen_names()) {
    cols.push_back(name + "_displacement [m]");
    for (int k = 0; k < D; ++k) cols.push_back(name + "_force_" + axes[k] + " [N]");
    cols.push_back(name + "_load [N]");
  }
  for (const auto& name : sim.bc_names())
    for (int k = 0; k < D; ++k) cols.push_back(name + "_reaction_" + axes[k] + " [N]");
  std::vector<Kokkos::View<int*>> monitor_nodes;
  for (const auto& name : c.monitors) {
    const auto& nodes = mesh.node_sets.at(name);
    Kokkos::View<int*> v("fdem::monitor", nodes.size());
    auto vh = Kokkos::create_mirror_view(v);
    for (size_t j = 0; j < nodes.size(); ++j) vh(j) = nodes[j];
    Kokkos::deep_copy(v, vh);
    monitor_nodes.push_back(v);
    for (int k = 0; k < D; ++k) cols.push_back(name + "_u" + axes[k] + " [m]");
  }
  const bool srf = c.srf_initial != 1.0 || c.srf_rate > 0;
  auto srf_at = [&](double t) {
    return c.srf_initial + c.srf_rate * std::max(0.0, t - c.srf_start);
  };
  if (srf) cols.push_back("strength_reduction_factor");
  for (int k = 0; k < D; ++k) cols.push_back(std::string("momentum_") + axes[k] + " [N s]");
  for (const char* e : {"E_kinetic [J]", "E_strain [J]", "E_interface [J]", "E_contact [J]",
                        "D_fracture [J]", "D_damping [J]", "D_friction [J]", "W_external [J]",
                        "energy_error [J]", "interfaces_damaged", "interfaces_failed"})
    cols.push_back(e);
  // ---- run-loop state (saved in checkpoints) ----
  const double hist_dt = c.history_interval > 0 ? c.history_interval : c.end_time / 200;
  const double ckpt_dt = opt.checkpoint_every >= 0 ? opt.checkpoint_every : c.checkpoint_every;
  double next_hist = 0, next_snap = c.snapshot_interval, next_ckpt = ckpt_dt;
  std::vector<double> peak(np, 0.0), peak_disp(np, 0.0);
  double max_rel_error = 0;
  Energies last{};
  bool last_was_row = false;

  // Fragments (runs with interfaces): fragments.csv at every history row, ids in the snapshots.
  std::unique_ptr<FragmentAnalysis<D>> frag;
  std::unique_ptr<HistoryWriter> frag_csv;
  if (c.output_fragments && sim.m.ni > 0) {
    frag = std::make_unique<FragmentAnalysis<D>>(sim.m);
    std::vector<std::string> fc = {"time [s]", "step", "fragments", "largest_fraction",
                                   "largest_mass [kg]", "total_mass [kg]", "single_element_fragments"};
    for (int b = 0; b < kFragmentBins; ++b) fc.push_back("count_" + FragmentStats::bin_name(b));
    for (int b = 0; b < kFragmentBins; ++b) fc.push_back("mass_" + FragmentStats::bin_name(b));
    frag_csv = std::make_unique<HistoryWriter>(out + "/fragments.csv", fc);
  }
  long frag_step = -1;
  auto fragments_now = [&]() -> const FragmentStats& {
    if (frag_step != sim.step_count) {
      frag->compute(sim.m);
      frag_step = sim.step_count;
    }
    return frag->last();
  };

  long last_snap_step = -1;
  std::vector<double> rows;  // every history row so far (row-major), for checkpoints
  double prior_wall = 0, prior_loop_wall = 0, ckpt_wall = 0;
  long ckpt_written = 0;
  std::vector<long> snap_steps;
  std::vector<double> snap_times;
  if (restart) {
    const StateArrays& R = *restart;
    std::string joined;
    for (const auto& col : cols) joined += col + "\n";
    if (R.string("run/history_columns") != joined)
      throw InputError("restart file '" + R.file + "': its history columns differ from this case's");
    next_hist = R.get("run/next_history");
    next_snap = R.get("run/next_snapshot");
    if (ckpt_dt > 0) {  // the next checkpoint after the restart point
      next_ckpt = R.get("run/next_checkpoint");
      if (!(next_ckpt > 0) || R.get("run/checkpoint_every") != ckpt_dt) {
        next_ckpt = ckpt_dt * std::floor(sim.t / ckpt_dt);
        while (next_ckpt <= sim.t * (1 + 1e-12)) next_ckpt += ckpt_dt;
      }
    }
    peak = R.array("run/peak_load", np);
    peak_disp = R.array("run/peak_displacement", np);
    max_rel_error = R.get("run/max_relative_balance_error");
    last = energies_from_vector(R.array("run/last_row_energies", kEnergyFieldCount));
    last_was_row = R.get_int("run/last_was_row") != 0;
    last_snap_step = static_cast<long>(R.get_int("run/last_snapshot_step"));
    rows = R.array("run/history_rows");
    if (rows.size() % cols.size() != 0)
      throw InputError("restart file '" + R.file + "': history rows do not fit the columns");
    prior_wall = R.get("run/wall_seconds");
    prior_loop_wall = R.get("run/loop_wall_seconds");
    ckpt_wall = R.get("run/checkpoint_seconds");
    ckpt_written = static_cast<long>(R.get_int("run/checkpoints_written"));
    for (long long st : R.int_array("run/snapshot_steps")) snap_steps.push_back(static_cast<long>(st));
    snap_times = R.array("run/snapshot_times", static_cast<long long>(snap_steps.size()));
  }

  std::unique_ptr<HistoryWriter> history =
      restart ? std::make_unique<HistoryWriter>(out + "/history.csv", cols, rows)
              : std::make_unique<HistoryWriter>(out + "/history.csv", cols);
  std::unique_ptr<SnapshotWriter> snaps;
  if (c.snapshot_interval > 0) {
    if (restart) {
      std::string note;
      snaps = std::make_unique<SnapshotWriter>(out, mesh, snap_steps, snap_times, note);
      if (!note.empty()) std::fprintf(stderr, "fdem: warning: %s\n", note.c_str());
    } else {
      snaps = std::make_unique<SnapshotWriter>(out, mesh);
    }
  }
  std::vector<double> sx, su, sv, ss, sd;
  std::vector<int> sfrag;
  auto snapshot = [&]() {
    if (!snaps || sim.step_count == last_snap_step) return;
    last_snap_step = sim.step_count;
    sim.download(sx, su, sv, ss, sd);
    SnapshotFrame fr;
    fr.time = sim.t;
    fr.step = sim.step_count;
    fr.x = sx.data();
    fr.u = su.data();
    fr.v = sv.data();
    fr.stress = ss.data();
    fr.damage = sd.data();
    if (frag) {
      fragments_now();
      frag->element_ids(sfrag);
      fr.fragment = sfrag.data();
    }
    snaps->write(fr);
  };

  std::string stop_reason = "end_time";
  int stop_platen = -1;
  for (int p = 0; p < np; ++p)
    if (sim.platen_names()[p] == c.stop_platen) stop_platen = p;

  auto write_row = [&]() -> bool {  // returns true when the stop condition is met
    last = sim.energies();
    std::vector<double> row = {last.time, static_cast<double>(last.step)};
    bool stop = false;
    for (int p = 0; p < np; ++p) {
      const auto F = sim.platen_force(p);
      const auto& P = sim.m.platens.p[p];
      const double load = F[0] * P.n[0] + F[1] * P.n[1] + F[2] * P.n[2];
      const double disp = sim.platen_displacement(p, last.time);
      row.push_back(disp);
      for (int k = 0; k < D; ++k) row.push_back(F[k]);
      row.push_back(load);
      if (load > peak[p]) {
        peak[p] = load;
        peak_disp[p] = disp;
      }
      if (p == stop_platen && peak[p] > 0 && load < (1 - c.stop_drop_fraction) * peak[p]) stop = true;
    }
    for (const auto& r : sim.reactions())
      for (int k = 0; k < D; ++k) row.push_back(r[k]);
    for (const auto& nodes : monitor_nodes) {
      double u[3];
      node_list_displacement<D>(sim.m, nodes, u);
      for (int k = 0; k < D; ++k) row.push_back(u[k]);
    }
    if (srf) row.push_back(srf_at(last.time));
    for (int k = 0; k < D; ++k) row.push_back(last.momentum[k]);
    for (double e : {last.kinetic, last.strain, last.interface_elastic, last.contact_elastic,
                     last.fracture, last.damping, last.friction, last.work_external,
                     last.balance_error, static_cast<double>(last.damaged),
                     static_cast<double>(last.failed)})
      row.push_back(e);
    history->row(row);
    rows.insert(rows.end(), row.begin(), row.end());
    if (frag) {  // the interface history is that of x(n), the instant of the row
      const FragmentStats& fs = fragments_now();
      std::vector<double> fr = {last.time, static_cast<double>(last.step), double(fs.count),
                                fs.largest_fraction, fs.largest_mass, fs.total_mass,
                                double(fs.single_element)};
      for (int b = 0; b < kFragmentBins; ++b) fr.push_back(fs.bin_count[b]);
      for (int b = 0; b < kFragmentBins; ++b) fr.push_back(fs.bin_mass_fraction[b]);
      frag_csv->row(fr);
    }
    if (last.scale > 0) max_rel_error = std::max(max_rel_error, std::fabs(last.balance_error) / last.scale);
    return stop;
  };

  auto check = [&]() { sim.check_stability(); };

  Progress progress(opt.progress, sim.step_count, sim.t);
  if (opt.progress) {
    std::fprintf(stderr, "fdem: %s: %d nodes, %d elements, %d interfaces; dt = %.3e s (%.2f x critical %.3e s); %.0f steps to end_time\n",
                 c.name.c_str(), sim.m.nn, sim.m.ne, sim.m.ni, sim.dt, sim.dt / sim.stable.critical,
                 sim.stable.critical, std::ceil(c.end_time / sim.dt));
    if (sim.stable.contact_pending)
      std::fprintf(stderr, "fdem: contact springs act once surfaces can meet (first failed interface); the critical step "
                           "is then %.3e s\n", sim.stable.critical_contact);
  }
  const std::string ckpt_path = out + "/checkpoint.h5";
  auto loop0 = Clock::now();
  auto write_ckpt = [&]() {
    const auto c0 = Clock::now();
    StateArrays st;
    sim.save_state(st);
    std::string joined;
    for (const auto& col : cols) joined += col + "\n";
    st.str["run/history_columns"] = joined;
    st.f64["run/history_rows"] = rows;
    st.put("run/next_history", next_hist);
    st.put("run/next_snapshot", next_snap);
    st.put("run/next_checkpoint", next_ckpt);
    st.put("run/checkpoint_every", ckpt_dt);
    st.f64["run/peak_load"] = peak;
    st.f64["run/peak_displacement"] = peak_disp;
    st.put("run/max_relative_balance_error", max_rel_error);
    st.f64["run/last_row_energies"] = energies_to_vector(last);
    st.put_int("run/last_was_row", last_was_row);
    st.put_int("run/last_snapshot_step", last_snap_step);
    std::vector<long long> ss;
    std::vector<double> stimes;
    if (snaps) {
      for (long x : snaps->steps()) ss.push_back(x);
      stimes = snaps->times();
    }
    st.i64["run/snapshot_steps"] = ss;
    st.f64["run/snapshot_times"] = stimes;
    const double now = std::chrono::duration<double>(c0 - wall0).count();
    st.put("run/wall_seconds", prior_wall + now);
    st.put("run/loop_wall_seconds", prior_loop_wall + std::chrono::duration<double>(c0 - loop0).count());
    st.put("run/checkpoint_seconds", ckpt_wall);
    st.put_int("run/checkpoints_written", ckpt_written + 1);
    CheckpointHeader h;
    h.dim = D;
    h.nodes = sim.m.nn;
    h.elements = sim.m.ne;
    h.interfaces = sim.m.ni;
    h.case_hash = id.case_hash;
    h.mesh_hash = id.mesh_hash;
    h.time = sim.t;
    h.step = sim.step_count;
    write_checkpoint(ckpt_path, h, st);
    ++ckpt_written;
    ckpt_wall += std::chrono::duration<double>(Clock::now() - c0).count();
  };

  if (restart) {
    if (opt.progress)
      std::fprintf(stderr, "fdem: restarting from %s at step %ld, t = %.6e s (%zu history rows, %d snapshots kept)\n",
                   restart->file.c_str(), sim.step_count, sim.t, rows.size() / cols.size(),
                   snaps ? snaps->frames() : 0);
  } else {
    snapshot();
  }
  loop0 = Clock::now();
  while (sim.t < c.end_time * (1 - 1e-12)) {
    if (c.max_steps > 0 && sim.step_count >= c.max_steps) {
      stop_reason = "max_steps";
      break;
    }
    // history rows and checks sample the state at the start of a step
    const bool hist = sim.t >= next_hist * (1 - 1e-12);
    const bool chk = c.check_interval > 0 && (sim.step_count + 1) % c.check_interval == 0;
    sim.set_sample_reactions(hist);
    if (srf) sim.set_strength_reduction(srf_at(sim.t));
    if (c.damping_change_time >= 0 && sim.t >= c.damping_change_time * (1 - 1e-12))
      sim.set_damping(c.damping_change_local, c.damping_change_mass);
    sim.step(hist || chk);
    if (hist || chk) check();
    if (sim.dt_changed_at() == sim.step_count - 1) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "fdem: step %ld, t = %.4e s: surfaces can meet, contact springs act: dt = %.3e -> %.3e s "
                    "(critical %.3e s)",
                    sim.dt_changed_at(), sim.t, sim.dt_before_change(), sim.dt, sim.stable.critical);
      progress.note(line);
    }
    last_was_row = hist;
    if (hist) {
      next_hist += hist_dt;
      if (write_row()) {
        stop_reason = "load_drop";
        break;
      }
    }
    if (snaps && sim.t >= next_snap * (1 - 1e-12)) {
      snapshot();
      next_snap += c.snapshot_interval;
    }
    if (ckpt_dt > 0 && sim.t >= next_ckpt * (1 - 1e-12)) {
      while (next_ckpt <= sim.t * (1 + 1e-12)) next_ckpt += ckpt_dt;
      write_ckpt();
    }
    progress.update(sim.step_count, sim.t, c.end_time);
  }
  const double loop_wall = prior_loop_wall + std::chrono::duration<double>(Clock::now() - loop0).count();
  progress.update(sim.step_count, sim.t, c.end_time, true);
  progress.done();
  if (!last_was_row) {  // a final row: one more sampled step
    sim.set_sample_reactions(true);
    sim.step(true);
    check();
    write_row();
  }
  snapshot();

  nlohmann::json summary;
  summary["case"] = c.name;
  summary["dimension"] = D;
  summary["counts"] = mesh_report(mesh);
  summary["counts"]["boundary_nodes"] = boundary_nodes;
  summary["time_step"] = stable_report(sim);
  summary["steps"] = sim.step_count;
  summary["end_time_s"] = sim.t;
  summary["stop_reason"] = stop_reason;
  summary["wall_seconds"] = prior_wall + std::chrono::duration<double>(Clock::now() - wall0).count();
  summary["loop_wall_seconds"] = loop_wall;
  summary["element_steps_per_second"] = loop_wall > 0 ? sim.step_count * double(sim.m.ne) / loop_wall : 0;
  summary["energy"] = {{"kinetic_J", last.kinetic},
                       {"strain_J", last.strain},
                       {"interface_elastic_J", last.interface_elastic},
                       {"contact_elastic_J", last.contact_elastic},
                       {"fracture_J", last.fracture},
                       {"damping_J", last.damping},
                       {"friction_J", last.friction},
                       {"external_work_J", last.work_external},
                       {"balance_error_J", last.balance_error},
                       {"max_relative_balance_error", max_rel_error}};
  summary["interfaces_damaged"] = last.damaged;
  summary["interfaces_failed"] = last.failed;
  summary["momentum_N_s"] = std::vector<double>(last.momentum, last.momentum + D);
  if (ContactSystem<D>* ct = sim.contact()) {
    summary["contact"] = {{"interfaces_handed_over", ct->handed_over()},
                          {"surface_nodes", ct->surface_nodes()},
                          {"candidate_pairs", ct->candidates()},
                          {"active_contacts", ct->active_contacts()},
                          {"grid_builds", ct->builds()},
                          {"stable_step_s", ct->stable_step()}};
  }
  if (frag) {
    const FragmentStats& fs = fragments_now();
    std::vector<double> masses = frag->masses();
    std::sort(masses.begin(), masses.end(), [](double a, double b) { return a > b; });
    std::vector<double> top;
    for (size_t i = 0; i < masses.size() && i < 10; ++i)
      top.push_back(fs.total_mass > 0 ? masses[i] / fs.total_mass : 0.0);
    std::vector<std::string> edges;
    for (int b = 0; b < kFragmentBins; ++b) edges.push_back(FragmentStats::bin_name(b));
    summary["fragments"] = {
        {"count", fs.count},
        {"largest_fraction", fs.largest_fraction},
        {"largest_mass_kg", fs.largest_mass},
        {"total_mass_kg", fs.total_mass},
        {"single_element_fragments", fs.single_element},
        {"largest_fractions", top},
        {"distribution",
         {{"bin_lower_edge", edges},
          {"count", std::vector<double>(fs.bin_count.begin(), fs.bin_count.end())},
          {"mass_fraction",
           std::vector<double>(fs.bin_mass_fraction.begin(), fs.bin_mass_fraction.end())}}}};
  }
  nlohmann::json results = nlohmann::json::object();
  for (int p = 0; p < np; ++p) {
    results["platens"][sim.platen_names()[p]] = {{"peak_load_N", peak[p]},
                                                 {"displacement_at_peak_m", peak_disp[p]}};
  }
  if (np > 0) {
    results["peak_load_N"] = peak[0];
    if (D == 2 && c.mesh.kind == "disc" && np >= 2) {  // not for a disc striking one plate
      // Brazilian test: sigma_t = 2 P / (pi D L)
      results["tensile_strength_Pa"] = 2 * peak[0] / (M_PI * 2 * c.mesh.radius * c.thickness);
    }
  }
  summary["results"] = results;
  if (ckpt_dt > 0 || restart) {
    nlohmann::json ck = {{"file", ckpt_path}, {"every_s", ckpt_dt}, {"written", ckpt_written},
                         {"write_seconds", ckpt_wall}};
    if (restart)
      ck["restarted_from"] = {{"file", restart->file},
                              {"step", restart->get_int("simulation/step")},
                              {"time_s", restart->get("simulation/time")}};
    summary["checkpoint"] = ck;
  }
  summary["outputs"] = {{"history", out + "/history.csv"},
                        {"summary", out + "/summary.json"},
                        {"case", out + "/case.json"}};
  if (snaps) summary["outputs"]["snapshots"] = out + "/snapshots.xdmf";
  if (frag) summary["outputs"]["fragments"] = out + "/fragments.csv";
  write_file_atomic(out + "/summary.json", summary.dump(2) + "\n");
  if (opt.progress) {
    std::fprintf(stderr, "fdem: %ld steps in %.1f s (%.3g element-steps/s); stopped by %s\n",
                 sim.step_count, loop_wall, summary["element_steps_per_second"].get<double>(),
                 stop_reason.c_str());
  }
  std::printf("results: %s\n", out.c_str());
  std::printf("  history:   %s/history.csv\n  summary:   %s/summary.json\n", out.c_str(), out.c_str());
  if (snaps) std::printf("  snapshots: %s/snapshots.xdmf (open in ParaView)\n", out.c_str());
  std::fflush(stdout);
  return summary;
}

}  // namespace

namespace {

// The resolved case without the keys that do not change the results: the checkpoint interval,
// and the mesh file's path (its content is in the mesh hash; the project folder may move).
std::string case_hash(const Case& c) {
  nlohmann::json r = c.resolved;
  if (r.contains("output") && r["output"].is_object()) r["output"].erase("checkpoint_every");
  if (r.contains("mesh") && r["mesh"].is_object() && r["mesh"].contains("file")) r["mesh"]["file"] = "";
  const std::string text = r.dump();
  return hash_hex(text.data(), text.size());
}

std::string mesh_hash(const HostMesh& mesh) {
  uint64_t h = fnv1a(mesh.X.data(), mesh.X.size() * sizeof(double));
  h = fnv1a(mesh.elems.data(), mesh.elems.size() * sizeof(int), h);
  h = fnv1a(mesh.ifaces.data(), mesh.ifaces.size() * sizeof(int), h);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// A restart file must come from this case (same file, same --set options) and this mesh.
void check_restart_matches(const std::string& file, const CheckpointHeader& h, const Case& c,
                           const HostMesh& mesh, const RunIdentity& id) {
  std::string diff;
  auto cmp = [&](const char* what, long long have, long long want) {
    if (have != want)
      diff += std::string(diff.empty() ? "" : "; ") + what + " " + std::to_string(have) +
              " (this case: " + std::to_string(want) + ")";
  };
  cmp("dimension", h.dim, c.dim);
  cmp("nodes", h.nodes, mesh.num_nodes());
  cmp("elements", h.elements, mesh.num_elems());
  cmp("interfaces", h.interfaces, mesh.num_ifaces());
  if (diff.empty() && h.mesh_hash != id.mesh_hash) diff = "the mesh coordinates or connectivity differ";
  if (diff.empty() && h.case_hash != id.case_hash)
    diff = "the case differs (give the same case file and the same --set options as the run that "
           "wrote it; only the checkpoint interval may change)";
  if (!diff.empty())
    throw InputError("restart file '" + file + "' is a checkpoint of another case or mesh: " + diff);
}

}  // namespace

nlohmann::json run_case(const std::string& case_path, const RunOptions& opt) {
  const Case c = load_case(case_path, opt.overrides);
  if (opt.checkpoint_every >= 0 && !std::isfinite(opt.checkpoint_every))
    throw InputError("--checkpoint-every must be a finite time in seconds");
  StateArrays restart;
  CheckpointHeader header;
  if (!opt.restart.empty()) restart = read_checkpoint(opt.restart, header);
  const std::string out = opt.out_dir.empty() ? "out/" + c.name : opt.out_dir;
  ensure_output_dir(out);
  // (a restart checks the case against the checkpoint before it touches the folder's case.json)
  if (opt.restart.empty()) write_file_atomic(out + "/case.json", c.resolved.dump(2) + "\n");
  const HostMesh mesh = prepare_mesh(c);
  const RunIdentity id{case_hash(c), mesh_hash(mesh)};
  const StateArrays* r = nullptr;
  if (!opt.restart.empty()) {
    check_restart_matches(opt.restart, header, c, mesh, id);
    write_file_atomic(out + "/case.json", c.resolved.dump(2) + "\n");
    r = &restart;
  }
  return c.dim == 2 ? run_dim<2>(c, mesh, out, opt, id, r) : run_dim<3>(c, mesh, out, opt, id, r);
}

nlohmann::json check_case(const std::string& case_path, const std::vector<std::string>& overrides) {
  const Case c = load_case(case_path, overrides);
  const HostMesh mesh = prepare_mesh(c);
  nlohmann::json report = {{"case", c.name}, {"dimension", c.dim}, {"mesh", mesh_report(mesh)}};
  auto add_dt = [&](const auto& sim) {
    report["time_step"] = stable_report(sim);
    report["steps_to_end_time"] = std::ceil(c.end_time / sim.dt);  // at the starting step
  };
  if (c.dim == 2) add_dt(Simulation<2>(c, mesh));
  else add_dt(Simulation<3>(c, mesh));
  return report;
}

}  // namespace fdem
