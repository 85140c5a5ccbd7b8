#include "solver/summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/huge_pages.hpp"
#include "common/kernel_times.hpp"
#include "common/view_memory.hpp"
#include "common/setup_times.hpp"
#include "kernels/parts.hpp"

namespace fdem {

nlohmann::json mesh_report(const HostMesh& mesh) {
  return mesh_report(mesh.num_nodes(), mesh.num_elems(), mesh.num_ifaces(), mesh_quality(mesh), mesh.region_names,
                     mesh.warnings, mesh.bodies);
}

nlohmann::json mesh_report(long nodes, long elems, long ifaces, const MeshQuality& q,
                           const std::vector<std::string>& regions, const std::vector<std::string>& warnings,
                           int bodies) {
  nlohmann::json j = {{"nodes", nodes},
                      {"elements", elems},
                      {"interfaces", ifaces},
                      {"regions", regions},
                      {"quality",
                       {{"min_angle_deg", q.min_angle_deg},
                        {"max_aspect", q.max_aspect},
                        {"min_altitude_m", q.min_size},
                        {"mean_edge_m", q.mean_size}}}};
  if (!warnings.empty()) j["warnings"] = warnings;
  if (bodies > 0) j["bodies"] = bodies;  // separate bodies at the start (particles)
  return j;
}

template <int D>
nlohmann::json stable_report(const Simulation<D>& sim) {
  nlohmann::json j = {{"dt_s", sim.dt},
                      {"dt_critical_s", sim.stable.critical},
                      {"dt_bulk_s", sim.stable.bulk},
                      {"dt_springs_s", std::isfinite(sim.stable.springs) ? sim.stable.springs : 0.0}};
  // with contact that cannot act yet: the step once surfaces can meet
  if (sim.stable.contact_pending) j["dt_critical_with_contact_s"] = sim.stable.critical_contact;
  // with contact: the estimate with a crack face's contact and interface springs summed
  if (sim.stable.critical_summed > 0 && sim.stable.critical_summed < sim.stable.critical_contact)
    j["dt_critical_summed_s"] = sim.stable.critical_summed;
  // the step changed during the run (contact's springs applied)
  if (sim.dt_changed_at() >= 0) {
    j["dt_before_contact_s"] = sim.dt_before_change();
    j["dt_changed_at_step"] = sim.dt_changed_at();
  }
  return j;
}

template nlohmann::json stable_report(const Simulation<2>& sim);
template nlohmann::json stable_report(const Simulation<3>& sim);

namespace {

// What summary.json's phases are: the seconds of the phases done on every step
// are estimates, which can sum to more than the loop's wall time.
std::string phases_note(const PhaseTimes& p) {
  if (p.timed <= 0) return "no step was timed";
  if (p.timed >= p.steps) return "measured on every step";
  return "estimated from " + std::to_string(p.timed) + " timed steps of " + std::to_string(p.steps) +
         ": forces, platens, contact and nodes are their mean over the timed (sampled) steps times "
         "every step, the ledger (sampled steps only) as measured; a timed step waits for each "
         "phase's kernels and sums the energies, so total_seconds can exceed loop_wall_seconds";
}

}  // namespace

// The phases of every step estimated from the timed (sampled) steps: their mean per step times the
// number of steps; the ledger's work is done on sampled steps only, its time is the measured one.
nlohmann::json phases_report(const PhaseTimes& p) {
  const double scale = p.timed > 0 ? static_cast<double>(p.steps) / static_cast<double>(p.timed) : 0.0;
  const double total = (p.forces + p.platens + p.contact + p.nodes) * scale + p.ledger;
  nlohmann::json j;
  auto add = [&](const char* name, double s) {
    j[name] = {{"seconds", s}, {"share", total > 0 ? s / total : 0.0}};
  };
  add("forces", p.forces * scale);
  add("platens", p.platens * scale);
  add("contact", p.contact * scale);
  add("ledger", p.ledger);
  add("nodes", p.nodes * scale);
  j["total_seconds"] = total;
  j["steps"] = p.steps;
  j["timed_steps"] = p.timed;
  j["estimated"] = p.timed > 0 && p.timed < p.steps;
  j["note"] = phases_note(p);
  return j;
}

namespace {

nlohmann::json energy_report(const Energies& e, double max_rel_error) {
  nlohmann::json r;
  const auto& terms = energy_terms();  // the ledger's (solver/ledger.hpp)
  for (size_t i = 0; i < terms.size(); ++i) r[std::string(terms[i].key) + "_J"] = term_value(e, i);
  r["balance_error_J"] = e.balance_error;
  r["max_relative_balance_error"] = max_rel_error;
  return r;
}

template <int D>
nlohmann::json results_report(const Case& c, const Simulation<D>& sim, const HistoryTable<D>& history) {
  const std::vector<double>& peak = history.peak_load();
  const int np = static_cast<int>(peak.size());
  nlohmann::json results = nlohmann::json::object();
  for (int p = 0; p < np; ++p) {
    results["platens"][sim.platen_names()[p]] = {{"peak_load_N", peak[p]},
                                                 {"displacement_at_peak_m", history.peak_displacement()[p]}};
  }
  if (!c.stop_platen.empty()) {  // the load sampling of the stop rule (solver/history_table.hpp)
    results["stop_rule"] = {{"platen", c.stop_platen},
                            {"drop_fraction", c.stop_drop_fraction},
                            {"window_s", history.load_window()},
                            {"sample_interval_s", history.load_sample_interval()},
                            {"window_averaged_peak_load_N", history.smoothed_peak()}};
    if (history.stop_met_at() >= 0) results["stop_rule"]["met_at_s"] = history.stop_met_at();
  }
  if (np > 0) {
    results["peak_load_N"] = peak[0];
    const bool disc = c.mesh.kind == "disc" || (c.mesh.kind == "grains" && c.mesh.shape == "disc");
    if (D == 2 && disc && np >= 2) {  // not for a disc striking one plate
      // Brazilian test: sigma_t = 2 P / (pi D L)
      results["tensile_strength_Pa"] = 2 * peak[0] / (M_PI * 2 * c.mesh.radius * c.thickness);
    }
  }
  return results;
}

nlohmann::json checkpoint_report(const RunRecord& r) {
  nlohmann::json ck = {{"file", r.checkpoint_file}, {"every_s", r.checkpoint_every},
                       {"written", r.checkpoints_written}, {"write_seconds", r.checkpoint_seconds}};
  if (r.restart)
    ck["restarted_from"] = {{"file", r.restart->file},
                            {"step", r.restart->get_int("simulation/step")},
                            {"time_s", r.restart->get("simulation/time")}};
  return ck;
}

// The candidates' spread over the surface points at the end (ContactSystem::candidate_spread): the
// narrow phase's work per point, which GPUs share among a team's threads above a bound.
template <int D>
nlohmann::json spread_report(const ContactSystem<D>& ct) {
  const auto sp = ct.candidate_spread();
  nlohmann::json above = nlohmann::json::object();
  for (int k = 0; k < ContactSystem<D>::kSpreadBins; ++k)
    above[std::to_string(ContactSystem<D>::kSpreadBounds[k])] = {{"points", sp.points_above[k]},
                                                                {"pairs", sp.pairs_above[k]}};
  return {{"points", sp.points},
          {"mean", sp.points > 0 ? static_cast<double>(sp.pairs) / sp.points : 0.0},
          {"max", sp.max},
          {"above", above}};
}

template <int D>
nlohmann::json contact_report(ContactSystem<D>& ct, const Simulation<D>& sim) {
  if (!sim.parts().many())  // one process: its own counts (the summary's keys differ)
    return {{"interfaces_handed_over", ct.handed_over()},
            {"surface_nodes", ct.surface_nodes()},
            {"candidate_pairs", ct.candidates()},
            {"candidates_per_point", spread_report(ct)},
            {"active_contacts", ct.active_contacts()},
            {"grid_builds", ct.builds()},
            {"list_updates", ct.list_updates()},
            {"stable_step_s", ct.stable_step()}};
  // Over several processes (every process calls this): the whole run's counts, each item counted
  // by its owner (interfaces handed over: the counted ones; surface nodes and contacts: the own
  // nodes'), and per process what each holds (candidate pairs, its own and its ghosts') and did.
  const long handed = count_handed(sim.m.icontact, sim.m.owned_ifaces());
  const Parts<D>& parts = sim.parts();
  const int n = parts.size();
  const std::vector<double> mine = {static_cast<double>(handed), static_cast<double>(ct.own_surface_nodes()),
                                    static_cast<double>(ct.active_contacts()), static_cast<double>(ct.candidates()),
                                    static_cast<double>(ct.builds()), static_cast<double>(ct.list_updates())};
  std::vector<double> all(mine.size() * n, 0.0), sum(mine.size(), 0.0);
  for (size_t i = 0; i < mine.size(); ++i) {  // (every process gets every value: sums of one-hot rows)
    std::vector<double> row(n, 0.0);
    row[parts.rank()] = mine[i];
    parts.sum(row.data(), n);
    for (int p = 0; p < n; ++p) {
      all[i * n + p] = row[p];
      sum[i] += row[p];
    }
  }
  auto per = [&](size_t i) { return std::vector<double>(all.begin() + i * n, all.begin() + (i + 1) * n); };
  return {{"interfaces_handed_over", sum[0]},
          {"surface_nodes", sum[1]},
          {"active_contacts", sum[2]},
          {"candidate_pairs", sum[3]},
          {"stable_step_s", ct.stable_step()},
          {"per_process", {{"candidate_pairs", per(3)}, {"grid_builds", per(4)}, {"list_updates", per(5)}}}};
}

}  // namespace

template <int D>
nlohmann::json run_summary(const Case& c, const nlohmann::json& counts, Simulation<D>& sim,
                           const HistoryTable<D>& history, RunFragments<D>* frag, const RunRecord& r) {
  const Energies& last = history.last();
  nlohmann::json summary;
  summary["case"] = c.name;
  summary["dimension"] = D;
  summary["counts"] = counts;
  summary["counts"]["boundary_nodes"] = r.boundary_nodes;
  summary["time_step"] = stable_report(sim);
  summary["steps"] = sim.step_count;
  summary["end_time_s"] = sim.t;
  summary["stop_reason"] = r.stop_reason;
  if (r.signal) summary["signal"] = r.signal;
  summary["wall_seconds"] = r.wall_seconds;
  summary["loop_wall_seconds"] = r.loop_wall_seconds;
  summary["element_steps_per_second"] =
      r.loop_wall_seconds > 0 ? sim.step_count * counts.value("elements", double(sim.m.ne)) / r.loop_wall_seconds
                              : 0;  // the whole mesh's elements (a run over several processes too)
  summary["phases"] = phases_report(sim.phase_times());
  summary["setup"] = setup_times::report();
  const double peak = setup_times::peak_rss_bytes();
  summary["memory"] = {{"peak_rss_bytes", peak},
                       {"peak_rss_bytes_per_element", peak / std::max(1, sim.m.ne)},
                       {"gmsh_peak_rss_bytes", setup_times::gmsh_peak_bytes()},
                       {"huge_pages", huge_pages_state()}};  // (common/huge_pages.hpp)
  if (view_memory::enabled()) {
    // the Views' peak (what a GPU would hold, less the host's scatter copies): docs/performance.md
    nlohmann::json vm = view_memory::report(64);  // (every View of a run: about 60)
    const double elems = std::max(1, sim.m.ne);
    const double scatter = vm["peak_by_kind"].value("scatter", 0.0);
    vm["peak_bytes_per_element"] = vm["peak_bytes"].get<double>() / elems;
    vm["device_bytes_per_element"] = (vm["peak_bytes"].get<double>() - scatter) / elems;
    summary["memory"]["views"] = vm;
  }
  if (kernel_times::enabled()) summary["kernel_times"] = kernel_times::report();
  summary["energy"] = energy_report(last, history.max_relative_balance_error());
  summary["energy"]["warning_threshold"] = HistoryTable<D>::kBalanceWarning;
  if (history.balance_warned_at() >= 0)
    summary["energy"]["warning"] = {{"time_s", history.balance_warned_at()},
                                    {"step", history.balance_warned_step()},
                                    {"relative_balance_error", history.balance_warned_error()}};
  summary["interfaces_damaged"] = last.damaged;
  summary["interfaces_failed"] = last.failed;
  summary["momentum_N_s"] = std::vector<double>(last.momentum, last.momentum + D);
  if (ContactSystem<D>* ct = sim.contact()) summary["contact"] = contact_report(*ct, sim);
  if (frag) {
    summary["fragments"] = frag->summary(sim);
    summary["fragment_labelling"] = frag->labelling_report();
  }
  summary["results"] = results_report(c, sim, history);
  if (r.checkpoint_every > 0 || r.restart || r.checkpoints_written > 0)
    summary["checkpoint"] = checkpoint_report(r);
  summary["outputs"] = {{"history", r.out + "/history.csv"},
                        {"summary", r.out + "/summary.json"},
                        {"case", r.out + "/case.json"}};
  if (r.snapshots) summary["outputs"]["snapshots"] = r.out + "/snapshots.xdmf";
  if (frag) summary["outputs"]["fragments"] = r.out + "/fragments.csv";
  return summary;
}

template nlohmann::json run_summary(const Case&, const nlohmann::json&, Simulation<2>&,
                                    const HistoryTable<2>&, RunFragments<2>*, const RunRecord&);
template nlohmann::json run_summary(const Case&, const nlohmann::json&, Simulation<3>&,
                                    const HistoryTable<3>&, RunFragments<3>*, const RunRecord&);

namespace {

// Every process's set-up (issue 49: the phases' times and the peak memory per process): a row per
// process of each phase's wall seconds (0 where it had none; the phases not listed summed under
// "unlisted"), its whole set-up's, its peak resident memory and its own elements, on process 0.
nlohmann::json setup_per_process(const Comm& comm, int own_elements) {
  static const std::vector<std::string> names = {
      "gmsh_meshing", "gmsh_extraction", "gmsh_process", "mesh", "refinement", "mesh_transforms",
      "mesh_checks", "renumbering", "interface_insertion", "local_parts", "local_sizes", "local_part",
      "local_whole_facts", "whole_mesh_rebuilt", "decomposition",
      "parts_sent", "mesh_kept",
      "model_elements", "model_interfaces", "contact_setup", "model_build", "part_mesh_released", "heap_released",
      "output_setup", "other"};
  const nlohmann::json st = setup_times::report();
  std::vector<double> mine(names.size() + 4, 0.0);
  for (const auto& ph : st.at("phases")) {
    const auto it = std::find(names.begin(), names.end(), ph.at("name").get<std::string>());
    mine[it == names.end() ? names.size() : it - names.begin()] += ph.at("wall_seconds").get<double>();
  }
  mine[names.size() + 1] = st.at("wall_seconds").get<double>();
  mine[names.size() + 2] = setup_times::peak_rss_bytes();
  mine[names.size() + 3] = own_elements;
  std::vector<double> all;
  comm.gather(mine, all);
  const std::size_t w = mine.size();
  nlohmann::json phases = nlohmann::json::object(), per_elem = nlohmann::json::array(),
                 total = nlohmann::json::array();
  for (std::size_t k = 0; k <= names.size(); ++k) {
    std::vector<double> col;
    bool any = false;
    for (std::size_t r = 0; r + w <= all.size(); r += w) {
      col.push_back(all[r + k]);
      any = any || all[r + k] > 0;
    }
    if (any) phases[k < names.size() ? names[k] : "unlisted"] = col;
  }
  for (std::size_t r = 0; r + w <= all.size(); r += w) {
    total.push_back(all[r + names.size() + 1]);
    per_elem.push_back(all[r + names.size() + 2] / std::max(1.0, all[r + names.size() + 3]));
  }
  return {{"setup_wall_seconds", total}, {"setup_phase_wall_seconds", phases},
          {"peak_rss_bytes_per_own_element", per_elem}};
}

}  // namespace

template <int D>
nlohmann::json processes_report(const Case& c, const Simulation<D>& sim, const CutHistory& cuts,
                                std::chrono::steady_clock::time_point loop_start, double cut_setup) {
  const Comm& comm = sim.parts().comm();
  double bytes[2] = {static_cast<double>(sim.exchange_bytes()), sim.phase_times().exchange};
  double most[2] = {-bytes[0], -bytes[1]};
  comm.sum(bytes, 2);
  comm.min(most, 2);
  std::vector<double> peaks, busy;  // every process's peak resident memory, on process 0
  comm.gather({setup_times::peak_rss_bytes()}, peaks);
  // the loop's time outside the exchange (which includes the waits for the others), every cut's
  // parts included: the measured balance
  const double loop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  const double busy_here = cuts.busy_seconds + loop_seconds - sim.phase_times().exchange;
  comm.gather(std::vector<double>{busy_here}, busy);
  const double cut_seconds = cuts.cut_seconds + cut_setup;
  const auto& b = sim.balance();
  // the excess at the first check of each part (the start's, then each cut's); null where a part
  // ended before its first check (a cut, or the run's end, within kContactPollEvery steps)
  nlohmann::json after = nlohmann::json::array();
  for (double e : cuts.excess_after_cuts) after.push_back(e >= 0 ? nlohmann::json(e) : nlohmann::json());
  after.push_back(b.after_cut >= 0 ? nlohmann::json(b.after_cut) : nlohmann::json());
  const bool checked = b.after_cut >= 0 || !cuts.excess_after_cuts.empty();
  nlohmann::json p = {{"count", comm.size()},
                      {"contact_recuts", cuts.recuts},
                      {"rebalances", cuts.rebalances},
                      {"cut_reasons", cuts.cut_reasons},
                      {"elements_moved", cuts.elements_moved},
                      {"elements_moved_at_cuts", cuts.elements_moved_at_cuts},
                      {"cut_seconds", cut_seconds},
                      {"exchange_bytes_per_step", bytes[0]},
                      {"exchange_bytes_per_step_most", -most[0]},
                      {"exchange_seconds_most", -most[1]},
                      {"gpu_aware_mpi", comm.gpu_aware()},
                      {"peak_rss_bytes", peaks},
                      {"busy_seconds", busy}};
  p.update(setup_per_process(comm, sim.m.owned_elems()));
  // the balance was checked (contact over processes: docs/parallel.md "Rebalancing")
  if (checked) {
    p["rebalance_above"] = c.rebalance_above;
    const WorkModel& wm = c.work_model;
    p["work_model_ns"] = {{"element", wm.element},
                          {"interface", wm.interface},
                          {"node", wm.node},
                          {"contact_unit", wm.contact_unit}};
    const bool last = b.after_cut >= 0;  // the last part's checks (null: it had none)
    p["work_excess"] = last ? nlohmann::json(b.excess) : nlohmann::json();
    p["work_excess_largest"] = std::max(b.largest, cuts.excess_largest);
    p["work_excess_at_rebalances"] = cuts.excess_at_rebalances;
    p["work_excess_after_cuts"] = after;
    p["work_ns_per_step_most"] = last ? nlohmann::json(b.work_most) : nlohmann::json();
    p["work_ns_per_step_mean"] = last ? nlohmann::json(b.work_mean) : nlohmann::json();
  }
  return p;
}

template nlohmann::json processes_report(const Case&, const Simulation<2>&, const CutHistory&,
                                         std::chrono::steady_clock::time_point, double);
template nlohmann::json processes_report(const Case&, const Simulation<3>&, const CutHistory&,
                                         std::chrono::steady_clock::time_point, double);

namespace {

// j[key] as a number into v (false when j is no object or holds no number there).
bool number(const nlohmann::json& j, const char* key, double& v) {
  if (!j.is_object()) return false;
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return false;
  v = it->get<double>();
  return true;
}

const nlohmann::json& member(const nlohmann::json& j, const char* key) {
  static const nlohmann::json kNull;
  if (!j.is_object()) return kNull;
  const auto it = j.find(key);
  return it == j.end() ? kNull : *it;
}

// v with 4 significant digits ("%.4g"), or with `decimals` after the point ("%.*f").
std::string g4(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// The parts joined by sep.
std::string joined(const std::vector<std::string>& parts, const char* sep) {
  std::string s;
  for (const std::string& p : parts) s += (s.empty() ? "" : sep) + p;
  return s;
}

// The strength (a disc between platens) and the peak load of every platen.
std::string key_load_lines(const nlohmann::json& results) {
  std::string text;
  double v = 0, peak = 0;
  if (number(results, "tensile_strength_Pa", v)) {
    text += "  tensile strength " + g4(v / 1e6) + " MPa";
    if (number(results, "peak_load_N", peak)) text += " (2 P / (pi D L) of the peak load " + g4(peak) + " N)";
    text += "\n";
  }
  const nlohmann::json& platens = member(results, "platens");
  std::vector<std::string> peaks;
  if (platens.is_object())
    for (auto it = platens.begin(); it != platens.end(); ++it) {
      if (!number(*it, "peak_load_N", peak)) continue;
      peaks.push_back(it.key() + " " + g4(peak) + " N");
      if (number(*it, "displacement_at_peak_m", v)) peaks.back() += " at " + g4(1e3 * v) + " mm";
    }
  if (!peaks.empty()) text += "  peak load: " + joined(peaks, ", ") + "\n";
  return text;
}

// Failed and damaged interfaces, the fragments and the largest one, the bodies broken.
std::string key_fracture_line(const nlohmann::json& summary) {
  std::vector<std::string> parts;
  double n = 0, failed = 0, v = 0;
  if (number(member(summary, "counts"), "interfaces", n) && n > 0 &&
      number(summary, "interfaces_failed", failed)) {
    parts.push_back("interfaces: " + fixed(failed, 0) + " failed");
    if (number(summary, "interfaces_damaged", v)) parts.back() += ", " + fixed(v, 0) + " damaged";
    parts.back() += " of " + fixed(n, 0);
  }
  const nlohmann::json& frag = member(summary, "fragments");
  if (number(frag, "count", n)) {
    parts.push_back("fragments: " + fixed(n, 0));
    if (number(frag, "largest_fraction", v))
      parts.back() += ", the largest " + fixed(100 * v, 1) + " % of the mass";
    const nlohmann::json& bodies = member(frag, "per_body");
    if (number(bodies, "bodies", n) && number(bodies, "broken", v))
      parts.push_back(fixed(v, 0) + " of " + fixed(n, 0) + " bodies broken");
  }
  return parts.empty() ? "" : "  " + joined(parts, "; ") + "\n";
}

// The main energies and how well they balanced.
std::string key_energy_line(const nlohmann::json& energy) {
  std::vector<std::string> terms;
  const char* names[][2] = {
      {"external_work_J", "external work"}, {"fracture_J", "fracture"}, {"kinetic_J", "kinetic"}};
  double v = 0;
  for (const auto& t : names)
    if (number(energy, t[0], v)) terms.push_back(std::string(t[1]) + " " + g4(v) + " J");
  std::vector<std::string> parts;
  if (!terms.empty()) parts.push_back(joined(terms, ", "));
  if (number(energy, "max_relative_balance_error", v)) {
    parts.push_back("balance error at most " + g4(100 * v) + " % of the energy scale");
    double limit = 0, at = 0;
    if (number(member(energy, "warning"), "time_s", at) && number(energy, "warning_threshold", limit))
      parts.back() += " (above the " + g4(100 * limit) + " % warning from t = " + g4(at) + " s)";
  }
  return parts.empty() ? "" : "  energy: " + joined(parts, "; ") + "\n";
}

}  // namespace

std::string key_results(const nlohmann::json& summary) {
  const nlohmann::json& name = member(summary, "case");
  const bool stopped = member(summary, "stop_reason") == "interrupted";  // (a restart goes on)
  std::string text = "fdem: key results" + (name.is_string() ? " of " + name.get<std::string>() : "") +
                     (stopped ? " so far (interrupted)" : "") + ":\n";
  text += key_load_lines(member(summary, "results"));
  text += key_fracture_line(summary);
  text += key_energy_line(member(summary, "energy"));
  return text;
}

void print_run_end(const nlohmann::json& summary, const RunRecord& r, long steps, bool progress) {
  if (progress) {
    std::fprintf(stderr, "fdem: %ld steps in %.1f s (%.3g element-steps/s); stopped by %s\n", steps,
                 r.loop_wall_seconds, summary["element_steps_per_second"].get<double>(),
                 r.stop_reason.c_str());
  }
  const char* out = r.out.c_str();
  std::printf("results: %s\n", out);
  std::printf("  history:   %s/history.csv\n  summary:   %s/summary.json\n", out, out);
  if (r.snapshots) std::printf("  snapshots: %s/snapshots.xdmf (open in ParaView)\n", out);
  std::fflush(stdout);
  if (progress) {  // the result the run was for, as the last lines (after the paths)
    std::fputs(key_results(summary).c_str(), stderr);
    std::fflush(stderr);
  }
}

}  // namespace fdem
