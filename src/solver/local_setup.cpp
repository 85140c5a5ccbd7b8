// local_setup (local_setup.hpp) and its phases: the coarse mesh and its partition shared, the
// whole mesh's sizes from each process's own refinement, the part built, the node sets' sizes and
// the exchange lists from the processes, the whole mesh's facts summed; and the whole mesh gathered
// on process 0 when a cut or the serial snapshots need it (gather_whole_mesh).
#include "solver/local_setup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "common/union_find.hpp"
#include "mesh/refine.hpp"
#include "parallel/comm.hpp"
#include "parallel/local_part.hpp"
#include "solver/contact_system.hpp"
#include "solver/interface_materials.hpp"
#include "solver/run_setup.hpp"
#include "solver/summary.hpp"

namespace fdem {

namespace {

// What every process knows of the coarse mesh.
struct Basis {
  HostMesh coarse;
  CoarseTopology topo;
  std::vector<std::int64_t> off;  // refined_interface_offsets
  std::vector<int> cpart;         // each coarse element's part
  int children = 1;
};

std::vector<char> int_bytes(const std::vector<int>& v) {
  std::vector<char> b(v.size() * sizeof(int));
  if (!v.empty()) std::memcpy(b.data(), v.data(), b.size());
  return b;
}
std::vector<int> bytes_ints(const std::vector<char>& b) {
  std::vector<int> v(b.size() / sizeof(int));
  if (!v.empty()) std::memcpy(v.data(), b.data(), v.size() * sizeof(int));
  return v;
}

// 1. Process 0's coarse mesh and its partition to every process; each derives the topology.
Basis share_coarse(const Case& c, const Comm& comm, const HostMesh& coarse, PartitionMethod method) {
  Basis b;
  std::vector<char> bytes;
  if (comm.rank() == 0) bytes = pack_mesh(coarse);
  comm.broadcast_bytes(bytes);
  b.coarse = comm.rank() == 0 ? coarse : unpack_mesh(bytes);
  b.topo = coarse_topology(b.coarse, c.mesh.refine, curved_surfaces(c.mesh, c.dim));
  b.off = refined_interface_offsets(b.coarse, b.topo);
  b.children = static_cast<int>(refine_factor(c.dim, c.mesh.refine) + 0.5);
  // (process 0 partitions: a partitioner need not give every process the same bits)
  if (comm.rank() == 0) bytes = int_bytes(partition_coarse(b.coarse, b.topo, b.off, comm.size(), method));
  comm.broadcast_bytes(bytes);
  b.cpart = bytes_ints(bytes);
  std::vector<long> per(comm.size(), 0);
  for (int p : b.cpart) ++per[p];
  for (int p = 0; p < comm.size(); ++p)
    if (per[p] == 0)
      throw InputError(c.file + ": the partition of the coarse mesh's " + std::to_string(b.cpart.size()) +
                       " elements leaves process " + std::to_string(p) + " of " + std::to_string(comm.size()) +
                       " without an element: run it on fewer processes (mpirun -n), or with a finer coarse mesh");
  return b;
}

// The connected pieces of the whole refined mesh with interfaces everywhere: its coarse elements
// joined across their facets (elements that touch at an edge or a vertex only share no fine
// interface).
int facet_pieces(const Basis& b) {
  const int ne = b.coarse.num_elems(), npe = b.coarse.dim + 1;
  UnionFind u(ne);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a)
      if (const int o = b.topo.elem_neighbours[static_cast<size_t>(e) * npe + a]; o >= 0) u.join(e, o);
  int pieces = 0;
  for (int e = 0; e < ne; ++e) pieces += u.find(e) == e;
  return pieces;
}

// The rotation of mesh.rotation about the whole refined mesh's centre, which the processes find
// together (the box of the coarse nodes and of every process's new nodes), as a transform of a
// neighbourhood; none without a rotation. widen: each coarse element's largest box diagonal (the
// contact zones' boxes are the rotated elements').
LocalHooks rotation_hooks(const Case& c, const Comm& comm, const Basis& b, const HostMesh& own) {
  LocalHooks h;
  if (c.mesh.rotation_deg == 0) return h;
  MeshSpec spec = c.mesh;
  spec.jitter = 0;
  const int D = c.dim;
  if (!spec.has_rotation_center) {
    std::vector<double> v(6, std::numeric_limits<double>::infinity());  // lo, -hi
    for (const HostMesh* m : {&b.coarse, &own})
      for (int n = 0; n < m->num_nodes(); ++n)
        for (int k = 0; k < D; ++k) {
          v[k] = std::min(v[k], m->X[static_cast<size_t>(n) * D + k]);
          v[3 + k] = std::min(v[3 + k], -m->X[static_cast<size_t>(n) * D + k]);
        }
    comm.min(v.data(), 6);
    for (int k = 0; k < 3; ++k) spec.rotation_center[k] = k < D ? 0.5 * (v[k] + -v[3 + k]) : 0.0;
    spec.has_rotation_center = true;
  }
  h.refined = [spec](HostMesh& m) { transform_mesh(m, spec); };
  const int npe = D + 1;
  for (int e = 0; e < b.coarse.num_elems(); ++e) {
    double d2 = 0;
    for (int k = 0; k < D; ++k) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int a = 0; a < npe; ++a) {
        const double x = b.coarse.X[static_cast<size_t>(b.coarse.elems[static_cast<size_t>(e) * npe + a]) * D + k];
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
      d2 += (hi - lo) * (hi - lo);
    }
    h.widen = std::max(h.widen, std::sqrt(d2));
  }
  return h;
}

// 2. The whole refined mesh's mean and smallest element size (mean_element_size, mesh_quality's
// min_size) from every process's refinement of its own coarse elements: each sends its coarse
// elements' edge sums to process 0, which adds them in coarse order.
void whole_sizes(const Comm& comm, const Basis& b, const HostMesh& own, const std::vector<int>& own_elems,
                 double& mean, double& min) {
  const std::vector<double> sums = coarse_edge_sums(own, b.children);
  std::vector<double> mine, all;
  for (size_t i = 0; i < own_elems.size(); ++i) {
    mine.push_back(own_elems[i]);
    mine.push_back(sums[i]);
  }
  comm.gather(mine, all);
  mean = std::numeric_limits<double>::infinity();
  if (comm.rank() == 0) {
    std::vector<double> S(b.coarse.num_elems(), 0.0);
    for (size_t j = 0; j + 1 < all.size(); j += 2) S[static_cast<size_t>(all[j])] = all[j + 1];
    mean = mean_size_from_sums(S, static_cast<long>(b.coarse.num_elems()) * b.children, own.dim);
  }
  comm.min(&mean, 1);  // process 0's
  min = mesh_sizes(own).min_size;
  comm.min(&min, 1);
}

// The whole node sets' sizes: every node is one process's own.
void whole_set_sizes(const Comm& comm, SubMesh& s) {
  std::vector<double> n;
  for (const auto& [name, set] : s.mesh.node_sets) n.push_back(static_cast<double>(set.size()));
  comm.sum(n.data(), static_cast<int>(n.size()));
  size_t k = 0;
  for (const auto& [name, set] : s.mesh.node_sets) s.mesh.whole_set_size[name] = static_cast<long>(n[k++]);
}

// 3. The send lists: every process's requests (the global ids of the ghosts it receives from each
// neighbour) through process 0 to their owners (lists_from_requests).
void complete_from_requests(const Comm& comm, SubMesh& s) {
  const std::vector<std::vector<std::int64_t>> req = ghost_requests(s);
  std::vector<double> mine{static_cast<double>(comm.rank()), static_cast<double>(s.neighbours.size())}, all;
  for (size_t k = 0; k < req.size(); ++k) {
    mine.push_back(s.neighbours[k]);
    mine.push_back(static_cast<double>(req[k].size()));
    for (std::int64_t g : req[k]) mine.push_back(static_cast<double>(g));
  }
  mine.insert(mine.begin(), static_cast<double>(mine.size()));  // (the blocks' lengths: one pass)
  comm.gather(mine, all);
  std::vector<std::vector<double>> inbox(comm.rank() == 0 ? comm.size() : 0);  // (from, count, ids)...
  for (size_t j = 0; j < all.size();) {
    const size_t len = static_cast<size_t>(all[j]);
    const double from = all[j + 1];
    size_t at = j + 3;
    for (int k = 0; k < static_cast<int>(all[j + 2]); ++k) {
      const int to = static_cast<int>(all[at]);
      const size_t n = static_cast<size_t>(all[at + 1]);
      std::vector<double>& box = inbox[to];
      box.push_back(from);
      box.push_back(static_cast<double>(n));
      box.insert(box.end(), all.begin() + at + 2, all.begin() + at + 2 + n);
      at += 2 + n;
    }
    j += 1 + len;
  }
  std::vector<std::vector<char>> out(inbox.size());
  for (size_t r = 0; r < inbox.size(); ++r) {
    out[r].resize(inbox[r].size() * sizeof(double));
    if (!inbox[r].empty()) std::memcpy(out[r].data(), inbox[r].data(), out[r].size());
  }
  std::vector<char> got;
  comm.scatter_bytes(out, got);
  std::vector<double> box(got.size() / sizeof(double));
  if (!box.empty()) std::memcpy(box.data(), got.data(), box.size() * sizeof(double));
  std::vector<int> from;  // (ascending: process 0 gathered the requests in process order)
  std::vector<std::vector<std::int64_t>> asked;
  for (size_t j = 0; j < box.size();) {
    from.push_back(static_cast<int>(box[j]));
    const size_t n = static_cast<size_t>(box[j + 1]);
    asked.emplace_back();
    for (size_t i = 0; i < n; ++i) asked.back().push_back(static_cast<std::int64_t>(box[j + 2 + i]));
    j += 2 + n;
  }
  complete_lists(s, lists_from_requests(s, from, asked));
}

}  // namespace

MeshHash own_rows_hash(const SubMesh& s) {
  const HostMesh& m = s.mesh;
  const int D = m.dim, npe = D + 1;
  MeshHash h;
  std::vector<int> row(static_cast<size_t>(2 * D));
  for (int n = 0; n < m.owned_nodes; ++n) h.node(s.node_global[n], &m.X[static_cast<size_t>(n) * D], D);
  for (int e = 0; e < m.owned_elems; ++e) {
    for (int a = 0; a < npe; ++a) row[a] = s.node_global[m.elems[static_cast<size_t>(e) * npe + a]];
    h.elem(s.elem_global[e], row.data(), npe);
  }
  for (int q = 0; q < m.owned_ifaces; ++q) {
    for (int a = 0; a < 2 * D; ++a) row[a] = s.node_global[m.ifaces[static_cast<size_t>(q) * 2 * D + a]];
    h.iface(s.iface_global[q], row.data(), 2 * D);
  }
  return h;
}

namespace {

// 4. The whole mesh's facts from every process's own rows: the mesh hash (own_rows_hash, added
// over the processes exactly: sum_hashes_over_processes), the mesh report (the quality's minima,
// maxima and edge sums) and the material rules no interface takes.
std::string parts_mesh_hash(const Comm& comm, const SubMesh& s) {
  MeshHash h = own_rows_hash(s);
  const std::vector<uint64_t> all = sum_hashes_over_processes({h.sums[0], h.sums[1], h.sums[2]},
                                                              [&comm](double* v, int n) { comm.sum(v, n); });
  for (int k = 0; k < 3; ++k) h.sums[k] = all[k];
  return h.hex();
}

nlohmann::json parts_mesh_report(const Case& c, const Comm& comm, const SubMesh& s) {
  const HostMesh& m = s.mesh;
  MeshQuality q = mesh_quality(m, m.owned_elems);
  double lows[4] = {q.min_angle_deg, -q.max_aspect, q.min_size, q.min_measure};
  if (m.owned_elems == 0)
    for (double& v : lows) v = std::numeric_limits<double>::infinity();
  comm.min(lows, 4);
  double sums[2] = {q.edge_sum, static_cast<double>(q.edge_count)};
  comm.sum(sums, 2);
  q.min_angle_deg = lows[0];
  q.max_aspect = -lows[1];
  q.min_size = lows[2];
  q.min_measure = lows[3];
  q.edge_sum = sums[0];
  q.edge_count = static_cast<long>(sums[1]);
  q.mean_size = q.edge_count ? q.edge_sum / sums[1] : 0.0;
  const std::vector<long> mine = region_pair_counts(m, m.owned_ifaces);
  std::vector<double> between(mine.begin(), mine.end());
  comm.sum(between.data(), static_cast<int>(between.size()));
  std::vector<std::string> warnings = m.warnings;
  for (std::string& w : unused_material_rules(c, m.region_names, std::vector<long>(between.begin(), between.end()))) {
    if (comm.rank() == 0) std::fprintf(stderr, "fdem: warning: %s\n", w.c_str());
    warnings.push_back(std::move(w));
  }
  return mesh_report(s.whole_nodes, s.whole_elems, s.whole_ifaces, q, m.region_names, warnings, m.bodies);
}

// 5. The whole mesh on process 0 (gather_whole_mesh). One kind of row at a time, each taken into
// the mesh and let go of before the next (process 0's peak memory).
//
// Rows of `width` values per own item (fill(i, row)) gathered into the whole mesh's order; on
// process 0 take(j, row) for every whole item j.
template <class Fill, class Take>
void gather_each(const Comm& comm, size_t own, size_t width, const std::vector<int>& ids, long whole, Fill&& fill,
                 Take&& take) {
  std::vector<double> mine(own * width);
  for (size_t i = 0; i < own; ++i) fill(i, &mine[i * width]);
  const std::vector<double> all = gather_rows(comm, mine.data(), own, width, ids, static_cast<size_t>(whole));
  mine = std::vector<double>{};
  if (comm.rank() == 0)
    for (long j = 0; j < whole; ++j) take(j, &all[static_cast<size_t>(j) * width]);
}

}  // namespace

HostMesh gather_whole_mesh(const Comm& comm, const SubMesh& s) {
  const HostMesh& m = s.mesh;
  const int D = m.dim, npe = D + 1, iw = 2 * D + 2;
  const bool root = comm.rank() == 0;
  HostMesh w;
  if (root) {
    w.X.resize(static_cast<size_t>(s.whole_nodes) * D);
    w.node_origin.resize(static_cast<size_t>(s.whole_nodes));
  }
  gather_each(
      comm, m.owned_nodes, D + 1, s.node_global, s.whole_nodes,
      [&](size_t n, double* r) {
        for (int k = 0; k < D; ++k) r[k] = m.X[n * D + k];
        r[D] = m.node_origin[n];
      },
      [&](long n, const double* r) {
        for (int k = 0; k < D; ++k) w.X[static_cast<size_t>(n) * D + k] = r[k];
        w.node_origin[n] = static_cast<int>(r[D]);
      });
  gather_each(
      comm, m.owned_elems, npe + 1, s.elem_global, s.whole_elems,
      [&](size_t e, double* r) {
        for (int a = 0; a < npe; ++a) r[a] = s.node_global[m.elems[e * npe + a]];
        r[npe] = m.elem_region[e];
      },
      [&](long, const double* r) {
        for (int a = 0; a < npe; ++a) w.elems.push_back(static_cast<int>(r[a]));
        w.elem_region.push_back(static_cast<int>(r[npe]));
      });
  gather_each(
      comm, m.owned_ifaces, iw, s.iface_global, s.whole_ifaces,
      [&](size_t q, double* r) {
        for (int a = 0; a < 2 * D; ++a) r[a] = s.node_global[m.ifaces[q * 2 * D + a]];
        for (int side = 0; side < 2; ++side) r[2 * D + side] = s.elem_global[m.iface_elems[2 * q + side]];
      },
      [&](long, const double* r) {
        for (int a = 0; a < 2 * D; ++a) w.ifaces.push_back(static_cast<int>(r[a]));
        for (int side = 0; side < 2; ++side) w.iface_elems.push_back(static_cast<int>(r[2 * D + side]));
      });
  for (const auto& [name, set] : m.node_sets) {  // (the same names on every process)
    std::vector<double> mine, all;
    for (int n : set) mine.push_back(s.node_global[n]);
    comm.gather(mine, all);
    if (!root) continue;
    std::vector<int>& g = w.node_sets[name];
    for (double v : all) g.push_back(static_cast<int>(v));
    std::sort(g.begin(), g.end());
  }
  if (!root) return HostMesh{};
  w.dim = D;
  w.region_names = m.region_names;
  w.warnings = m.warnings;
  w.bodies = m.bodies;
  return w;
}

std::string local_setup_refusal(const Case& c, const HostMesh& coarse, bool restarting) {
  const char* w = std::getenv("FDEM_WHOLE_SETUP");
  if (w && std::string(w) == "1") return "FDEM_WHOLE_SETUP=1";
  if (c.mesh.refine < 1) return "the mesh is not refined (mesh.refine)";
  if (restarting) return "a restart";
  if (c.mesh.jitter > 0) return "mesh.jitter (drawn over the whole mesh)";
  if (!c.surface_iface_material.empty()) return "interfaces cut along named surfaces (fracture.surfaces)";
  for (const std::string& r : coarse.region_names)
    if (std::find(c.fracturable_regions.begin(), c.fracturable_regions.end(), r) == c.fracturable_regions.end())
      return "region '" + r + "' is not fracturable";
  return "";
}

LocalSetup local_setup(Case& c, const Comm& comm, const HostMesh& coarse, PartitionMethod method,
                       const std::vector<std::string>& region_sets) {
  setup_times::Phase phase("local_parts");
  const Basis b = share_coarse(c, comm, coarse, method);
  std::vector<int> own_elems;
  for (int e = 0; e < b.coarse.num_elems(); ++e)
    if (b.cpart[e] == comm.rank()) own_elems.push_back(e);
  LocalSetup out;
  double min_size = 0;
  LocalHooks hooks;
  {
    setup_times::Phase sizes("local_sizes");  // (inside local_parts: counted once)
    RefinedPart own = refine_elements(b.coarse, b.topo, own_elems);
    hooks = rotation_hooks(c, comm, b, own.mesh);
    if (hooks.refined) hooks.refined(own.mesh);
    // (prepare_mesh checks the whole refined mesh's elements: here each process its own)
    check_elements(own.mesh, c.mesh.kind == "file" ? c.mesh.file : c.file + ": mesh");
    whole_sizes(comm, b, own.mesh, own_elems, out.mean_size, min_size);
  }
  resolve_defaults(c, out.mean_size);
  out.reach = c.contact.enabled != 0
                  ? contact_penetration_depth(min_size, out.mean_size) + c.contact.skin + c.contact.zone
                  : 0.0;
  hooks.inserted = [&region_sets](HostMesh& m) { add_region_node_sets(m, region_sets); };
  WholeFacts facts;
  facts.elems = static_cast<long>(b.coarse.num_elems()) * b.children;
  facts.nodes = facts.elems * (c.dim + 1);
  facts.ifaces = static_cast<long>(b.off.back());
  facts.pieces = facet_pieces(b);
  facts.min_size = min_size;
  facts.warnings = b.coarse.warnings;
  facts.bodies = b.coarse.bodies;
  {
    setup_times::Phase part("local_part");
    out.part = local_part(b.coarse, b.topo, b.off, b.cpart, comm.size(), comm.rank(), out.reach, facts, nullptr, hooks);
  }
  setup_times::Phase facts_phase("local_whole_facts");
  whole_set_sizes(comm, out.part);
  complete_from_requests(comm, out.part);
  out.mesh_hash = parts_mesh_hash(comm, out.part);
  out.mesh_report = parts_mesh_report(c, comm, out.part);
  facts_phase.stop();
  phase.stop();
  if (comm.rank() == 0 && out.reach > 0) {
    out.elem_part.resize(static_cast<size_t>(facts.elems));
    for (size_t e = 0; e < out.elem_part.size(); ++e) out.elem_part[e] = b.cpart[e / b.children];
  }
  return out;
}

}  // namespace fdem
