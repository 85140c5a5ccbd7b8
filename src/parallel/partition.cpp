// Element partitions (partition.hpp): the element graph, METIS and two plain baselines, the
// statistics of a partition, and a VTK file that shows it.
#include "parallel/partition.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <numeric>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"  // face_node, sort_face_key, centroid

#ifdef FDEM_HAVE_METIS
#include <metis.h>
#endif
#ifdef FDEM_HAVE_ZOLTAN
#include "parallel/partition_zoltan.hpp"
#endif

namespace fdem {

namespace {
const char* const kNoMetis =
    "--method metis: this fdem was built without METIS (install libmetis-dev and configure again; "
    "allowed here: rcb, block)";
const char* const kNoZoltan =
    ": this fdem was built without Zoltan (configure with -DFDEM_ENABLE_MPI=ON, docs/parallel.md; "
    "allowed here: metis, rcb, block)";
}  // namespace

PartitionMethod parse_partition_method(const std::string& name) {
  if (name == "metis") {
    if (!partition_has_metis()) throw InputError(kNoMetis);
    return PartitionMethod::Metis;
  }
  if (name == "rcb") return PartitionMethod::Rcb;
  if (name == "block") return PartitionMethod::Block;
  for (auto m : {PartitionMethod::ZoltanRcb, PartitionMethod::ZoltanRib, PartitionMethod::ZoltanHsfc})
    if (name == partition_method_name(m)) {
      if (!partition_has_zoltan()) throw InputError("--method " + name + kNoZoltan);
      return m;
    }
  throw InputError("--method '" + name + "' is not a partition method (allowed: metis, rcb, block; " +
                   "zoltan-rcb, zoltan-rib, zoltan-hsfc in a build with -DFDEM_ENABLE_MPI=ON)");
}

const char* partition_method_name(PartitionMethod m) {
  switch (m) {
    case PartitionMethod::Metis:
      return "metis";
    case PartitionMethod::Rcb:
      return "rcb";
    case PartitionMethod::Block:
      return "block";
    case PartitionMethod::ZoltanRcb:
      return "zoltan-rcb";
    case PartitionMethod::ZoltanRib:
      return "zoltan-rib";
    case PartitionMethod::ZoltanHsfc:
      return "zoltan-hsfc";
  }
  return "?";
}

bool partition_has_metis() {
#ifdef FDEM_HAVE_METIS
  return true;
#else
  return false;
#endif
}

bool partition_has_zoltan() {
#ifdef FDEM_HAVE_ZOLTAN
  return true;
#else
  return false;
#endif
}

namespace {

std::vector<std::array<double, 3>> centroids(const HostMesh& m) {
  std::vector<std::array<double, 3>> c(m.num_elems());
  for (int e = 0; e < m.num_elems(); ++e) c[e] = mesh_detail::centroid(m, e);
  return c;
}

#ifdef FDEM_HAVE_ZOLTAN
// The centroids as Zoltan takes them: dim coordinates per element, one after the other.
std::vector<double> centroid_coords(const HostMesh& m) {
  const auto c = centroids(m);
  std::vector<double> xyz(c.size() * static_cast<size_t>(m.dim));
  for (size_t e = 0; e < c.size(); ++e)
    for (int d = 0; d < m.dim; ++d) xyz[e * m.dim + d] = c[e][d];
  return xyz;
}
#endif

// Recursive coordinate bisection (a baseline): split the elements at the weighted median of their
// centroids along the longest side of their bounding box, in proportion to the parts on each side.
void rcb(const std::vector<std::array<double, 3>>& c, const std::vector<double>& w, int dim, int* first,
         int* last, int part0, int nparts, std::vector<int>& part) {
  if (nparts == 1) {
    for (int* p = first; p != last; ++p) part[*p] = part0;
    return;
  }
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (int* p = first; p != last; ++p)
    for (int d = 0; d < dim; ++d) {
      lo[d] = std::min(lo[d], c[*p][d]);
      hi[d] = std::max(hi[d], c[*p][d]);
    }
  int axis = 0;
  for (int d = 1; d < dim; ++d)
    if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
  std::sort(first, last,
            [&](int a, int b) { return c[a][axis] != c[b][axis] ? c[a][axis] < c[b][axis] : a < b; });
  const int left = nparts / 2;
  double total = 0;  // (integer weights: exact sums)
  for (int* p = first; p != last; ++p) total += w[*p];
  const double target = total * left / nparts;
  const long n = last - first;
  long cut = 0;
  double acc = 0;
  while (cut < n && acc + 0.5 * w[first[cut]] < target) acc += w[first[cut++]];
  cut = std::max<long>(left, std::min<long>(cut, n - (nparts - left)));  // no part left empty
  rcb(c, w, dim, first, first + cut, part0, left, part);
  rcb(c, w, dim, first + cut, last, part0 + left, nparts - left, part);
}

}  // namespace

ElementGraph element_graph(const HostMesh& m) {
  const int ne = m.num_elems(), ni = m.num_ifaces();
  std::vector<std::pair<int, int>> edges;  // (a, b) with its kind in kinds
  std::vector<unsigned char> kinds;
  ElementGraph g;
  g.weight.assign(ne, 1);
  for (int i = 0; i < ni; ++i) {
    const int a = m.iface_elems[2 * static_cast<size_t>(i)],
              b = m.iface_elems[2 * static_cast<size_t>(i) + 1];
    if (a < 0 || b < 0 || a >= ne || b >= ne || a == b) continue;
    edges.emplace_back(a, b);
    kinds.push_back(0);
    ++g.weight[a];
  }
  // Continuous faces: only nodes used by more than one element can be on one (none in a fully
  // fracturable mesh, where every element owns its nodes).
  std::vector<int> uses(m.num_nodes(), 0);
  for (int n : m.elems) ++uses[n];
  std::vector<std::pair<std::array<int, 3>, int>> faces;
  const int k = m.nodes_per_elem();
  for (int e = 0; e < ne; ++e) {
    for (int j = 0; j < mesh_detail::faces_per_elem(m.dim); ++j) {
      std::array<int, 3> f{-1, -1, -1};
      bool shared = true;
      for (int a = 0; a < m.dim; ++a) {
        f[a] = m.elems[static_cast<size_t>(e) * k + mesh_detail::face_node(m.dim, j, a)];
        shared = shared && uses[f[a]] > 1;
      }
      if (!shared) continue;
      mesh_detail::sort_face_key(f, m.dim);
      faces.emplace_back(f, e);
    }
  }
  std::sort(faces.begin(), faces.end());
  for (size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].first == faces[i + 1].first && faces[i].second != faces[i + 1].second) {
      edges.emplace_back(faces[i].second, faces[i + 1].second);
      kinds.push_back(1);
      ++i;
    }
  g.xadj.assign(ne + 1, 0);
  for (const auto& [a, b] : edges) {
    ++g.xadj[a + 1];
    ++g.xadj[b + 1];
  }
  for (int e = 0; e < ne; ++e) g.xadj[e + 1] += g.xadj[e];
  g.adj.resize(g.xadj[ne]);
  g.kind.resize(g.xadj[ne]);
  std::vector<int> fill(g.xadj.begin(), g.xadj.end() - 1);
  for (size_t i = 0; i < edges.size(); ++i) {
    const auto [a, b] = edges[i];
    g.adj[fill[a]] = b;
    g.kind[fill[a]++] = kinds[i];
    g.adj[fill[b]] = a;
    g.kind[fill[b]++] = kinds[i];
  }
  return g;
}

#ifdef FDEM_HAVE_METIS
// METIS_PartGraphKway on the element graph with vertex weights vwgt (one per element, >= 1).
static std::vector<int> metis_kway(const ElementGraph& g, std::vector<idx_t> vwgt, int parts) {
  const idx_t ne = static_cast<idx_t>(vwgt.size());
  std::vector<idx_t> xadj(g.xadj.begin(), g.xadj.end()), adj(g.adj.begin(), g.adj.end()), out(ne, 0);
  idx_t nv = ne, ncon = 1, np = parts, objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_NUMBERING] = 0;
  options[METIS_OPTION_SEED] = 1;  // fixed: the same partition every time
  // the best of 4 tries (different seeds inside METIS): 0-12 % fewer cut interfaces than one try on
  // the disc and the 3D impact at 2-16 parts, at 2-3 times the time
  options[METIS_OPTION_NCUTS] = 4;
  // load within 1 % of the mean (METIS's default: 3 %): 1-3 % more interfaces cut on the 3D impact
  // meshes at 8 and 64 parts, imbalance 0.3-1.0 % instead of 0.7-3.0 % (docs/parallel.md)
  options[METIS_OPTION_UFACTOR] = 10;
  const int rc = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adj.data(), vwgt.data(), nullptr, nullptr, &np,
                                     nullptr, nullptr, options, &objval, out.data());
  if (rc != METIS_OK)
    throw std::runtime_error("METIS_PartGraphKway failed (status " + std::to_string(rc) + ") for " +
                             std::to_string(ne) + " elements into " + std::to_string(parts) + " parts");
  return std::vector<int>(out.begin(), out.end());
}
#endif

std::vector<int> partition_elements_weighted(const HostMesh& mesh, int parts, const std::vector<double>& work,
                                             bool graph) {
  const int ne = mesh.num_elems();
  if (parts < 1 || parts > ne)
    throw InputError("partition: " + std::to_string(parts) + " parts is out of range: give an integer in [1, " +
                     std::to_string(ne) + "] (at most the number of elements)");
  if (work.size() != static_cast<size_t>(ne))
    throw InputError("partition: " + std::to_string(work.size()) + " element weights for " + std::to_string(ne) +
                     " elements");
  for (double w : work)
    if (!(w > 0) || !std::isfinite(w)) throw InputError("partition: an element weight is not a positive number");
  std::vector<int> part(ne, 0);
  if (parts == 1) return part;
  if (graph) {
#ifdef FDEM_HAVE_METIS
    const double most = *std::max_element(work.begin(), work.end());
    std::vector<idx_t> vwgt(ne);  // integers for METIS: the largest weight 1000, each at least 1
    for (int e = 0; e < ne; ++e)
      vwgt[e] = std::max<idx_t>(1, static_cast<idx_t>(std::lround(1000 * work[e] / most)));
    return metis_kway(element_graph(mesh), std::move(vwgt), parts);
#else
    throw InputError(kNoMetis);
#endif
  }
#ifdef FDEM_HAVE_ZOLTAN
  // Zoltan's RCB (the MPI build, which alone cuts during a run), the largest part within 1 % of the
  // mean work; the baseline below where the build has no Zoltan (docs/parallel.md, "Rebalancing")
  const std::vector<float> weight(work.begin(), work.end());
  return zoltan_partition(mesh.dim, centroid_coords(mesh), weight, parts, "RCB", 1.01);
#else
  std::vector<int> ids(ne);
  std::iota(ids.begin(), ids.end(), 0);
  rcb(centroids(mesh), work, mesh.dim, ids.data(), ids.data() + ne, 0, parts, part);
  return part;
#endif
}

void partition_init(PartitionMethod method) {
#ifdef FDEM_HAVE_ZOLTAN
  if (method == PartitionMethod::ZoltanRcb || method == PartitionMethod::ZoltanRib ||
      method == PartitionMethod::ZoltanHsfc)
    zoltan_init();
#else
  (void)method;
#endif
}

std::vector<int> partition_elements(const HostMesh& mesh, int parts, PartitionMethod method) {
  const int ne = mesh.num_elems();
  if (parts < 1 || parts > ne)
    throw InputError("--parts " + std::to_string(parts) + " is out of range: give an integer in [1, " +
                     std::to_string(ne) + "] (at most the number of elements)");
  std::vector<int> part(ne, 0);
  if (parts == 1) return part;
  if (method == PartitionMethod::Metis) {
#ifdef FDEM_HAVE_METIS
    const ElementGraph g = element_graph(mesh);
    part = metis_kway(g, std::vector<idx_t>(g.weight.begin(), g.weight.end()), parts);
#else
    throw InputError(kNoMetis);
#endif
  } else {
    std::vector<int> w(ne, 1);
    for (int i = 0; i < mesh.num_ifaces(); ++i) {
      const int a = mesh.iface_elems[2 * static_cast<size_t>(i)];
      if (a >= 0 && a < ne) ++w[a];
    }
    if (method == PartitionMethod::ZoltanRcb || method == PartitionMethod::ZoltanRib ||
        method == PartitionMethod::ZoltanHsfc) {
#ifdef FDEM_HAVE_ZOLTAN
      const std::vector<double> xyz = centroid_coords(mesh);
      const char* lb = method == PartitionMethod::ZoltanRcb   ? "RCB"
                       : method == PartitionMethod::ZoltanRib ? "RIB"
                                                              : "HSFC";
      part = zoltan_partition(mesh.dim, xyz, std::vector<float>(w.begin(), w.end()), parts, lb);
#else
      throw InputError(std::string("--method ") + partition_method_name(method) + kNoZoltan);
#endif
    } else if (method == PartitionMethod::Rcb) {
      std::vector<int> ids(ne);
      std::iota(ids.begin(), ids.end(), 0);
      rcb(centroids(mesh), std::vector<double>(w.begin(), w.end()), mesh.dim, ids.data(), ids.data() + ne, 0,
          parts, part);
    } else {  // Block: contiguous index ranges of equal weight
      const long total = std::accumulate(w.begin(), w.end(), 0L);
      long acc = 0;
      for (int e = 0; e < ne; ++e) {
        part[e] = static_cast<int>(std::min<long>(parts - 1, (2 * acc + w[e]) * parts / (2 * total)));
        acc += w[e];
      }
    }
  }
  return part;
}

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
