// The statistics of an element partition (partition.hpp: partition_stats, migrated_elements,
// moved_mesh, the JSON and text reports) and the VTK file that shows it. Split from partition.cpp.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "parallel/partition.hpp"

namespace fdem {

PartitionStats partition_stats(const HostMesh& mesh, const std::vector<int>& part, int parts) {
  PartitionStats s;
  const int ne = mesh.num_elems();
  if (static_cast<int>(part.size()) != ne) throw std::logic_error("partition_stats: one part per element");
  s.parts = parts;
  s.elements = ne;
  s.interfaces = mesh.num_ifaces();
  s.elements_per_part.assign(parts, 0);
  s.load_per_part.assign(parts, 0);
  s.ghosts_per_part.assign(parts, 0);
  const ElementGraph g = element_graph(mesh);
  std::vector<std::pair<int, int>> ghost;  // (part, element of another part next to it)
  for (int e = 0; e < ne; ++e) {
    const int p = part[e];
    ++s.elements_per_part[p];
    s.load_per_part[p] += g.weight[e];
    for (int j = g.xadj[e]; j < g.xadj[e + 1]; ++j) {
      const int o = g.adj[j];
      if (g.kind[j] == 1 && e < o) ++s.shared_faces;
      if (part[o] == p) continue;
      ghost.emplace_back(p, o);
      if (e < o) ++(g.kind[j] == 0 ? s.interfaces_cut : s.shared_faces_cut);
    }
  }
  s.ghost_nodes_per_part.assign(parts, 0);
  std::vector<std::pair<int, int>> gnodes;  // (part, node of the other side of a cut interface)
  const int d = mesh.dim;
  for (int i = 0; i < mesh.num_ifaces(); ++i) {
    const int a = mesh.iface_elems[2 * static_cast<size_t>(i)],
              b = mesh.iface_elems[2 * static_cast<size_t>(i) + 1];
    if (a < 0 || b < 0 || a >= ne || b >= ne || part[a] == part[b]) continue;
    for (int k = 0; k < d; ++k) {
      gnodes.emplace_back(part[a], mesh.ifaces[2 * d * static_cast<size_t>(i) + d + k]);
      gnodes.emplace_back(part[b], mesh.ifaces[2 * d * static_cast<size_t>(i) + k]);
    }
  }
  s.work_per_part = s.load_per_part;
  for (int i = 0; i < mesh.num_ifaces(); ++i) {
    const int a = mesh.iface_elems[2 * static_cast<size_t>(i)],
              b = mesh.iface_elems[2 * static_cast<size_t>(i) + 1];
    if (a >= 0 && b >= 0 && a < ne && b < ne && part[a] != part[b]) ++s.work_per_part[part[b]];
  }
  std::sort(gnodes.begin(), gnodes.end());
  gnodes.erase(std::unique(gnodes.begin(), gnodes.end()), gnodes.end());
  for (const auto& pn : gnodes) ++s.ghost_nodes_per_part[pn.first];
  s.ghost_nodes = static_cast<long>(gnodes.size());
  std::sort(ghost.begin(), ghost.end());
  ghost.erase(std::unique(ghost.begin(), ghost.end()), ghost.end());
  for (const auto& pe : ghost) ++s.ghosts_per_part[pe.first];
  s.ghosts = static_cast<long>(ghost.size());
  auto imbalance = [parts](const std::vector<long>& v) {
    const double total = static_cast<double>(std::accumulate(v.begin(), v.end(), 0L));
    return total > 0 ? *std::max_element(v.begin(), v.end()) * parts / total - 1 : 0.0;
  };
  s.imbalance = imbalance(s.load_per_part);
  s.element_imbalance = imbalance(s.elements_per_part);
  // the work's imbalance against the mean load without duplicates (what a perfect split would reach)
  const double mean_load =
      static_cast<double>(std::accumulate(s.load_per_part.begin(), s.load_per_part.end(), 0L)) / parts;
  s.work_imbalance =
      mean_load > 0 ? *std::max_element(s.work_per_part.begin(), s.work_per_part.end()) / mean_load - 1 : 0;
  return s;
}

long migrated_elements(const std::vector<int>& before, const std::vector<int>& after, int parts) {
  if (before.size() != after.size())
    throw std::logic_error("migrated_elements: partitions of different meshes");
  std::vector<long> overlap(static_cast<size_t>(parts) * parts, 0);  // [after][before]
  for (size_t e = 0; e < before.size(); ++e) ++overlap[static_cast<size_t>(after[e]) * parts + before[e]];
  std::vector<size_t> order(overlap.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return overlap[a] > overlap[b]; });
  std::vector<int> rename(parts, -1);
  std::vector<bool> taken(parts, false);
  for (size_t k : order) {
    const int a = static_cast<int>(k / parts), b = static_cast<int>(k % parts);
    if (rename[a] < 0 && !taken[b]) {
      rename[a] = b;
      taken[b] = true;
    }
  }
  long moved = 0;
  for (size_t e = 0; e < before.size(); ++e) moved += rename[after[e]] != before[e];
  return moved;
}

HostMesh moved_mesh(const HostMesh& mesh, const std::vector<double>& x, const std::vector<double>& damage) {
  HostMesh m = mesh;
  const int nn = mesh.num_nodes(), d = mesh.dim;
  if (x.size() != static_cast<size_t>(nn) * 3 || damage.size() != static_cast<size_t>(mesh.num_ifaces()))
    throw std::logic_error("moved_mesh: positions or damage of another mesh");
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < d; ++k) m.X[static_cast<size_t>(n) * d + k] = x[3 * static_cast<size_t>(n) + k];
  m.ifaces.clear();
  m.iface_elems.clear();
  for (int i = 0; i < mesh.num_ifaces(); ++i) {
    if (damage[i] >= 1) continue;
    m.ifaces.insert(m.ifaces.end(), mesh.ifaces.begin() + 2 * d * static_cast<size_t>(i),
                    mesh.ifaces.begin() + 2 * d * static_cast<size_t>(i + 1));
    m.iface_elems.push_back(mesh.iface_elems[2 * static_cast<size_t>(i)]);
    m.iface_elems.push_back(mesh.iface_elems[2 * static_cast<size_t>(i) + 1]);
  }
  m.iface_sets.clear();
  return m;
}

nlohmann::json partition_stats_json(const PartitionStats& s) {
  return {{"parts", s.parts},
          {"elements", s.elements},
          {"interfaces", s.interfaces},
          {"shared_faces", s.shared_faces},
          {"imbalance", s.imbalance},
          {"element_imbalance", s.element_imbalance},
          {"work_imbalance", s.work_imbalance},
          {"interfaces_cut", s.interfaces_cut},
          {"shared_faces_cut", s.shared_faces_cut},
          {"ghosts", s.ghosts},
          {"ghost_nodes", s.ghost_nodes},
          {"seconds", s.seconds},
          {"elements_per_part", s.elements_per_part},
          {"load_per_part", s.load_per_part},
          {"ghosts_per_part", s.ghosts_per_part},
          {"ghost_nodes_per_part", s.ghost_nodes_per_part},
          {"work_per_part", s.work_per_part}};
}

std::string partition_report_text(const nlohmann::json& r) {
  std::string t;
  char buf[256];
  std::snprintf(buf, sizeof buf, "partition of %s (%dD): %ld elements, %ld interfaces, %ld shared faces\n",
                r.value("case", "").c_str(), r.value("dimension", 0), r.value("elements", 0L),
                r.value("interfaces", 0L), r.value("shared_faces", 0L));
  t += buf;
  std::snprintf(buf, sizeof buf, "method %s, %d parts, partition time %.4f s\n",
                r.value("method", "").c_str(), r.value("parts", 0), r.value("seconds", 0.0));
  t += buf;
  const long ni = r.value("interfaces", 0L);
  std::snprintf(
      buf, sizeof buf,
      "load imbalance (max/mean - 1 of elements + side-A interfaces) %.2f %%, of elements %.2f %%\n"
      "interfaces cut %ld (%.2f %% of all), shared faces cut %ld, ghost elements %ld, ghost nodes %ld\n",
      100 * r.value("imbalance", 0.0), 100 * r.value("element_imbalance", 0.0), r.value("interfaces_cut", 0L),
      ni ? 100.0 * r.value("interfaces_cut", 0L) / ni : 0.0, r.value("shared_faces_cut", 0L),
      r.value("ghosts", 0L), r.value("ghost_nodes", 0L));
  t += buf;
  if (r.contains("decomposition")) {  // partition_case: what a run over processes holds and sends
    const auto& d = r["decomposition"];
    std::snprintf(buf, sizeof buf,
                  "run over %d processes: ghost nodes %ld (%ld needed by interfaces and own nodes' elements), "
                  "bytes sent per step %ld, at most %ld by one process, at most %ld neighbours\n",
                  r.value("parts", 0), d.value("ghost_nodes", 0L), d.value("ghost_nodes_needed", 0L),
                  d.value("send_bytes_per_step", 0L), d.value("send_bytes_per_step_most", 0L),
                  d.value("neighbours_most", 0L));
    t += buf;
  }
  t += "  part  elements      load    ghosts  ghost nodes\n";
  const auto &el = r["elements_per_part"], &ld = r["load_per_part"], &gh = r["ghosts_per_part"],
             &gn = r["ghost_nodes_per_part"];
  for (size_t p = 0; p < el.size(); ++p) {
    std::snprintf(buf, sizeof buf, "%6zu %9ld %9ld %9ld %12ld\n", p, el[p].get<long>(), ld[p].get<long>(),
                  gh[p].get<long>(), gn[p].get<long>());
    t += buf;
  }
  return t;
}

namespace {

template <class T>
void put_be(std::ofstream& o, T v) {  // legacy VTK binary data are big-endian
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  std::reverse(b, b + sizeof(T));
  o.write(reinterpret_cast<const char*>(b), sizeof(T));
}

}  // namespace

void write_partition_vtk(const std::string& path, const HostMesh& m, const std::vector<int>& part) {
  std::ofstream o(path, std::ios::binary);
  if (!o) throw InputError(path + ": cannot write the partition file");
  const int nn = m.num_nodes(), ne = m.num_elems(), k = m.nodes_per_elem();
  o << "# vtk DataFile Version 3.0\nfdem partition\nBINARY\nDATASET UNSTRUCTURED_GRID\n";
  o << "POINTS " << nn << " double\n";
  for (int n = 0; n < nn; ++n)
    for (int d = 0; d < 3; ++d) put_be<double>(o, d < m.dim ? m.X[static_cast<size_t>(n) * m.dim + d] : 0.0);
  o << "\nCELLS " << ne << " " << static_cast<long>(ne) * (k + 1) << "\n";
  for (int e = 0; e < ne; ++e) {
    put_be<int32_t>(o, k);
    for (int a = 0; a < k; ++a) put_be<int32_t>(o, m.elems[static_cast<size_t>(e) * k + a]);
  }
  o << "\nCELL_TYPES " << ne << "\n";
  for (int e = 0; e < ne; ++e) put_be<int32_t>(o, m.dim == 2 ? 5 : 10);  // VTK_TRIANGLE, VTK_TETRA
  o << "\nCELL_DATA " << ne << "\nSCALARS part int 1\nLOOKUP_TABLE default\n";
  for (int e = 0; e < ne; ++e) put_be<int32_t>(o, part[e]);
  o << "\nSCALARS region int 1\nLOOKUP_TABLE default\n";
  for (int e = 0; e < ne; ++e) put_be<int32_t>(o, m.elem_region.empty() ? 0 : m.elem_region[e]);
  o << "\n";
  if (!o) throw InputError(path + ": writing the partition file failed");
}

}  // namespace fdem
