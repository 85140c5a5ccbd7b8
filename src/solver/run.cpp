#include "solver/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numeric>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh.hpp"
#include "parallel/comm.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/homogenise.hpp"
#include "solver/interface_materials.hpp"
#include "solver/run_loop.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"
#include "solver/summary.hpp"

namespace fdem {

namespace {

// The regions named by "region.<name>" node sets in the boundary conditions, loads and monitors.
std::vector<std::string> region_sets_used(const Case& c) {
  std::vector<std::string> sets = c.monitors, out;
  for (const auto& b : c.velocity_bcs) sets.push_back(b.set);
  for (const auto& p : c.point_loads) sets.push_back(p.set);
  const std::string prefix = kRegionSetPrefix;
  for (const auto& s : sets)
    if (s.compare(0, prefix.size(), prefix) == 0) out.push_back(s.substr(prefix.size()));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

// Mesh of a case, ready for the solver (run.hpp). Each part is a set-up phase
// (common/setup_times.hpp; Gmsh's own inside "mesh").
HostMesh prepare_mesh(const Case& c) {
  using setup_times::Phase;
  Phase build("mesh");
  HostMesh mesh = build_mesh(c.mesh, c.dim);
  build.stop();
  Phase checks("mesh_checks");
  const std::string source = c.mesh.kind == "file" ? c.mesh.file : c.file + ": mesh";
  check_elements(mesh, source);
  check_case_against_mesh(c, mesh);
  const BodyCheck bodies = check_bodies(mesh, source);  // duplicate nodes, overlapping bodies
  mesh.warnings = bodies.warnings;
  mesh.bodies = bodies.bodies;
  for (const auto& w : mesh.warnings) std::fprintf(stderr, "fdem: warning: %s\n", w.c_str());
  checks.stop();
  Phase reorder("renumbering");
  reorder_for_locality(mesh);
  reorder.stop();
  if (!c.fracturable_regions.empty() || !c.surface_iface_material.empty()) {
    Phase insert("interface_insertion");
    std::vector<bool> frac(mesh.region_names.size(), false);
    for (const auto& r : c.fracturable_regions) frac[mesh.region_index(r)] = true;
    std::vector<std::string> cut;
    for (const auto& kv : c.surface_iface_material) cut.push_back(kv.first);
    insert_interfaces(mesh, frac, cut);
  }
  add_region_node_sets(mesh, region_sets_used(c));
  // the exact count (a .msh file's is known only now), before the model is allocated
  check_fits_in_memory(mesh.num_elems(), mesh.dim, "the mesh of " + source);
  return mesh;
}

namespace {

// The resolved case without the keys that do not change the results: the checkpoint interval,
// and the mesh file's path (its content is in the mesh hash; the project folder may move). Taken
// of the case as read, before resolve_defaults (checkpoints of earlier versions store this hash).
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

// What run_case and the run over several processes set up alike before the model is built: the
// checkpoint to go on from, the output folder, and on the process that writes (one process, or
// process 0 of several) the folder made and locked, the prepared mesh, a restart's match with the
// case and mesh, a new run's old outputs removed, the case's derived values (resolve_defaults).
struct PreparedRun {
  std::string out;                   // the output folder
  std::unique_ptr<OutputLock> lock;  // the folder is this run's until it ends
  bool restarting = false;           // RunOptions::restart given
  StateArrays restart;               // its checkpoint
  CheckpointHeader header;
  HostMesh mesh;   // over several processes on process 0 only
  RunIdentity id;  // (the mesh's hash on the process that writes)
  // The checkpoint the run goes on from; null: a new run.
  const StateArrays* checkpoint() const { return restarting ? &restart : nullptr; }
};

// Whether the run is over several processes (RunOptions::comm).
bool over_processes(const RunOptions& opt) { return opt.comm && opt.comm->size() > 1; }

PreparedRun prepare_run(const std::string& case_path, Case& c, const RunOptions& opt) {
  const bool many = over_processes(opt);
  PreparedRun p;
  p.restarting = !opt.restart.empty();
  // over several processes a checkpoint holds the whole run's state (Simulation::save_state_whole):
  // every process reads it and takes its part's rows, whatever the process count that wrote it; of
  // the entries written by rows (write_checkpoint_rows) each process reads only its rows
  // (Simulation::load_state_whole)
  if (p.restarting) p.restart = read_checkpoint(opt.restart, p.header, many);
  p.out = opt.out_dir.empty() ? "out/" + c.name : opt.out_dir;
  p.id.case_hash = case_hash(c);
  if (many && opt.comm->rank() != 0) return p;  // (process 0 alone touches the folder and meshes the case)
  ensure_output_dir(p.out);
  p.lock = std::make_unique<OutputLock>(p.out);
  refuse_inputs_among_outputs(p.out, {case_path, c.mesh.kind == "file" ? c.mesh.file : ""});
  // The mesh (and a restart's match with it) before the folder is touched: a case whose mesh
  // cannot be made or would not fit leaves the results of an earlier run where they are.
  p.mesh = prepare_mesh(c);
  p.id.mesh_hash = mesh_hash(p.mesh);
  if (p.restarting) check_restart_matches(opt.restart, p.header, c, p.mesh, p.id);
  // A new run's folder holds only its results; a restart continues those there.
  if (!p.restarting) remove_old_outputs(p.out);
  // the case as run, with the derived values the run uses (case.json)
  resolve_defaults(c, p.mesh);
  return p;
}

// The measurement switch FDEM_CUT_METHOD (docs/parallel.md, "Rebalancing"): "rcb" (or unset), the
// cut by Zoltan's RCB; "metis", by METIS's graph of the interfaces not handed over to contact.
bool cut_by_graph() {
  const char* m = std::getenv("FDEM_CUT_METHOD");
  if (!m || !*m || std::string(m) == "rcb") return false;
  if (std::string(m) == "metis") return true;
  throw InputError("FDEM_CUT_METHOD='" + std::string(m) + "': give rcb or metis (unset: rcb)");
}

// Process 0 at a restart: every row of an entry per node left in the checkpoint (StateArrays::by_rows),
// verified against its stored checksum, into `s`.
void whole_rows_of(StateArrays& s, const std::string& name, const HostMesh& mesh) {
  const int nn = mesh.num_nodes();
  std::vector<int> all(static_cast<size_t>(nn));
  std::iota(all.begin(), all.end(), 0);
  uint64_t hash = 0;
  std::vector<double> v = read_rows(s, name, all, all.size(), all.size(), 1, nn, mesh.dim, hash);
  if (!rows_checksum_matches(s, name, hash))
    throw InputError("restart file '" + s.file + "' is damaged: dataset '" + name + "' fails its checksum");
  s.f64[name] = std::move(v);
}

// Every process's part of `mesh` (decompose), packed for sending.
std::vector<std::vector<char>> packed_parts(const HostMesh& mesh, const std::vector<int>& elem_part, int parts,
                                            double reach, const std::vector<double>* at) {
  std::vector<SubMesh> all = decompose(mesh, elem_part, parts, reach, at);
  std::vector<std::vector<char>> out;
  for (SubMesh& s : all) {
    out.push_back(pack_submesh(s));
    s = SubMesh{};  // packed: freed
  }
  return out;
}

// A run over several processes (RunOptions::comm; docs/parallel.md): what it cannot do yet is
// refused, naming the key. Process 0 meshes the case, partitions and decomposes it and sends each
// process its part (the others never hold the whole mesh); every process runs its part; process 0
// alone touches the output folder (every process reads a restart's checkpoint). With contact the
// parts are cut anew when a run loop asks for it (RunLoop::run: LoopEnd::Kind::cut_due), and the
// next run loop goes on from the whole state, on the new parts.
class ProcessesRun {
 public:
  ProcessesRun(const std::string& case_path, Case& c, const RunOptions& opt)
      : comm_(*opt.comm), root_(comm_.rank() == 0), c_(c), opt_(opt), prep_(prepare_run(case_path, c, opt)) {
    opt_.progress = opt.progress && root_;
  }
  nlohmann::json run();

 private:
  void first_parts();
  std::vector<int> restart_parts(const std::vector<double>& at, PartitionMethod bisection) const;
  void send_first_parts();
  void receive_part();
  void hold_part_only();
  void take_restart_cuts();
  LoopEnd run_part();
  void record_cut(const CutRequest& cut);
  std::vector<std::vector<char>> cut_anew();
  std::vector<int> parts_by_work(const std::vector<double>& x) const;
  void send_cut(std::vector<std::vector<char>>& states);

  const Comm& comm_;
  const bool root_;
  Case& c_;
  RunOptions opt_;  // (the progress lines on process 0 only)
  PreparedRun prep_;
  double mean_size_ = std::numeric_limits<double>::infinity();  // process 0's mean element size
  std::vector<std::vector<char>> packed_;  // process 0: every process's part, packed for sending
  SubMesh part_;                           // this process's part
  // process 0, with contact: the whole mesh, to cut the parts anew, and the contact zones' reach
  std::unique_ptr<HostMesh> whole_;
  double whole_reach_ = 0;
  std::vector<int> elem_part_at_start_;  // process 0: the parts this run starts with
  CutHistory cuts_;
  const StateArrays* from_ = nullptr;  // the state the next parts start from (a checkpoint, a cut's)
};

nlohmann::json ProcessesRun::run() {
  if (root_) first_parts();
  // (an error on process 0 above ends every process: the others wait in the sending)
  send_first_parts();
  take_restart_cuts();
  for (;;) {
    LoopEnd end = run_part();
    if (end.kind != LoopEnd::Kind::cut_due) return std::move(end.summary);
    // Cutting the parts anew: the nodes have moved so far that a contact zone may soon miss a
    // face, or the balance asks for it. Process 0 partitions the elements by coordinate bisection
    // at the current positions (the parts follow where the material is now, so each zone stays a
    // thin layer around a compact region; METIS's graph does not know where fragments have flown),
    // decomposes the whole mesh with the zones at the current positions and sends each process its
    // part and the whole state, which each takes its rows of, as from a checkpoint
    // (Simulation::load_state_whole): elements, nodes, interface and contact histories move to
    // their new owners.
    const auto cut0 = std::chrono::steady_clock::now();
    record_cut(end.cut);
    std::vector<std::vector<char>> states;
    if (root_) states = cut_anew();
    send_cut(states);
    cuts_.cut_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - cut0).count();
  }
}

// Process 0: the first parts, packed for sending. With contact each part holds the faces within its
// contact zone (reach: the search distance, the contact law's penetration depth, ContactSystem::set_law,
// and the skin, and contact.zone), and the whole mesh is kept for cutting the parts anew.
void ProcessesRun::first_parts() {
  const HostMesh& mesh = prep_.mesh;
  const MeshQuality mq = mesh_quality(mesh);
  mean_size_ = mq.mean_size;
  setup_times::Phase phase("decomposition");
  const double reach = contact_wanted(c_, mesh) ? contact_penetration_depth(mq.min_size, mq.mean_size) +
                                                      c_.contact.skin + c_.contact.zone
                                                : 0.0;
  // METIS when the build has it, else coordinate bisection (Zoltan's RCB where the build has
  // Zoltan, as every MPI build does; docs/parallel.md). A restart with contact cuts its parts
  // where the run last cut them (the checkpoint's processes/cut_x), as the run did: coordinate
  // bisection there after a cut during the run; so its zones hold as they did, and on as many
  // processes the parts are the same (the run goes on to the bit)
  const PartitionMethod bisection =
      partition_has_zoltan() ? PartitionMethod::ZoltanRcb : PartitionMethod::Rcb;
  const PartitionMethod method = partition_has_metis() ? PartitionMethod::Metis : bisection;
  if (reach > 0) cut_by_graph();  // a bad FDEM_CUT_METHOD fails here, before the run
  StateArrays& restart = prep_.restart;
  if (reach > 0 && restart.by_rows.count("processes/cut_x")) whole_rows_of(restart, "processes/cut_x", mesh);
  const bool resumed = reach > 0 && restart.f64.count("processes/cut_x");
  const std::vector<double>* at =
      resumed ? &restart.array("processes/cut_x", static_cast<long long>(mesh.X.size())) : nullptr;
  std::vector<int> elem_part =
      resumed && restart.has("processes/contact_recuts") && restart.get_int("processes/contact_recuts") > 0
          ? restart_parts(*at, bisection)
          : partition_elements(mesh, comm_.size(), method);
  packed_ = packed_parts(mesh, elem_part, comm_.size(), reach, at);
  elem_part_at_start_ = std::move(elem_part);
  if (reach > 0) {
    whole_ = std::make_unique<HostMesh>(mesh);  // (kept for cutting the parts anew during the run)
    whole_reach_ = reach;
  }
}

// Process 0 at a restart of a run that cut its parts anew: the parts of the last cut on as many
// processes (weighted by the work then); else coordinate bisection at the cut's positions `at`
// (checkpoints written before 2026-12-04 hold no parts).
std::vector<int> ProcessesRun::restart_parts(const std::vector<double>& at, PartitionMethod bisection) const {
  const StateArrays& restart = prep_.restart;
  const long long count = restart.has("processes/count") ? restart.get_int("processes/count") : 1;
  if (count != comm_.size() || !restart.i64.count("processes/cut_parts")) {
    HostMesh moved = prep_.mesh;
    moved.X = at;
    return partition_elements(moved, comm_.size(), bisection);
  }
  const std::vector<long long>& cp = restart.int_array("processes/cut_parts");
  const std::string& file = opt_.restart;
  if (cp.size() != static_cast<size_t>(prep_.mesh.num_elems()))
    throw InputError("checkpoint '" + file + "': processes/cut_parts has " + std::to_string(cp.size()) +
                     " entries, not " + std::to_string(prep_.mesh.num_elems()) + " (the file is damaged)");
  std::vector<int> elem_part;
  for (long long p : cp) {
    if (p < 0 || p >= comm_.size())
      throw InputError("checkpoint '" + file + "': processes/cut_parts holds part " + std::to_string(p) +
                       " outside [0, " + std::to_string(comm_.size() - 1) + "] (the file is damaged)");
    elem_part.push_back(static_cast<int>(p));
  }
  return elem_part;
}

// Every process: its first part from process 0, the case's derived values (the others: from
// process 0's mean element size, the same values) and case.json (process 0).
void ProcessesRun::send_first_parts() {
  {
    setup_times::Phase phase("parts_sent");
    receive_part();
  }
  comm_.min(&mean_size_, 1);  // process 0's
  if (root_) {
    write_file_atomic(prep_.out + "/case.json", c_.resolved.dump(2) + "\n");  // (defaults: prepare_run)
  } else {
    resolve_defaults(c_, mean_size_);  // the same values from the same mean size
    hold_part_only();
  }
}

// This process's part from process 0 (packed_ there).
void ProcessesRun::receive_part() {
  std::vector<char> mine;
  comm_.scatter_bytes(packed_, mine);
  part_ = unpack_submesh(mine);
}

// A process other than process 0 holds no whole mesh: its run loop's is an empty one with the
// dimension and the part's body count.
void ProcessesRun::hold_part_only() {
  prep_.mesh = HostMesh{};
  prep_.mesh.dim = c_.dim;
  prep_.mesh.bodies = part_.mesh.bodies;
}

// The cuts so far of the run the checkpoint is of (a restart on as many processes cuts its parts
// where that run did: process 0's parts at the start are the last cut's), and the state the first
// parts start from.
void ProcessesRun::take_restart_cuts() {
  const StateArrays& restart = prep_.restart;
  cuts_.load(restart);
  if (root_ && cuts_.recuts > 0 && restart.has("processes/contact_recuts"))
    cuts_.cut_parts = elem_part_at_start_;
  cuts_.restarted = prep_.checkpoint();
  from_ = prep_.checkpoint();
}

// This process's part run from from_ until the run ends or its parts are to be cut anew.
LoopEnd ProcessesRun::run_part() {
  HostMesh& mesh = prep_.mesh;  // (taken by the run loop)
  return c_.dim == 2 ? run_dim<2>(c_, std::move(mesh), prep_.out, opt_, prep_.id, from_, &part_, &cuts_)
                     : run_dim<3>(c_, std::move(mesh), prep_.out, opt_, prep_.id, from_, &part_, &cuts_);
}

// A cut into the CutHistory: why (for the progress note of the next parts), the balance's excesses,
// this process's busy time in the parts that ended, the cut's time so far.
void ProcessesRun::record_cut(const CutRequest& cut) {
  ++cuts_.recuts;
  cuts_.cut_seconds += cut.gather_seconds + cut.setup_seconds;
  const bool work = cut.reason == "work";
  cuts_.excess_after_cuts.push_back(cut.after_cut);
  cuts_.excess_largest = std::max(cuts_.excess_largest, cut.largest);
  cuts_.busy_seconds += cut.busy;
  char why[200];
  if (work) {
    ++cuts_.rebalances;
    cuts_.excess_at_rebalances.push_back(cut.excess);
    std::snprintf(why, sizeof why,
                  "the most loaded process's work was %.0f %% above the mean, "
                  "parallel.rebalance_above = %.3g",
                  100.0 * cut.excess, c_.rebalance_above);
  } else {
    std::snprintf(why, sizeof why, "nodes had moved far into the contact zones");
  }
  cuts_.last_cut_reason = why;
  cuts_.cut_reasons.push_back(cut.reason);
}

// Process 0 at a cut: the new parts (parts_by_work; the test hook FDEM_TEST_RECUT moves every
// element to another process), the elements that change process counted, every process's part
// packed, and the whole state packed for each; the whole mesh again for the next run loop.
std::vector<std::vector<char>> ProcessesRun::cut_anew() {
  setup_times::Phase phase("decomposition");
  const std::vector<double>& x = cuts_.state.array("model/x", static_cast<long long>(whole_->X.size()));
  std::vector<int> elem_part = parts_by_work(x);
  if (std::getenv("FDEM_TEST_RECUT"))  // test hook (Simulation): every element to another process
    for (int& p : elem_part) p = (p + cuts_.recuts) % comm_.size();
  const std::vector<int>& before = cuts_.cut_parts.empty() ? elem_part_at_start_ : cuts_.cut_parts;
  long long moved_now = 0;  // the elements that change process at this cut
  for (size_t e = 0; e < elem_part.size(); ++e) moved_now += e >= before.size() || before[e] != elem_part[e];
  cuts_.elements_moved_at_cuts.push_back(moved_now);
  cuts_.elements_moved += moved_now;
  cuts_.cut_parts = elem_part;  // (checkpoints: a restart on as many processes cuts the same parts)
  packed_ = packed_parts(*whole_, elem_part, comm_.size(), whole_reach_, &x);
  const std::vector<char> bytes = pack_state(cuts_.state);
  std::vector<std::vector<char>> states(static_cast<size_t>(comm_.size()), bytes);
  prep_.mesh = *whole_;
  return states;
}

// The parts of a cut, at the current positions x: the elements weighted by their modelled work of
// a step (WorkModel: their own and their nodes' contact work; docs/parallel.md "Rebalancing"), so
// that the parts carry equal work, not equal element counts, where the contacts gather.
std::vector<int> ProcessesRun::parts_by_work(const std::vector<double>& x) const {
  const StateArrays& state = cuts_.state;
  const std::vector<double>& nw = state.array("recut/node_work", static_cast<long long>(whole_->num_nodes()));
  HostMesh moved = *whole_;
  moved.X = x;
  const std::vector<long long>& handed =
      state.int_array("model/icontact", static_cast<long long>(whole_->num_ifaces()));
  const std::vector<double> work = element_work(moved, nw, handed, c_.work_model);
  if (!cut_by_graph()) return partition_elements_weighted(moved, comm_.size(), work);
  // (measurement switch) METIS on the graph of the interfaces not handed over
  std::vector<double> x3(3 * static_cast<size_t>(moved.num_nodes()), 0.0), gone(handed.size());
  for (int n = 0; n < moved.num_nodes(); ++n)
    for (int k = 0; k < moved.dim; ++k)
      x3[3 * static_cast<size_t>(n) + k] = x[static_cast<size_t>(n) * moved.dim + k];
  for (size_t i = 0; i < handed.size(); ++i) gone[i] = handed[i] != 0;
  return partition_elements_weighted(moved_mesh(moved, x3, gone), comm_.size(), work, true);
}

// Every process at a cut: its new part and the whole state at the cut from process 0 (states
// there), which the next parts start from.
void ProcessesRun::send_cut(std::vector<std::vector<char>>& states) {
  receive_part();
  std::vector<char> mine;
  comm_.scatter_bytes(states, mine);
  cuts_.state = unpack_state(mine);
  cuts_.state.file = "(the run's state where its parts were cut anew)";
  if (!root_) hold_part_only();
  from_ = &cuts_.state;
}

nlohmann::json run_over_processes(const std::string& case_path, Case& c, const RunOptions& opt) {
  return ProcessesRun(case_path, c, opt).run();
}

}  // namespace

nlohmann::json run_case(const std::string& case_path, const RunOptions& opt) {
  setup_times::reset();
  Case c = load_case(case_path, opt.overrides);
  if (!std::isfinite(opt.checkpoint_every))  // NaN too
    throw InputError("--checkpoint-every must be a finite time in seconds");
  if (over_processes(opt)) return run_over_processes(case_path, c, opt);
  PreparedRun p = prepare_run(case_path, c, opt);
  write_file_atomic(p.out + "/case.json", c.resolved.dump(2) + "\n");
  // the run takes the mesh and frees it once it is set up
  const StateArrays* r = p.checkpoint();
  return c.dim == 2 ? run_dim<2>(c, std::move(p.mesh), p.out, opt, p.id, r).summary
                    : run_dim<3>(c, std::move(p.mesh), p.out, opt, p.id, r).summary;
}

nlohmann::json check_case(const std::string& case_path, const std::vector<std::string>& overrides, bool moduli) {
  Case c = load_case(case_path, overrides);
  const HostMesh mesh = prepare_mesh(c);
  resolve_defaults(c, mesh);
  nlohmann::json report = {{"case", c.name}, {"dimension", c.dim}, {"mesh", mesh_report(mesh)}};
  if (mesh.num_ifaces() > 0) {
    report["interfaces"] = interface_material_report(c, interface_material_map(c, mesh));
    for (const auto& [name, qs] : mesh.iface_sets)  // named curves or surfaces that interfaces lie on
      if (!qs.empty()) report["interfaces"]["interfaces_per_surface"][name] = qs.size();
  }
  const MemoryBudget mem = available_memory();
  report["memory"] = {{"estimated_bytes", mesh.num_elems() * bytes_per_element(c.dim)},
                      {"available_bytes", mem.bytes},
                      {"available_from", mem.source}};
  auto add_dt = [&](const auto& sim) {
    report["time_step"] = stable_report(sim);
    report["steps_to_end_time"] = std::ceil(c.end_time / sim.dt);  // at the starting step
  };
  if (c.dim == 2) add_dt(Simulation<2>(c, mesh));
  else add_dt(Simulation<3>(c, mesh));
  if (moduli) report["effective_moduli"] = effective_moduli_report(c, effective_moduli(c, mesh));
  return report;
}

}  // namespace fdem
