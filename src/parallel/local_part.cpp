// local_part (local_part.hpp) and its phases: the halo of coarse elements, their refinement with
// interfaces and global ids, the part cut out of it, and the exchange lists from requests.
#include "parallel/local_part.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"

namespace fdem {

namespace {

// How far the refinement may move a new node out of its coarse element: onto a curved surface
// (CurvedSurface) radially, from a point of a boundary facet at distance d >= the facet's plane's
// from the centre, so by at most R - d; the largest over the curved facets.
double curved_margin(const HostMesh& m, const CoarseTopology& t) {
  const int D = m.dim;
  double margin = 0;
  const std::size_t facets = D == 2 ? t.edges.size() : t.faces.size();
  for (std::size_t F = 0; F < facets; ++F) {
    const int s = D == 2 ? t.edge_surface[F] : t.face_surface[F];
    if (s < 0) continue;
    const CurvedSurface& S = t.surfaces[s];
    double v[3][3] = {};
    for (int a = 0; a < D; ++a) {
      const int n = D == 2 ? t.edges[F][a] : t.faces[F][a];
      for (int k = 0; k < D; ++k) v[a][k] = m.X[static_cast<std::size_t>(n) * D + k] - S.centre[k];
    }
    double nrm[3] = {0, 0, 0};
    if (D == 2) {
      nrm[0] = v[1][1] - v[0][1];
      nrm[1] = v[0][0] - v[1][0];
    } else {
      const double e1[3] = {v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
      const double e2[3] = {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
      nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
      nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
      nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
    }
    double len = 0, d = 0;
    for (int k = 0; k < D; ++k) len += nrm[k] * nrm[k];
    len = std::sqrt(len);
    if (!(len > 0)) return std::numeric_limits<double>::infinity();  // degenerate: no bound
    for (int k = 0; k < D; ++k) d += nrm[k] / len * v[0][k];
    margin = std::max(margin, S.radius - std::abs(d));
  }
  return margin;
}

// Each coarse element's bounding box widened by `w` (lo, hi: D values each).
void coarse_boxes(const HostMesh& m, double w, std::vector<double>& lo, std::vector<double>& hi) {
  const int D = m.dim, npe = D + 1, ne = m.num_elems();
  lo.assign(static_cast<std::size_t>(ne) * D, std::numeric_limits<double>::infinity());
  hi.assign(static_cast<std::size_t>(ne) * D, -std::numeric_limits<double>::infinity());
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a)
      for (int k = 0; k < D; ++k) {
        const double x = m.X[static_cast<std::size_t>(m.elems[static_cast<std::size_t>(e) * npe + a]) * D + k];
        lo[static_cast<std::size_t>(e) * D + k] = std::min(lo[static_cast<std::size_t>(e) * D + k], x - w);
        hi[static_cast<std::size_t>(e) * D + k] = std::max(hi[static_cast<std::size_t>(e) * D + k], x + w);
      }
}

// The coarse elements whose widened box comes within `reach` of an own element's widened box: the
// own elements binned in a uniform grid (cells about a mean element wide, at least `reach`) by
// their boxes widened by reach, each element tested against those of the cells its box meets.
std::vector<char> within_reach(const HostMesh& m, const std::vector<int>& coarse_part, int p, double margin,
                               double reach) {
  const int D = m.dim, ne = m.num_elems();
  std::vector<double> lo, hi;
  coarse_boxes(m, margin, lo, hi);
  auto L = [&](int e, int k) { return lo[static_cast<std::size_t>(e) * D + k]; };
  auto H = [&](int e, int k) { return hi[static_cast<std::size_t>(e) * D + k]; };
  double glo[3] = {0, 0, 0}, ghi[3] = {0, 0, 0}, ext = 0;
  for (int k = 0; k < D; ++k) {
    glo[k] = std::numeric_limits<double>::infinity();
    ghi[k] = -glo[k];
  }
  for (int e = 0; e < ne; ++e) {
    double emax = 0;
    for (int k = 0; k < D; ++k) {
      glo[k] = std::min(glo[k], L(e, k) - reach);
      ghi[k] = std::max(ghi[k], H(e, k) + reach);
      emax = std::max(emax, H(e, k) - L(e, k));
    }
    ext += emax;
  }
  double cell = std::max({reach, ext / std::max(ne, 1), 1e-300});
  long dims[3] = {1, 1, 1}, total = 1;
  for (;;) {  // at most about 4 cells per coarse element
    total = 1;
    for (int k = 0; k < D; ++k) {
      dims[k] = static_cast<long>(std::floor((ghi[k] - glo[k]) / cell)) + 1;
      total *= dims[k];
    }
    if (total <= 4L * ne + 64) break;
    cell *= 1.5;
  }
  auto range = [&](int e, double w, long* c0, long* c1) {
    for (int k = 0; k < 3; ++k) c0[k] = c1[k] = 0;
    for (int k = 0; k < D; ++k) {
      c0[k] = std::clamp<long>(static_cast<long>(std::floor((L(e, k) - w - glo[k]) / cell)), 0, dims[k] - 1);
      c1[k] = std::clamp<long>(static_cast<long>(std::floor((H(e, k) + w - glo[k]) / cell)), 0, dims[k] - 1);
    }
  };
  auto each_cell = [&](int e, double w, auto&& f) {
    long c0[3], c1[3], c[3];
    range(e, w, c0, c1);
    for (c[2] = c0[2]; c[2] <= c1[2]; ++c[2])
      for (c[1] = c0[1]; c[1] <= c1[1]; ++c[1])
        for (c[0] = c0[0]; c[0] <= c1[0]; ++c[0]) f(c[0] + dims[0] * (c[1] + dims[1] * c[2]));
  };
  // the own elements by the cells their boxes widened by reach meet (compressed rows)
  std::vector<int> start(static_cast<std::size_t>(total) + 1, 0), items;
  for (int e = 0; e < ne; ++e)
    if (coarse_part[e] == p) each_cell(e, reach, [&](long id) { ++start[id + 1]; });
  for (long id = 0; id < total; ++id) start[id + 1] += start[id];
  items.resize(start[total]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int e = 0; e < ne; ++e)
    if (coarse_part[e] == p) each_cell(e, reach, [&](long id) { items[fill[id]++] = e; });
  std::vector<char> sel(ne, 0);
  for (int e = 0; e < ne; ++e) {
    if (coarse_part[e] == p) {
      sel[e] = 1;
      continue;
    }
    each_cell(e, 0.0, [&](long id) {
      for (int j = start[id]; j < start[id + 1] && !sel[e]; ++j) {
        const int o = items[j];
        double d2 = 0;
        for (int k = 0; k < D; ++k) {
          const double gap = std::max({L(o, k) - H(e, k), L(e, k) - H(o, k), 0.0});
          d2 += gap * gap;
        }
        sel[e] = d2 <= reach * reach;
      }
    });
  }
  return sel;
}

// Adds `rings` rings of facet neighbours around the selected elements. Two hold what a part needs
// (local_part): its own and contact zone's fine elements lie in the selection; the sides of their
// interfaces are their face neighbours, within the first ring; the second completes the first's
// faces (each fine node is one element's copy, so no other element joins through a node).
void add_rings(const HostMesh& m, const CoarseTopology& t, std::vector<char>& sel, int rings) {
  const int npe = m.dim + 1, ne = m.num_elems();
  for (int r = 0; r < rings; ++r) {
    const std::vector<char> before = sel;
    for (int e = 0; e < ne; ++e)
      if (before[e])
        for (int a = 0; a < npe; ++a)
          if (const int o = t.elem_neighbours[static_cast<std::size_t>(e) * npe + a]; o >= 0) sel[o] = 1;
  }
}

// The coarse mesh must come without interfaces (they are inserted after the refinement).
void check_scope(const HostMesh& coarse) {
  if (!coarse.ifaces.empty()) throw InputError("local_part: the coarse mesh already has interfaces");
}

// Part p cut from a refined neighbourhood, in the neighbourhood's numbering, and whether every item
// it holds lies where the neighbourhood is the whole mesh's (else the halo needs another ring).
bool cut_part(const LocalRefinement& L, const std::vector<int>& coarse_part, int parts, int p, double reach,
              std::int64_t children, SubMesh& s) {
  std::vector<int> elem_part(L.mesh.num_elems());
  for (int e = 0; e < L.mesh.num_elems(); ++e) elem_part[e] = coarse_part[L.elem_gid[e] / children];
  PartBuilder b(L.mesh, elem_part, parts, reach, nullptr, p);
  s = b.part(p);
  for (int q : s.iface_global)
    if (L.iface_gid[q] < 0) return false;
  for (int e : s.elem_global)
    if (!L.closed[L.elem_gid[e] / children]) return false;
  return true;
}

// The part's items renumbered to the whole mesh's ids, with the whole mesh's facts.
void to_global(const LocalRefinement& L, const WholeFacts& facts, double reach, SubMesh& s) {
  for (int& n : s.node_global) n = static_cast<int>(L.node_gid[n]);
  for (int& e : s.elem_global) e = static_cast<int>(L.elem_gid[e]);
  for (int& q : s.iface_global) q = static_cast<int>(L.iface_gid[q]);
  s.mesh.iface_ids = s.iface_global;
  s.whole_nodes = facts.nodes;
  s.whole_elems = facts.elems;
  s.whole_ifaces = facts.ifaces;
  s.mesh.warnings = facts.warnings;
  s.mesh.bodies = facts.bodies;
  if (reach > 0) {
    s.mesh.pieces = facts.pieces;
    s.mesh.whole_min_size = facts.min_size;
  }
  s.mesh.whole_set_size.clear();
  for (const auto& [name, size] : facts.set_sizes) s.mesh.whole_set_size[name] = size;
}

}  // namespace

std::vector<int> halo_coarse_elements(const HostMesh& coarse, const CoarseTopology& topo,
                                      const std::vector<int>& coarse_part, int p, double reach, int rings) {
  if (static_cast<int>(coarse_part.size()) != coarse.num_elems())
    throw InputError("halo_coarse_elements: " + std::to_string(coarse_part.size()) + " part ids for " +
                     std::to_string(coarse.num_elems()) + " coarse elements");
  const double margin = curved_margin(coarse, topo);
  // (a degenerate curved facet gives no bound: every coarse element then)
  std::vector<char> sel = std::isfinite(margin) ? within_reach(coarse, coarse_part, p, margin, std::max(reach, 0.0))
                                                : std::vector<char>(coarse.num_elems(), 1);
  add_rings(coarse, topo, sel, rings);
  std::vector<int> out;
  for (int e = 0; e < coarse.num_elems(); ++e)
    if (sel[e]) out.push_back(e);
  return out;
}

LocalRefinement refine_and_insert(const HostMesh& coarse, const CoarseTopology& topo,
                                  const std::vector<std::int64_t>& iface_offsets, const std::vector<int>& coarse_elems,
                                  const LocalHooks& hooks) {
  check_scope(coarse);
  const int D = coarse.dim, npe = D + 1;
  if (!std::is_sorted(coarse_elems.begin(), coarse_elems.end()))
    throw InputError("refine_and_insert: the coarse elements must be in ascending order");
  RefinedPart r = refine_elements(coarse, topo, coarse_elems);
  LocalRefinement L;
  L.mesh = std::move(r.mesh);
  L.elem_gid = std::move(r.elem_gid);
  for (int n = 0; n < L.mesh.num_nodes(); ++n) L.mesh.node_origin[n] = static_cast<int>(r.node_gid[n]);
  if (hooks.refined) hooks.refined(L.mesh);
  insert_interfaces(L.mesh, std::vector<bool>(L.mesh.region_names.size(), true));
  if (hooks.inserted) hooks.inserted(L.mesh);
  // the nodes: after insertion each is one element's copy of a corner, the whole mesh's e npe + a
  L.node_gid.assign(L.mesh.num_nodes(), -1);
  for (int e = 0; e < L.mesh.num_elems(); ++e)
    for (int a = 0; a < npe; ++a)
      L.node_gid[L.mesh.elems[static_cast<std::size_t>(e) * npe + a]] = L.elem_gid[e] * npe + a;
  // the interfaces: those of a coarse element's children (side A) are the whole mesh's when every
  // facet neighbour with a higher id is held (closed implies it), numbered from its offset on
  std::vector<char> held(coarse.num_elems(), 0), complete(coarse.num_elems(), 0);
  L.closed.assign(coarse.num_elems(), 0);
  for (int e : coarse_elems) held[e] = 1;
  for (int e : coarse_elems) {
    bool all = true, higher = true;
    for (int a = 0; a < npe; ++a) {
      const int o = topo.elem_neighbours[static_cast<std::size_t>(e) * npe + a];
      if (o >= 0 && !held[o]) {
        all = false;
        higher = higher && o < e;
      }
    }
    L.closed[e] = all;
    complete[e] = higher;
  }
  const std::int64_t children = static_cast<std::int64_t>(refine_factor(D, topo.levels) + 0.5);
  L.iface_gid.assign(L.mesh.num_ifaces(), -1);
  int run_start = 0;
  std::int64_t run_coarse = -1;
  for (int q = 0; q < L.mesh.num_ifaces(); ++q) {
    const std::int64_t c = L.elem_gid[L.mesh.iface_elems[2 * static_cast<std::size_t>(q)]] / children;
    if (c != run_coarse) {
      run_coarse = c;
      run_start = q;
    }
    if (complete[c]) L.iface_gid[q] = iface_offsets[c] + (q - run_start);
  }
  return L;
}

SubMesh local_part(const HostMesh& coarse, const CoarseTopology& topo, const std::vector<std::int64_t>& iface_offsets,
                   const std::vector<int>& coarse_part, int parts, int p, double contact_reach, const WholeFacts& facts,
                   LocalPartStats* stats, const LocalHooks& hooks) {
  check_scope(coarse);
  if (p < 0 || p >= parts)
    throw InputError("local_part: part " + std::to_string(p) + " outside [0, " + std::to_string(parts - 1) + "]");
  const std::int64_t children = static_cast<std::int64_t>(refine_factor(coarse.dim, topo.levels) + 0.5);
  // two rings always hold the sides of the part's interfaces and their faces (add_rings); one is
  // often enough (the boxes within reach already hold the coarse elements touching the own ones):
  // try it first, then more
  LocalPartStats st;
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  for (int rings = 1; rings <= 8; ++rings) {
    Clock::time_point t = Clock::now();
    const std::vector<int> halo =
        halo_coarse_elements(coarse, topo, coarse_part, p, contact_reach > 0 ? contact_reach + hooks.widen : 0.0, rings);
    st.halo_seconds += since(t);
    t = Clock::now();
    const LocalRefinement L = refine_and_insert(coarse, topo, iface_offsets, halo, hooks);
    st.refine_seconds += since(t);
    t = Clock::now();
    SubMesh s;
    const bool held = cut_part(L, coarse_part, parts, p, contact_reach, children, s);
    st.cut_seconds += since(t);
    if (!held) continue;
    to_global(L, facts, contact_reach, s);
    st.coarse_elems = static_cast<long>(halo.size());
    st.fine_elems = L.mesh.num_elems();
    st.rings = rings;
    if (stats) *stats = st;
    return s;
  }
  throw InputError("local_part: part " + std::to_string(p) +
                   " needs more than 8 rings of coarse elements around it (a contact reach far larger than the "
                   "coarse elements?)");
}

std::vector<std::vector<std::int64_t>> ghost_requests(const SubMesh& s) {
  std::vector<std::vector<std::int64_t>> out(s.neighbours.size());
  for (std::size_t k = 0; k < s.neighbours.size(); ++k)
    for (int j : s.recv[k]) out[k].push_back(s.node_global[j]);
  return out;
}

PartLists lists_from_requests(const SubMesh& s, const std::vector<int>& from,
                              const std::vector<std::vector<std::int64_t>>& requested) {
  if (from.size() != requested.size())
    throw InputError("lists_from_requests: " + std::to_string(requested.size()) + " requests from " +
                     std::to_string(from.size()) + " parts");
  const int own = s.mesh.owned_nodes;
  const auto b = s.node_global.begin(), e = s.node_global.begin() + own;  // ascending
  PartLists l;
  l.neighbours = s.neighbours;
  l.neighbours.insert(l.neighbours.end(), from.begin(), from.end());
  std::sort(l.neighbours.begin(), l.neighbours.end());
  l.neighbours.erase(std::unique(l.neighbours.begin(), l.neighbours.end()), l.neighbours.end());
  l.send.resize(l.neighbours.size());
  for (std::size_t k = 0; k < from.size(); ++k) {
    const std::size_t slot = std::lower_bound(l.neighbours.begin(), l.neighbours.end(), from[k]) - l.neighbours.begin();
    for (std::int64_t g : requested[k]) {
      const auto it = std::lower_bound(b, e, g);
      if (it == e || *it != g)
        throw InputError("lists_from_requests: part " + std::to_string(from[k]) + " asks part " +
                         std::to_string(s.part) + " for node " + std::to_string(g) + ", not one of its own");
      l.send[slot].push_back(static_cast<int>(it - b));
    }
  }
  return l;
}

}  // namespace fdem
