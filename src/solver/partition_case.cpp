// `fdem partition` (parallel/partition.hpp: partition_case): the case's mesh as a run prepares it
// (prepare_mesh, solver/run.hpp: hence here, above src/parallel), its partition, the statistics,
// and the files partition.json and partition.vtk.
#include <algorithm>
#include <chrono>
#include <numeric>
#include <cstring>
#include <filesystem>

#include "common/error.hpp"
#include "io/case.hpp"
#include "io/hdf5_util.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/run.hpp"

namespace fdem {

namespace {

// The last frame of a snapshots.h5 (src/io/snapshot_writer.cpp): node coordinates (nn x 3) and
// interface damage (ni). InputError naming the file when it is not one of this mesh.
struct Frame {
  double time = 0;
  std::vector<double> x, damage;
};

Frame read_last_frame(const std::string& path, const HostMesh& mesh) {
  const std::string what = "--snapshot " + path;
  if (!std::filesystem::is_regular_file(path)) throw InputError(what + ": no such file");
  h5::silence();
  const h5::Id fapl = h5::file_access_without_locking();
  const h5::Id f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.ok() ? fapl.get() : H5P_DEFAULT), H5Fclose);
  if (!f.ok()) throw InputError(what + ": not an HDF5 file (" + h5::reason() + ")");
  std::string last;  // zero-padded step numbers: the largest name is the last frame
  H5G_info_t info{};
  if (H5Gget_info(f.get(), &info) >= 0)
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      char name[64] = {0};
      if (H5Lget_name_by_idx(f.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0)
        continue;
      if (std::strncmp(name, "step_", 5) == 0 && std::string(name) > last) last = name;
    }
  if (last.empty()) throw InputError(what + ": no snapshot frame (step_...) in it");
  const h5::Id g(H5Gopen2(f.get(), last.c_str(), H5P_DEFAULT), H5Gclose);
  Frame fr;
  h5::read_scalar_attr(g.get(), "time", H5T_NATIVE_DOUBLE, fr.time);
  auto read = [&](const char* name, size_t n) {
    std::vector<double> v(n);
    const h5::Id d(H5Dopen2(g.get(), name, H5P_DEFAULT), H5Dclose);
    const h5::Id sp(d.ok() ? H5Dget_space(d.get()) : -1, H5Sclose);
    if (!d.ok() || !sp.ok() || static_cast<size_t>(H5Sget_simple_extent_npoints(sp.get())) != n ||
        (n > 0 && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0))
      throw InputError(what + ": " + last + "/" + name + " is missing or not of this mesh (" +
                       std::to_string(mesh.num_nodes()) + " nodes, " + std::to_string(mesh.num_ifaces()) +
                       " interfaces): give the snapshots.h5 of a run of the same case and --set options");
    return v;
  };
  fr.x = read("coordinates", static_cast<size_t>(mesh.num_nodes()) * 3);
  fr.damage = read("damage", static_cast<size_t>(mesh.num_ifaces()));
  return fr;
}

// What `fdem run` under mpirun would hold and send with this partition (parallel/decompose.hpp):
// per part its elements with the ghosts, its ghost nodes, the bytes it sends per step (dim doubles
// per node) and its neighbours; and the ghost nodes a part needs for its interfaces and for the
// elements at its own nodes, against those it holds (the rest come with the ghost elements' bulk
// forces, which no own node needs where every node has one element).
nlohmann::json decomposition_json(const HostMesh& mesh, const std::vector<int>& part, int parts) {
  const std::vector<SubMesh> subs = decompose(mesh, part, parts);
  const int D = mesh.dim;
  std::vector<long> local, ghosts, sent, nbrs, needed;
  for (const SubMesh& sm : subs) {
    const HostMesh& m = sm.mesh;
    local.push_back(m.num_elems());
    ghosts.push_back(sm.ghost_nodes());
    long bytes = 0;
    for (const auto& l : sm.send) bytes += static_cast<long>(l.size()) * D * static_cast<long>(sizeof(double));
    sent.push_back(bytes);
    nbrs.push_back(static_cast<long>(sm.neighbours.size()));
    std::vector<char> need(m.num_nodes(), 0);
    for (int n : m.ifaces) need[n] = 1;
    for (int e = 0; e < m.num_elems(); ++e) {
      bool own = false;
      for (int a = 0; a <= D; ++a) own = own || m.elems[(D + 1) * e + a] < m.owned_nodes;
      if (own)
        for (int a = 0; a <= D; ++a) need[m.elems[(D + 1) * e + a]] = 1;
    }
    long k = 0;
    for (int n = m.owned_nodes; n < m.num_nodes(); ++n) k += need[n];
    needed.push_back(k);
  }
  auto total = [](const std::vector<long>& v) { return std::accumulate(v.begin(), v.end(), 0L); };
  auto most = [](const std::vector<long>& v) { return v.empty() ? 0L : *std::max_element(v.begin(), v.end()); };
  return {{"local_elements_per_part", local},   {"ghost_nodes_per_part", ghosts},
          {"send_bytes_per_step_per_part", sent}, {"neighbours_per_part", nbrs},
          {"send_bytes_per_step", total(sent)},  {"send_bytes_per_step_most", most(sent)},
          {"neighbours_most", most(nbrs)},       {"ghost_nodes", total(ghosts)},
          {"ghost_nodes_needed", total(needed)}};
}

}  // namespace

nlohmann::json partition_case(const std::string& case_path, const std::vector<std::string>& overrides,
                              int parts, const std::string& method_name, const std::string& out_dir,
                              const std::string& snapshot) {
  const PartitionMethod method = parse_partition_method(method_name);  // before the mesh: fails fast
  if (parts < 1)
    throw InputError("--parts " + std::to_string(parts) +
                     " is out of range: give an integer in [1, number of elements]");
  Case c = load_case(case_path, overrides);
  const std::string out = out_dir.empty() ? "out/" + c.name : out_dir;
  ensure_output_dir(out);
  const OutputLock lock(out);  // the folder is this command's until it ends (as a run's)
  HostMesh coarse;  // (a refined case's: its partition is the coarse mesh's, as a run's)
  const HostMesh mesh = prepare_mesh(c, &coarse);
  partition_init(method);  // MPI_Init for Zoltan: not part of the partition's time
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<int> part = coarse.num_elems() > 0 ? refined_partition(c, coarse, parts, method)
                                                       : partition_elements(mesh, parts, method);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PartitionStats s = partition_stats(mesh, part, parts);
  s.seconds = seconds;
  nlohmann::json report = {{"case", c.name}, {"dimension", c.dim}, {"method", partition_method_name(method)}};
  report.update(partition_stats_json(s));
  report["decomposition"] = decomposition_json(mesh, part, parts);
  if (!snapshot.empty()) {  // the rebalance at the snapshot's last frame
    const Frame fr = read_last_frame(snapshot, mesh);
    const HostMesh moved = moved_mesh(mesh, fr.x, fr.damage);
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<int> again = partition_elements(moved, parts, method);
    PartitionStats r = partition_stats(moved, again, parts);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    const PartitionStats kept = partition_stats(moved, part, parts);  // no rebalance
    const long migrated = migrated_elements(part, again, parts);
    report["rebalance"] = {{"snapshot", snapshot},
                           {"time", fr.time},
                           {"failed_interfaces", mesh.num_ifaces() - moved.num_ifaces()},
                           {"migrated_elements", migrated},
                           {"migrated_fraction", static_cast<double>(migrated) / mesh.num_elems()},
                           {"kept",
                            {{"interfaces_cut", kept.interfaces_cut},
                             {"ghost_nodes", kept.ghost_nodes},
                             {"imbalance", kept.imbalance}}},
                           {"rebalanced", partition_stats_json(r)}};
  }
  write_file_atomic(out + "/partition.json", report.dump(2) + "\n");
  write_partition_vtk(out + "/partition.vtk", mesh, part);
  report["files"] = {out + "/partition.json", out + "/partition.vtk (cell fields part, region)"};
  return report;
}

}  // namespace fdem
