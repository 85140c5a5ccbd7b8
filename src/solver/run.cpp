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

}  // namespace

namespace {

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
// alone touches the output folder (every process reads a restart's checkpoint).
nlohmann::json run_over_processes(const std::string& case_path, Case& c, const RunOptions& opt) {
  const Comm& comm = *opt.comm;
  const bool root = comm.rank() == 0;
  // a checkpoint holds the whole run's state (Simulation::save_state_whole): every process reads
  // it and takes its part's rows, whatever the process count that wrote it; of the entries written
  // by rows (write_checkpoint_rows) each process reads only its rows (Simulation::load_state_whole)
  StateArrays restart;
  CheckpointHeader header;
  if (!opt.restart.empty()) restart = read_checkpoint(opt.restart, header, true);
  const std::string out = opt.out_dir.empty() ? "out/" + c.name : opt.out_dir;
  std::unique_ptr<OutputLock> lock;
  HostMesh mesh;  // the whole mesh on process 0; elsewhere only its dimension and body count
  RunIdentity id{case_hash(c), ""};
  double mean_size = std::numeric_limits<double>::infinity();
  std::vector<std::vector<char>> parts;
  std::unique_ptr<HostMesh> whole;  // process 0, with contact: the whole mesh, to cut the parts anew
  double whole_reach = 0;
  std::vector<int> elem_part_at_start;  // process 0: the parts this run starts with
  if (root) {
    ensure_output_dir(out);
    lock = std::make_unique<OutputLock>(out);
    refuse_inputs_among_outputs(out, {case_path, c.mesh.kind == "file" ? c.mesh.file : ""});
    mesh = prepare_mesh(c);
    id.mesh_hash = mesh_hash(mesh);
    if (!opt.restart.empty()) check_restart_matches(opt.restart, header, c, mesh, id);
    if (opt.restart.empty()) remove_old_outputs(out);
    const MeshQuality mq = mesh_quality(mesh);
    mean_size = mq.mean_size;
    resolve_defaults(c, mesh);
    setup_times::Phase phase("decomposition");
    // with contact each part holds the faces within its contact zone: the search distance (the
    // contact law's penetration depth, ContactSystem::set_law, and the skin) and contact.zone
    const double reach = contact_wanted(c, mesh) ? 0.25 * (mq.min_size > 0 ? mq.min_size : mq.mean_size) +
                                                       c.contact.skin + c.contact.zone
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
    if (reach > 0 && restart.by_rows.count("processes/cut_x"))
      whole_rows_of(restart, "processes/cut_x", mesh);
    const bool resumed = reach > 0 && restart.f64.count("processes/cut_x");
    const std::vector<double>* at =
        resumed ? &restart.array("processes/cut_x", static_cast<long long>(mesh.X.size())) : nullptr;
    std::vector<int> elem_part;
    if (resumed && restart.has("processes/contact_recuts") && restart.get_int("processes/contact_recuts") > 0) {
      // the parts of the last cut on as many processes (weighted by the work then); else coordinate
      // bisection at the cut's positions (checkpoints written before 2026-12-04 hold no parts)
      const long long count = restart.has("processes/count") ? restart.get_int("processes/count") : 1;
      if (count == comm.size() && restart.i64.count("processes/cut_parts")) {
        const std::vector<long long>& cp = restart.int_array("processes/cut_parts");
        if (cp.size() != static_cast<size_t>(mesh.num_elems()))
          throw InputError("checkpoint '" + opt.restart + "': processes/cut_parts has " + std::to_string(cp.size()) +
                           " entries, not " + std::to_string(mesh.num_elems()) + " (the file is damaged)");
        for (long long p : cp) {
          if (p < 0 || p >= comm.size())
            throw InputError("checkpoint '" + opt.restart + "': processes/cut_parts holds part " + std::to_string(p) +
                             " outside [0, " + std::to_string(comm.size() - 1) + "] (the file is damaged)");
          elem_part.push_back(static_cast<int>(p));
        }
      } else {
        HostMesh moved = mesh;
        moved.X = *at;
        elem_part = partition_elements(moved, comm.size(), bisection);
      }
    } else {
      elem_part = partition_elements(mesh, comm.size(), method);
    }
    parts = packed_parts(mesh, elem_part, comm.size(), reach, at);
    elem_part_at_start = std::move(elem_part);
    if (reach > 0) {
      whole = std::make_unique<HostMesh>(mesh);  // (kept for cutting the parts anew during the run)
      whole_reach = reach;
    }
  }
  // (an error on process 0 above ends every process: the others wait here)
  SubMesh part;
  {
    setup_times::Phase phase("parts_sent");
    std::vector<char> mine;
    comm.scatter_bytes(parts, mine);
    part = unpack_submesh(mine);
  }
  comm.min(&mean_size, 1);  // process 0's
  if (root) {
    write_file_atomic(out + "/case.json", c.resolved.dump(2) + "\n");  // (defaults resolved above)
  } else {
    resolve_defaults(c, mean_size);  // the same values from the same mean size
    mesh.dim = c.dim;
    mesh.bodies = part.mesh.bodies;
  }
  RunOptions o = opt;
  if (restart.has("processes/contact_recuts")) o.recuts = static_cast<int>(restart.get_int("processes/contact_recuts"));
  if (restart.has("processes/rebalances")) o.rebalances = static_cast<int>(restart.get_int("processes/rebalances"));
  if (restart.has("processes/elements_moved")) o.elements_moved = restart.get_int("processes/elements_moved");
  if (root && o.recuts > 0 && restart.has("processes/contact_recuts")) o.cut_parts = elem_part_at_start;
  o.progress = opt.progress && root;
  const StateArrays* r = opt.restart.empty() ? nullptr : &restart;
  StateArrays recut;  // the whole state at a cut (Simulation::recut_due)
  o.recut = &recut;
  o.restarted = r;
  for (;;) {
    nlohmann::json summary = c.dim == 2 ? run_dim<2>(c, std::move(mesh), out, o, id, r, &part)
                                        : run_dim<3>(c, std::move(mesh), out, o, id, r, &part);
    if (!summary.contains("recut")) return summary;
    // Cutting the parts anew: the nodes have moved so far that a contact zone may soon miss a face.
    // Process 0 partitions the elements by coordinate bisection at the current positions (the
    // parts follow where the material is now, so each zone stays a thin layer around a compact
    // region; METIS's graph does not know where fragments have flown), decomposes the whole mesh
    // with the zones at the current positions and sends each process its part and the whole
    // state, which each takes its rows of, as from a checkpoint (Simulation::load_state_whole):
    // elements, nodes, interface and contact histories move to their new owners.
    // The cut is weighted by each element's modelled work of a step (WorkModel: its own and its
    // nodes' contact work; docs/parallel.md "Rebalancing"), so the parts carry equal work, not
    // equal element counts, where the contacts gather.
    const auto cut0 = std::chrono::steady_clock::now();
    ++o.recuts;
    o.cut_seconds += summary.value("gather_seconds", 0.0) + summary.value("setup_seconds", 0.0);
    const std::string reason = summary.value("reason", std::string());
    const bool work = reason == "work";
    const double excess = summary.value("excess", 0.0);
    o.excess_after_cuts.push_back(summary.value("after_cut", 0.0));
    o.excess_largest = std::max(o.excess_largest, summary.value("largest", 0.0));
    o.busy_seconds += summary.value("busy", 0.0);
    char why[200];
    if (work) {
      ++o.rebalances;
      o.excess_at_rebalances.push_back(excess);
      std::snprintf(why, sizeof why, "the most loaded process's work was %.0f %% above the mean, "
                    "parallel.rebalance_above = %.3g", 100.0 * excess, c.rebalance_above);
    } else {
      std::snprintf(why, sizeof why, "nodes had moved far into the contact zones");
    }
    o.last_cut_reason = why;
    o.cut_reasons.push_back(reason);
    std::vector<std::vector<char>> states;
    if (root) {
      setup_times::Phase phase("decomposition");
      const std::vector<double>& x = recut.array("model/x", static_cast<long long>(whole->X.size()));
      const std::vector<double>& nw = recut.array("recut/node_work", static_cast<long long>(whole->num_nodes()));
      std::vector<int> elem_part;
      {
        HostMesh moved = *whole;
        moved.X = x;
        const std::vector<long long>& handed =
            recut.int_array("model/icontact", static_cast<long long>(whole->num_ifaces()));
        const std::vector<double> work = element_work(moved, nw, handed, c.work_model);
        if (cut_by_graph()) {  // (measurement switch) METIS on the graph of the interfaces not handed over
          std::vector<double> x3(3 * static_cast<size_t>(moved.num_nodes()), 0.0), gone(handed.size());
          for (int n = 0; n < moved.num_nodes(); ++n)
            for (int k = 0; k < moved.dim; ++k)
              x3[3 * static_cast<size_t>(n) + k] = x[static_cast<size_t>(n) * moved.dim + k];
          for (size_t i = 0; i < handed.size(); ++i) gone[i] = handed[i] != 0;
          elem_part = partition_elements_weighted(moved_mesh(moved, x3, gone), comm.size(), work, true);
        } else {
          elem_part = partition_elements_weighted(moved, comm.size(), work);
        }
      }
      if (std::getenv("FDEM_TEST_RECUT"))  // test hook (Simulation): every element to another process
        for (int& p : elem_part) p = (p + o.recuts) % comm.size();
      const std::vector<int>& before = o.cut_parts.empty() ? elem_part_at_start : o.cut_parts;
      long long moved_now = 0;  // the elements that change process at this cut
      for (size_t e = 0; e < elem_part.size(); ++e)
        moved_now += e >= before.size() || before[e] != elem_part[e];
      o.elements_moved_at_cuts.push_back(moved_now);
      o.elements_moved += moved_now;
      o.cut_parts = elem_part;  // (checkpoints: a restart on as many processes cuts the same parts)
      parts = packed_parts(*whole, elem_part, comm.size(), whole_reach, &x);
      const std::vector<char> bytes = pack_state(recut);
      states.assign(static_cast<size_t>(comm.size()), bytes);
      mesh = *whole;
    } else {
      mesh = HostMesh{};
      mesh.dim = c.dim;
    }
    std::vector<char> mine;
    comm.scatter_bytes(parts, mine);
    part = unpack_submesh(mine);
    comm.scatter_bytes(states, mine);
    recut = unpack_state(mine);
    recut.file = "(the run's state where its parts were cut anew)";
    if (!root) mesh.bodies = part.mesh.bodies;
    r = &recut;
    o.cut_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - cut0).count();
  }
}

}  // namespace

nlohmann::json run_case(const std::string& case_path, const RunOptions& opt) {
  setup_times::reset();
  Case c = load_case(case_path, opt.overrides);
  if (!std::isfinite(opt.checkpoint_every))  // NaN too
    throw InputError("--checkpoint-every must be a finite time in seconds");
  if (opt.comm && opt.comm->size() > 1) return run_over_processes(case_path, c, opt);
  StateArrays restart;
  CheckpointHeader header;
  if (!opt.restart.empty()) restart = read_checkpoint(opt.restart, header);
  const std::string out = opt.out_dir.empty() ? "out/" + c.name : opt.out_dir;
  ensure_output_dir(out);
  const OutputLock lock(out);  // the folder is this run's until it returns
  refuse_inputs_among_outputs(out, {case_path, c.mesh.kind == "file" ? c.mesh.file : ""});
  // The mesh (and a restart's match with it) before the folder is touched: a case whose mesh
  // cannot be made or would not fit leaves the results of an earlier run where they are.
  HostMesh mesh = prepare_mesh(c);
  const RunIdentity id{case_hash(c), mesh_hash(mesh)};
  const StateArrays* r = nullptr;
  if (!opt.restart.empty()) {
    check_restart_matches(opt.restart, header, c, mesh, id);
    r = &restart;
  }
  // A new run's folder holds only its results; a restart continues those there.
  if (opt.restart.empty()) remove_old_outputs(out);
  // case.json: the case as run, with the derived values the run uses
  resolve_defaults(c, mesh);
  write_file_atomic(out + "/case.json", c.resolved.dump(2) + "\n");
  // the run takes the mesh and frees it once it is set up
  return c.dim == 2 ? run_dim<2>(c, std::move(mesh), out, opt, id, r)
                    : run_dim<3>(c, std::move(mesh), out, opt, id, r);
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
