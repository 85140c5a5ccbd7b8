// A run on one process and the set-up every run shares: the case's mesh made ready (prepare_mesh),
// the output folder, the restart's checks and the derived values (prepare_run), run_case and
// check_case. The run over several processes is src/solver/run_processes.cpp.
#include "solver/run.hpp"
#include "solver/run_setup.hpp"

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
#include "mesh/refine.hpp"
#include "parallel/comm.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/homogenise.hpp"
#include "solver/interface_materials.hpp"
#include "solver/local_setup.hpp"
#include "solver/run_loop.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"
#include "solver/summary.hpp"

namespace fdem {

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

// A case's mesh as built (Gmsh, a file, a generator); a refined case's coarse mesh checked to fit
// once refined and renumbered for locality (the fine one is left in the order of its global ids,
// each coarse element's children together: the order a process that refines only its own coarse
// elements can compute, docs/parallel.md "Scale").
HostMesh prepare_coarse(const Case& c) {
  using setup_times::Phase;
  Phase build("mesh");
  HostMesh mesh = build_mesh(c.mesh, c.dim);
  build.stop();
  if (c.mesh.refine > 0) {
    Phase refine("refinement");
    check_fits_in_memory(static_cast<double>(mesh.num_elems()) * refine_factor(c.dim, c.mesh.refine), c.dim,
                         "mesh.refine = " + std::to_string(c.mesh.refine) + " (" + std::to_string(mesh.num_elems()) +
                             " coarse elements)");
    reorder_for_locality(mesh);
  }
  return mesh;
}

// Mesh of a case, ready for the solver (run.hpp). Each part is a set-up phase
// (common/setup_times.hpp; Gmsh's own inside "mesh").
HostMesh prepare_mesh(const Case& c, HostMesh* coarse) { return finish_mesh(c, prepare_coarse(c), coarse); }

// prepare_mesh after prepare_coarse: the refinement, the transforms, the checks, the renumbering,
// the interfaces and the region sets.
HostMesh finish_mesh(const Case& c, HostMesh mesh, HostMesh* coarse, bool warn) {
  using setup_times::Phase;
  const bool refined = c.mesh.refine > 0;
  if (refined) {
    Phase refine("refinement");
    if (coarse) *coarse = mesh;
    mesh = refine_mesh(mesh, c.mesh.refine, curved_surfaces(c.mesh, c.dim));
  }
  if (c.mesh.rotation_deg != 0 || c.mesh.jitter > 0) {
    Phase transform("mesh_transforms");
    transform_mesh(mesh, c.mesh);  // mesh.rotation, mesh.jitter
  }
  Phase checks("mesh_checks");
  const std::string source = c.mesh.kind == "file" ? c.mesh.file : c.file + ": mesh";
  check_elements(mesh, source);
  check_case_against_mesh(c, mesh);
  const BodyCheck bodies = check_bodies(mesh, source);  // duplicate nodes, overlapping bodies
  mesh.warnings = bodies.warnings;
  mesh.bodies = bodies.bodies;
  for (const auto& w : mesh.warnings)
    if (warn) std::fprintf(stderr, "fdem: warning: %s\n", w.c_str());
  checks.stop();
  Phase reorder("renumbering");
  reorder_for_locality(mesh, !refined);  // a refined mesh's elements keep their order (above)
  reorder.stop();
  if (!c.fracturable_regions.empty() || !c.surface_iface_material.empty()) {
    Phase insert("interface_insertion");
    std::vector<bool> frac(mesh.region_names.size(), false);
    for (const auto& r : c.fracturable_regions) frac[mesh.region_index(r)] = true;
    std::vector<std::string> cut;
    for (const auto& kv : c.surface_iface_material) cut.push_back(kv.first);
    insert_interfaces(mesh, frac, cut);
  }
  for (std::string& w : unused_material_rules(c, mesh)) {  // (the whole mesh's interfaces)
    if (warn) std::fprintf(stderr, "fdem: warning: %s\n", w.c_str());
    mesh.warnings.push_back(std::move(w));
  }
  add_region_node_sets(mesh, region_sets_used(c));
  // the exact count (a .msh file's is known only now), before the model is allocated
  check_fits_in_memory(mesh.num_elems(), mesh.dim, "the mesh of " + source);
  return mesh;
}

int refined_group(const Case& c) {
  return c.mesh.refine > 0 ? static_cast<int>(refine_factor(c.dim, c.mesh.refine) + 0.5) : 1;
}

double mean_element_size(const Case& c, const HostMesh& mesh) {
  return c.mesh.refine > 0 ? refined_mean_size(mesh, refined_group(c)) : mesh_sizes(mesh).mean_size;
}

std::vector<int> refined_partition(const Case& c, const HostMesh& coarse, int parts, PartitionMethod method) {
  const CoarseTopology topo = coarse_topology(coarse, c.mesh.refine, curved_surfaces(c.mesh, c.dim));
  const std::vector<int> cpart = partition_coarse(coarse, topo, refined_interface_offsets(coarse, topo), parts, method);
  const int group = refined_group(c);
  std::vector<int> part(cpart.size() * static_cast<size_t>(group));
  for (size_t e = 0; e < part.size(); ++e) part[e] = cpart[e / group];
  return part;
}

namespace {

// The resolved case without the keys that do not change the results: the checkpoint interval,
// and the mesh file's path (its content is in the mesh hash; the project folder may move). Taken
// of the case as read, before resolve_defaults (checkpoints of earlier versions store this hash).
// The top-level `precision` counts only when it is not the default "double": the resolved case of
// versions before the key had none, and their checkpoints still restart.
std::string case_hash(const Case& c) {
  nlohmann::json r = c.resolved;
  if (r.contains("precision") && r["precision"] == "double") r.erase("precision");
  if (r.contains("output") && r["output"].is_object()) r["output"].erase("checkpoint_every");
  if (r.contains("mesh") && r["mesh"].is_object() && r["mesh"].contains("file")) r["mesh"]["file"] = "";
  const std::string text = r.dump();
  return hash_hex(text.data(), text.size());
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
  if (diff.empty() && h.mesh_hash != id.mesh_hash && h.mesh_hash != mesh_hash_before_2026_12_07(mesh))
    diff = "the mesh coordinates or connectivity differ";
  if (diff.empty() && h.case_hash != id.case_hash)
    diff = "the case differs (give the same case file and the same --set options as the run that "
           "wrote it; only the checkpoint interval may change)";
  if (!diff.empty())
    throw InputError("restart file '" + file + "' is a checkpoint of another case or mesh: " + diff);
}

}  // namespace

void MeshHash::node(long long id, const double* x, int dim) {
  sums[0] += ckpt::rows_hash(x, 1, sizeof(double) * dim, static_cast<uint64_t>(id));
}
void MeshHash::elem(long long id, const int* nodes, int count) {
  sums[1] += ckpt::rows_hash(nodes, 1, sizeof(int) * count, static_cast<uint64_t>(id));
}
void MeshHash::iface(long long id, const int* nodes, int count) {
  sums[2] += ckpt::rows_hash(nodes, 1, sizeof(int) * count, static_cast<uint64_t>(id));
}

std::string MeshHash::hex() const { return hash_hex(sums, sizeof sums); }

std::string mesh_hash(const HostMesh& mesh) {
  // (the whole mesh's rows in order: one call per kind)
  const size_t D = static_cast<size_t>(mesh.dim);
  MeshHash h;
  h.sums[0] = ckpt::rows_hash(mesh.X.data(), mesh.num_nodes(), sizeof(double) * D, 0);
  h.sums[1] = ckpt::rows_hash(mesh.elems.data(), mesh.num_elems(), sizeof(int) * (D + 1), 0);
  h.sums[2] = ckpt::rows_hash(mesh.ifaces.data(), mesh.num_ifaces(), sizeof(int) * 2 * D, 0);
  return h.hex();
}

std::string mesh_hash_before_2026_12_07(const HostMesh& mesh) {
  uint64_t h = fnv1a(mesh.X.data(), mesh.X.size() * sizeof(double));
  h = fnv1a(mesh.elems.data(), mesh.elems.size() * sizeof(int), h);
  h = fnv1a(mesh.ifaces.data(), mesh.ifaces.size() * sizeof(int), h);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// Whether the run is over several processes (RunOptions::comm).
bool over_processes(const RunOptions& opt) { return opt.comm && opt.comm->size() > 1; }

namespace {

// Process 0 of a refined run over processes: whether the parts are built from the coarse mesh
// (local_setup_refusal); if so it is checked as prepare_mesh checks the whole mesh (its bodies and
// warnings go to every process with it) and moved into p. Else the whole set-up follows.
bool prepare_local(const Case& c, HostMesh& coarse, PreparedRun& p) {
  if (!local_setup_refusal(c, coarse, p.restarting).empty()) return false;
  setup_times::Phase checks("mesh_checks");
  const std::string source = c.mesh.kind == "file" ? c.mesh.file : c.file + ": mesh";
  check_elements(coarse, source);
  check_case_against_mesh(c, coarse);
  const BodyCheck bodies = check_bodies(coarse, source);
  coarse.warnings = bodies.warnings;
  coarse.bodies = bodies.bodies;
  for (const auto& w : coarse.warnings) std::fprintf(stderr, "fdem: warning: %s\n", w.c_str());
  p.coarse = std::move(coarse);
  p.local = true;
  return true;
}

}  // namespace

PreparedRun prepare_run(const std::string& case_path, Case& c, const RunOptions& opt) {
  const bool many = over_processes(opt);
  PreparedRun p;
  p.restarting = !opt.restart.empty();
  // over several processes a checkpoint holds the whole run's state (save_whole_state, solver/whole_state.hpp):
  // every process reads it and takes its part's rows, whatever the process count that wrote it; of
  // the entries written by rows (write_checkpoint_rows) each process reads only its rows
  // (load_whole_state, solver/whole_state.hpp)
  if (p.restarting) p.restart = read_checkpoint(opt.restart, p.header, many);
  p.out = opt.out_dir.empty() ? "out/" + c.name : opt.out_dir;
  p.id.case_hash = case_hash(c);
  if (many && opt.comm->rank() != 0) return p;  // (process 0 alone touches the folder and meshes the case)
  ensure_output_dir(p.out);
  p.lock = std::make_unique<OutputLock>(p.out);
  refuse_inputs_among_outputs(p.out, {case_path, c.mesh.kind == "file" ? c.mesh.file : ""});
  // The mesh (and a restart's match with it) before the folder is touched: a case whose mesh
  // cannot be made or would not fit leaves the results of an earlier run where they are. Over
  // several processes a refined case's parts may be built from its coarse mesh alone
  // (solver/local_setup.hpp): then only that is made here, and checked.
  if (many && c.mesh.refine > 0) {
    HostMesh coarse = prepare_coarse(c);
    if (prepare_local(c, coarse, p)) {
      if (!p.restarting) remove_old_outputs(p.out);
      return p;
    }
    p.mesh = finish_mesh(c, std::move(coarse), &p.coarse);
  } else {
    p.mesh = prepare_mesh(c, &p.coarse);
  }
  p.id.mesh_hash = mesh_hash(p.mesh);
  if (p.restarting) check_restart_matches(opt.restart, p.header, c, p.mesh, p.id);
  // A new run's folder holds only its results; a restart continues those there.
  if (!p.restarting) remove_old_outputs(p.out);
  // the case as run, with the derived values the run uses (case.json)
  resolve_defaults(c, mean_element_size(c, p.mesh));
  return p;
}

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
  auto mesh = std::make_shared<const HostMesh>(std::move(p.mesh));
  return c.dim == 2 ? run_dim<2>(c, std::move(mesh), p.out, opt, p.id, r).summary
                    : run_dim<3>(c, std::move(mesh), p.out, opt, p.id, r).summary;
}

nlohmann::json check_case(const std::string& case_path, const std::vector<std::string>& overrides, bool moduli) {
  Case c = load_case(case_path, overrides);
  const HostMesh mesh = prepare_mesh(c);
  resolve_defaults(c, mean_element_size(c, mesh));
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
