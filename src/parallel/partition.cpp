// Element partitions (partition.hpp): the element graph, METIS, Zoltan and two plain baselines,
// and the weighted cut during a run. Their statistics and the VTK file: partition_stats.cpp.
#include "parallel/partition.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"  // face_node, sort_face_key, centroid
#include "mesh/refine.hpp"

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
// adjwgt: one weight per adjacency entry (empty: none).
static std::vector<int> metis_kway(const ElementGraph& g, std::vector<idx_t> vwgt, int parts,
                                   std::vector<idx_t> adjwgt = {}) {
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
  const int rc = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adj.data(), vwgt.data(), nullptr,
                                     adjwgt.empty() ? nullptr : adjwgt.data(), &np,
                                     nullptr, nullptr, options, &objval, out.data());
  if (rc != METIS_OK)
    throw std::runtime_error("METIS_PartGraphKway failed (status " + std::to_string(rc) + ") for " +
                             std::to_string(ne) + " elements into " + std::to_string(parts) + " parts");
  return std::vector<int>(out.begin(), out.end());
}

// METIS on the graph of groups of `group` consecutive elements (a refined mesh's children of one
// coarse element): a group's weight is its elements', an edge's the element pairs it joins.
static std::vector<int> metis_groups(const ElementGraph& g, int group, int parts) {
  const int ne = static_cast<int>(g.weight.size()), ng = ne / group;
  ElementGraph q;
  std::vector<idx_t> vwgt(ng, 0), adjwgt;
  q.xadj.assign(1, 0);
  std::vector<int> slot(ng, -1);  // this group's entry of each neighbour group
  for (int G = 0; G < ng; ++G) {
    const int first = static_cast<int>(q.adj.size());
    for (int e = G * group; e < (G + 1) * group; ++e) {
      vwgt[G] += g.weight[e];
      for (int j = g.xadj[e]; j < g.xadj[e + 1]; ++j) {
        const int H = g.adj[j] / group;
        if (H == G) continue;
        if (slot[H] < first) {
          slot[H] = static_cast<int>(q.adj.size());
          q.adj.push_back(H);
          adjwgt.push_back(0);
        }
        ++adjwgt[slot[H]];
      }
    }
    q.xadj.push_back(static_cast<int>(q.adj.size()));
  }
  const std::vector<int> gpart = metis_kway(q, std::move(vwgt), parts, std::move(adjwgt));
  std::vector<int> part(ne);
  for (int e = 0; e < ne; ++e) part[e] = gpart[e / group];
  return part;
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

// The parts of the methods other than METIS: the elements' centroids cut with the weights w
// (Zoltan's RCB, RIB or HSFC; the baseline RCB), or contiguous index ranges of equal weight (Block).
static std::vector<int> geometric_parts(const HostMesh& mesh, const std::vector<int>& w, int parts,
                                        PartitionMethod method) {
  const int ne = mesh.num_elems();
  std::vector<int> part(ne, 0);
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
    rcb(centroids(mesh), std::vector<double>(w.begin(), w.end()), mesh.dim, ids.data(), ids.data() + ne, 0, parts,
        part);
  } else {  // Block: contiguous index ranges of equal weight
    const long total = std::accumulate(w.begin(), w.end(), 0L);
    long acc = 0;
    for (int e = 0; e < ne; ++e) {
      part[e] = static_cast<int>(std::min<long>(parts - 1, (2 * acc + w[e]) * parts / (2 * total)));
      acc += w[e];
    }
  }
  return part;
}

std::vector<int> partition_elements(const HostMesh& mesh, int parts, PartitionMethod method, int group) {
  const int ne = mesh.num_elems();
  if (parts < 1 || parts > ne)
    throw InputError("--parts " + std::to_string(parts) + " is out of range: give an integer in [1, " +
                     std::to_string(ne) + "] (at most the number of elements)");
  std::vector<int> part(ne, 0);
  if (parts == 1) return part;
  if (method == PartitionMethod::Metis) {
#ifdef FDEM_HAVE_METIS
    const ElementGraph g = element_graph(mesh);
    // groups (a refined mesh): the coarse graph, where each part still gets at least 8 groups
    if (group > 1 && ne % group == 0 && ne / group >= 8 * parts)
      part = metis_groups(g, group, parts);
    else
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
    part = geometric_parts(mesh, w, parts, method);
  }
  return part;
}

std::vector<int> partition_coarse(const HostMesh& coarse, const CoarseTopology& topo,
                                  const std::vector<std::int64_t>& iface_offsets, int parts, PartitionMethod method) {
  const int ne = coarse.num_elems(), npe = coarse.dim + 1;
  if (parts < 1 || parts > ne)
    throw InputError("--parts " + std::to_string(parts) + " is out of range for a refined mesh: give an integer in [1, " +
                     std::to_string(ne) + "] (at most the coarse mesh's elements, which mesh.refine splits)");
  if (iface_offsets.size() != static_cast<size_t>(ne) + 1)
    throw InputError("partition: " + std::to_string(iface_offsets.size()) + " interface offsets for " +
                     std::to_string(ne) + " coarse elements");
  std::vector<int> part(ne, 0);
  if (parts == 1) return part;
  const int children = static_cast<int>(refine_factor(coarse.dim, topo.levels) + 0.5);
  std::vector<int> w(ne);  // the children and the interfaces whose side A they are
  for (int e = 0; e < ne; ++e) w[e] = children + static_cast<int>(iface_offsets[e + 1] - iface_offsets[e]);
  if (method != PartitionMethod::Metis) return geometric_parts(coarse, w, parts, method);
#ifdef FDEM_HAVE_METIS
  const int per_facet = coarse.dim == 2 ? topo.m : topo.m * topo.m;  // fine interfaces on a coarse facet
  ElementGraph q;
  q.xadj.assign(1, 0);
  std::vector<idx_t> adjwgt;
  for (int e = 0; e < ne; ++e) {
    std::vector<int> nb;
    for (int a = 0; a < npe; ++a)
      if (const int o = topo.elem_neighbours[static_cast<size_t>(e) * npe + a]; o >= 0) nb.push_back(o);
    std::sort(nb.begin(), nb.end());
    for (int o : nb) {
      q.adj.push_back(o);
      adjwgt.push_back(per_facet);
    }
    q.xadj.push_back(static_cast<int>(q.adj.size()));
  }
  return metis_kway(q, std::vector<idx_t>(w.begin(), w.end()), parts, std::move(adjwgt));
#else
  throw InputError(kNoMetis);
#endif
}

}  // namespace fdem
