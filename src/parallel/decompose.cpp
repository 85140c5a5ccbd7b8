// decompose (decompose.hpp) and its phases: the whole mesh's tables (node owners, the elements and
// interfaces at each node, the contact zones and outer faces), then each part's items, their
// order, its local mesh, sets and exchange lists. One concern: the cut of a mesh into its parts.
#include "parallel/decompose.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "mesh/pieces.hpp"

namespace fdem {

namespace {

// Distinct keys in ascending order: std::sort's order, by least-significant-digit radix sort over
// 16-bit digits (a digit the keys all share is skipped). The parts' orderings sort one key per
// interface: at 1e7 tetrahedra std::sort fell back to heap sort on them (0.8 s of a part's set-up).
void sort_keys(std::vector<std::uint64_t>& key) {
  if (key.size() < 4096) {
    std::sort(key.begin(), key.end());
    return;
  }
  std::vector<std::uint64_t> tmp(key.size());
  std::vector<size_t> count(size_t{1} << 16);
  for (int shift = 0; shift < 64; shift += 16) {
    std::fill(count.begin(), count.end(), size_t{0});
    for (const std::uint64_t k : key) ++count[(k >> shift) & 0xffffu];
    if (count[(key[0] >> shift) & 0xffffu] == key.size()) continue;  // (one digit: nothing to move)
    size_t at = 0;
    for (size_t& c : count) {
      const size_t n = c;
      c = at;
      at += n;
    }
    for (const std::uint64_t k : key) tmp[count[(k >> shift) & 0xffffu]++] = k;
    key.swap(tmp);
  }
}

// Compressed rows: the items of key k are items[start[k] .. start[k + 1]).
struct Rows {
  std::vector<int> start, items;
};

// The items j < count by key, by counting (a count per key, a prefix sum, a fill): key(j, a) in
// [0, keys) for a < per are the keys of item j, which is listed once for each; each row ascending.
template <class Key>
Rows rows_of(long keys, int count, int per, Key key) {
  Rows r;
  r.start.assign(static_cast<size_t>(keys) + 1, 0);
  for (int j = 0; j < count; ++j)
    for (int a = 0; a < per; ++a) ++r.start[key(j, a) + 1];
  for (long k = 0; k < keys; ++k) r.start[k + 1] += r.start[k];
  r.items.resize(r.start[keys]);
  std::vector<int> fill(r.start.begin(), r.start.end() - 1);
  for (int j = 0; j < count; ++j)
    for (int a = 0; a < per; ++a) r.items[fill[key(j, a)]++] = j;
  return r;
}

// At the positions X: each element's bounding box (lo, hi: D values per element), that of all the
// nodes (glo, ghi) and the sum over the elements of their longest side (ext).
struct Boxes {
  std::vector<double> lo, hi;
  double glo[3] = {0, 0, 0}, ghi[3] = {0, 0, 0}, ext = 0;
};

Boxes bounding_boxes(const HostMesh& whole, const std::vector<double>& X) {
  const int D = whole.dim, npe = D + 1, nn = whole.num_nodes(), ne = whole.num_elems();
  Boxes b;
  b.lo.resize(static_cast<size_t>(ne) * D);
  b.hi.resize(static_cast<size_t>(ne) * D);
  for (int k = 0; k < D; ++k) {
    b.glo[k] = std::numeric_limits<double>::infinity();
    b.ghi[k] = -b.glo[k];
  }
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < D; ++k) {
      b.glo[k] = std::min(b.glo[k], X[static_cast<size_t>(n) * D + k]);
      b.ghi[k] = std::max(b.ghi[k], X[static_cast<size_t>(n) * D + k]);
    }
  for (int e = 0; e < ne; ++e) {
    double emax = 0;
    for (int k = 0; k < D; ++k) {
      double l = std::numeric_limits<double>::infinity(), h = -l;
      for (int a = 0; a < npe; ++a) {
        const double x = X[static_cast<size_t>(whole.elems[static_cast<size_t>(e) * npe + a]) * D + k];
        l = std::min(l, x);
        h = std::max(h, x);
      }
      b.lo[static_cast<size_t>(e) * D + k] = l;
      b.hi[static_cast<size_t>(e) * D + k] = h;
      emax = std::max(emax, h - l);
    }
    b.ext += emax;
  }
  return b;
}

// The nodes binned in a uniform grid of cells at least `reach` and the mean element extent wide (at
// most about 4 cells per node): the nodes of each cell, ascending.
struct NodeGrid {
  int dim = 2;
  double glo[3] = {0, 0, 0}, cell = 0;
  long dims[3] = {1, 1, 1};
  Rows nodes;                          // by cell id
  std::vector<int> owner;              // the part owning each of nodes.items (read in its order)
  std::vector<char> mixed;             // per cell: its nodes have more than one owner
  long coord(double x, int k) const {  // the cell along axis k of x (clamped to the grid)
    const long c = static_cast<long>(std::floor((x - glo[k]) / cell));
    return std::clamp<long>(c, 0, dims[k] - 1);
  }
  long cell_id(const long* c) const {
    return dim == 2 ? c[0] + dims[0] * c[1] : c[0] + dims[0] * (c[1] + dims[1] * c[2]);
  }
};

NodeGrid node_grid(const Boxes& b, const std::vector<double>& X, int D, int nn, int ne, double reach) {
  NodeGrid g;
  g.dim = D;
  for (int k = 0; k < D; ++k) g.glo[k] = b.glo[k];
  g.cell = std::max({reach, b.ext / ne, 1e-300});
  for (;;) {
    long total = 1;
    for (int k = 0; k < D; ++k) {
      g.dims[k] = static_cast<long>(std::floor((b.ghi[k] - b.glo[k]) / g.cell)) + 1;
      total *= g.dims[k];
    }
    if (total <= 4L * nn + 64) break;
    g.cell *= 1.5;
  }
  std::vector<long> key(nn);
  for (int n = 0; n < nn; ++n) {
    long c[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) c[k] = g.coord(X[static_cast<size_t>(n) * D + k], k);
    key[n] = g.cell_id(c);
  }
  g.nodes = rows_of(g.dims[0] * g.dims[1] * g.dims[2], nn, 1, [&key](int n, int) { return key[n]; });
  return g;
}

// The query: for each element, the nodes of the cells its box widened by `reach` covers; an
// element joins the zone of each other part that owns one of them within reach of the box.
std::vector<std::vector<int>> query_zones(const Boxes& b, const NodeGrid& g, const std::vector<double>& X,
                                          const std::vector<int>& elem_part, int parts, double reach, int only) {
  const int D = g.dim, ne = static_cast<int>(elem_part.size());
  std::vector<std::vector<int>> zone(parts);
  std::vector<int> stamp(parts, -1);
  const double r2 = reach * reach;
  for (int e = 0; e < ne; ++e) {
    if (only >= 0 && elem_part[e] == only) continue;
    const double* l = &b.lo[static_cast<size_t>(e) * D];
    const double* h = &b.hi[static_cast<size_t>(e) * D];
    long c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) {
      c0[k] = g.coord(l[k] - reach, k);
      c1[k] = g.coord(h[k] + reach, k);
    }
    long c[3] = {0, 0, 0};
    for (c[2] = c0[2]; c[2] <= c1[2]; ++c[2])
      for (c[1] = c0[1]; c[1] <= c1[1]; ++c[1])
        for (c[0] = c0[0]; c[0] <= c1[0]; ++c[0]) {
          const long id = g.cell_id(c);
          const int j0 = g.nodes.start[id], j1 = g.nodes.start[id + 1];
          if (j0 == j1 || (!g.mixed[id] && (g.owner[j0] == elem_part[e] || stamp[g.owner[j0]] == e))) continue;
          for (int j = j0; j < j1; ++j) {
            const int p = g.owner[j];
            if (p == elem_part[e] || stamp[p] == e || (only >= 0 && p != only)) continue;
            const int n = g.nodes.items[j];
            double d2 = 0;
            for (int k = 0; k < D; ++k) {
              const double x = X[static_cast<size_t>(n) * D + k];
              const double d = x < l[k] ? l[k] - x : (x > h[k] ? x - h[k] : 0.0);
              d2 += d * d;
            }
            if (d2 <= r2) {
              stamp[p] = e;
              zone[p].push_back(e);
            }
          }
        }
  }
  return zone;
}

// For each part (only >= 0: that part only, the others' lists empty), the elements of the other
// parts that come within `reach` of one of its own nodes (the distance from the node to the
// element's bounding box, at the positions X), each list ascending: the bounding boxes, the node
// grid, the query.
std::vector<std::vector<int>> contact_zones(const HostMesh& whole, const std::vector<double>& X,
                                            const std::vector<int>& elem_part, const std::vector<int>& owner,
                                            int parts, double reach, int only) {
  const int D = whole.dim, nn = whole.num_nodes(), ne = whole.num_elems();
  if (ne == 0 || nn == 0) return std::vector<std::vector<int>>(parts);
  const Boxes b = bounding_boxes(whole, X);
  NodeGrid g = node_grid(b, X, D, nn, ne, reach);
  // the owners beside the grid's nodes: most nodes a query meets are its element's part's, skipped
  // on a sequential read instead of a random one
  g.owner.resize(g.nodes.items.size());
  for (size_t j = 0; j < g.owner.size(); ++j) g.owner[j] = owner[g.nodes.items[j]];
  // (and a cell all of whose nodes are the element's part's is skipped whole: the interior of a part)
  g.mixed.assign(g.nodes.start.size() - 1, 0);
  for (size_t id = 0; id + 1 < g.nodes.start.size(); ++id)
    for (int j = g.nodes.start[id] + 1; j < g.nodes.start[id + 1] && !g.mixed[id]; ++j)
      g.mixed[id] = g.owner[j] != g.owner[j - 1];
  return query_zones(b, g, X, elem_part, parts, reach, only);
}

// Who owns what: each node's part (that of the first element holding it; orphan nodes: part 0) and
// its index among its owner's own nodes; each part's own nodes and elements, ascending.
struct Owners {
  std::vector<int> owner, own_index;
  std::vector<std::vector<int>> own_nodes, own_elems;
};

// What a run with contact takes from the whole mesh: each part's contact zone, the outer faces (D
// nodes each) with the element of each, the connected pieces and the smallest element size.
struct WholeContact {
  std::vector<std::vector<int>> zones;
  std::vector<int> outer, outer_elem;
  int pieces = -1;
  double min_size = 0;
};

// A part's items (whole mesh's indices), at the end in their local order: interfaces, elements,
// ghost nodes and all its nodes (own, then the ghosts); the sizes of the leading groups (own and
// bulk elements, counted interfaces) and the number of inert ghosts.
struct PartItems {
  std::vector<int> ifs, els, nds, nodes;
  int eo = 0, eb = 0, io = 0, inert = 0;
};

// One decomposition: the whole mesh's tables (checks, node owners, adjacency, the contact's zones
// and outer faces), then each part in turn (its items, their order, its local mesh, sets and
// exchange lists), then the parts' neighbours.
class Decomposer {
 public:
  Decomposer(const HostMesh& whole, const std::vector<int>& elem_part, int parts, double contact_reach,
             const std::vector<double>* at, int only = -1);
  std::vector<SubMesh> run();
  SubMesh part(int p);
  PartLists lists(int q);

 private:
  int enode(int e, int a) const { return w_.elems[static_cast<size_t>(e) * npe_ + a]; }
  int inode(int q, int a) const { return w_.ifaces[static_cast<size_t>(q) * 2 * D_ + a]; }
  void check() const;
  void find_owners();
  void find_contact();
  void select_items(int p, PartItems& it);
  void list_ghost_nodes(int p, PartItems& it);
  void order_elements(int p, PartItems& it) const;
  void order_ghost_nodes(int p, PartItems& it);
  void order_interfaces(int p, PartItems& it);
  void local_mesh(const PartItems& it, SubMesh& s);
  void local_sets(int p, const PartItems& it, HostMesh& m) const;
  void exchange_lists(int p, const PartItems& it, SubMesh& s);

  const HostMesh& w_;
  const std::vector<int>& elem_part_;
  const int parts_;
  const double reach_;
  const std::vector<double>* at_;
  const int only_;  // >= 0: only this part is built (its zone only; no pieces or smallest size)
  const int D_, npe_, nn_, ne_, ni_;
  const bool zoned_;
  Owners own_;
  Rows n2e_, n2i_;  // the elements and the interfaces at each node
  WholeContact contact_;
  std::vector<int> emark_, imark_, nmark_;  // stamped with the part
  std::vector<int> elocal_, nlocal_, ilocal_;
  // sends_[q][p]: q's own local nodes that p needs, in p's order; recv_from_[p]: the parts p
  // receives from (its part's neighbours before lists())
  std::vector<std::vector<std::vector<int>>> sends_;
  std::vector<std::vector<int>> recv_from_;
};

Decomposer::Decomposer(const HostMesh& whole, const std::vector<int>& elem_part, int parts,
                       double contact_reach, const std::vector<double>* at, int only)
    : w_(whole),
      elem_part_(elem_part),
      parts_(parts),
      reach_(contact_reach),
      at_(at),
      only_(only),
      D_(whole.dim),
      npe_(whole.dim + 1),
      nn_(whole.num_nodes()),
      ne_(whole.num_elems()),
      ni_(whole.num_ifaces()),
      zoned_(contact_reach > 0) {
  check();
  find_owners();
  n2e_ = rows_of(nn_, ne_, npe_, [this](int e, int a) { return enode(e, a); });
  n2i_ = rows_of(nn_, ni_, 2 * D_, [this](int q, int a) { return inode(q, a); });
  if (zoned_) find_contact();
  emark_.assign(ne_, -1);
  imark_.assign(ni_, -1);
  nmark_.assign(nn_, -1);
  elocal_.assign(ne_, -1);
  nlocal_.assign(nn_, -1);
  ilocal_.assign(ni_, -1);
  sends_.assign(parts_, std::vector<std::vector<int>>(parts_));
  recv_from_.resize(parts_);
}

// The checks of the input (InputError).
void Decomposer::check() const {
  if (parts_ < 1)
    throw InputError("decompose: parts must be at least 1 (got " + std::to_string(parts_) + ")");
  if (static_cast<int>(elem_part_.size()) != ne_)
    throw InputError("decompose: " + std::to_string(elem_part_.size()) + " part ids for " +
                     std::to_string(ne_) + " elements");
  for (int e = 0; e < ne_; ++e)
    if (elem_part_[e] < 0 || elem_part_[e] >= parts_)
      throw InputError("decompose: element " + std::to_string(e) + " has part " +
                       std::to_string(elem_part_[e]) + ", outside [0, " + std::to_string(parts_ - 1) + "]");
  if (w_.owned_nodes >= 0) throw InputError("decompose: the mesh is already one part of a decomposition");
  if (zoned_ && !std::isfinite(reach_))
    throw InputError("decompose: the contact reach must be finite (got " + std::to_string(reach_) + ")");
  if (at_ && at_->size() != w_.X.size())
    throw InputError("decompose: " + std::to_string(at_->size()) + " position values for " +
                     std::to_string(w_.X.size()));
}

void Decomposer::find_owners() {
  std::vector<int>& owner = own_.owner;
  owner.assign(nn_, -1);
  for (int e = 0; e < ne_; ++e)
    for (int a = 0; a < npe_; ++a)
      if (owner[enode(e, a)] < 0) owner[enode(e, a)] = elem_part_[e];
  for (int& o : owner)
    if (o < 0) o = 0;
  own_.own_nodes.resize(parts_);
  own_.own_elems.resize(parts_);
  own_.own_index.assign(nn_, 0);
  for (int n = 0; n < nn_; ++n) {
    own_.own_index[n] = static_cast<int>(own_.own_nodes[owner[n]].size());
    own_.own_nodes[owner[n]].push_back(n);
  }
  for (int e = 0; e < ne_; ++e) own_.own_elems[elem_part_[e]].push_back(e);
}

// Contact: each part's zone (at the positions `at`, else the reference ones), the outer faces and
// the element of each, the connected pieces and the smallest element size.
void Decomposer::find_contact() {
  WholeContact& c = contact_;
  c.zones = contact_zones(w_, at_ ? *at_ : w_.X, elem_part_, own_.owner, parts_, reach_, only_);
  c.outer = boundary_faces(w_);
  c.outer_elem.assign(c.outer.size() / std::max(D_, 1), -1);  // the element of each outer face
  for (size_t f = 0; f < c.outer_elem.size(); ++f) {
    const int n0 = c.outer[f * D_];
    for (int k = n2e_.start[n0]; k < n2e_.start[n0 + 1] && c.outer_elem[f] < 0; ++k) {
      const int e = n2e_.items[k];
      int found = 0;
      for (int a = 0; a < D_; ++a)
        for (int b = 0; b < npe_; ++b) found += enode(e, b) == c.outer[f * D_ + a];
      if (found == D_) c.outer_elem[f] = e;
    }
  }
  if (only_ >= 0) return;  // (the caller's: local_part's WholeFacts)
  c.pieces = count_bodies(w_);
  c.min_size = mesh_sizes(w_).min_size;
}

std::vector<SubMesh> Decomposer::run() {
  std::vector<SubMesh> out(parts_);
  for (int p = 0; p < parts_; ++p) out[p] = part(p);
  for (int q = 0; q < parts_; ++q) complete_lists(out[q], lists(q));
  return out;
}

SubMesh Decomposer::part(int p) {
  if (only_ >= 0 && p != only_)
    throw InputError("decompose: part " + std::to_string(p) + " asked of a builder of part " + std::to_string(only_) +
                     " only");
  SubMesh s;
  s.part = p;
  s.parts = parts_;
  s.whole_nodes = nn_;
  s.whole_elems = ne_;
  s.whole_ifaces = w_.num_ifaces();
  s.contact_reach = reach_;
  PartItems it;
  select_items(p, it);
  list_ghost_nodes(p, it);
  order_elements(p, it);
  order_ghost_nodes(p, it);
  s.inert_ghosts = it.inert;
  order_interfaces(p, it);
  local_mesh(it, s);
  local_sets(p, it, s.mesh);
  exchange_lists(p, it, s);
  recv_from_[p] = s.neighbours;
  for (int n : it.nodes) nlocal_[n] = -1;
  for (int e : it.els) elocal_[e] = -1;
  for (int q : it.ifs) ilocal_[q] = -1;
  // the local items' whole mesh's indices (moved, not copied: at 1e7 tetrahedra each copy is tens
  // of MB of fresh pages)
  s.node_global = std::move(it.nodes);
  s.elem_global = std::move(it.els);
  s.mesh.iface_ids = it.ifs;  // (the strength scatter's draw: solver/interface_materials.cpp)
  s.iface_global = std::move(it.ifs);
  return s;
}

// The part's elements: its own, those at an own node, its contact zone, the sides of its
// interfaces, and the closure (every element at a node of those); its interfaces: those at an own
// node (with contact: at any node of the elements before the sides). Each in order of selection.
void Decomposer::select_items(int p, PartItems& it) {
  std::vector<int>& ifs = it.ifs;
  std::vector<int>& els = it.els;
  auto add_ifaces_at = [&](int n) {
    for (int k = n2i_.start[n]; k < n2i_.start[n + 1]; ++k)
      if (imark_[n2i_.items[k]] != p) {
        imark_[n2i_.items[k]] = p;
        ifs.push_back(n2i_.items[k]);
      }
  };
  auto add_elem = [&](int e) {
    if (emark_[e] != p) {
      emark_[e] = p;
      els.push_back(e);
    }
  };
  // (room for about what a part holds, so that neither grows by copying: untouched room costs no
  // memory)
  const size_t own = own_.own_elems[p].size() + (zoned_ ? contact_.zones[p].size() : 0);
  els.reserve(own + own / 2);
  ifs.reserve(static_cast<size_t>(npe_) * (own + own / 2) / 2);
  for (int e : own_.own_elems[p]) add_elem(e);
  for (int n : own_.own_nodes[p])
    for (int k = n2e_.start[n]; k < n2e_.start[n + 1]; ++k) add_elem(n2e_.items[k]);
  if (zoned_) {  // the contact zone, and the interfaces at every node held so far
    for (int e : contact_.zones[p]) add_elem(e);
    for (size_t j = 0; j < els.size(); ++j)
      for (int a = 0; a < npe_; ++a) add_ifaces_at(enode(els[j], a));
  } else {
    for (int n : own_.own_nodes[p]) add_ifaces_at(n);
  }
  for (int q : ifs)
    for (int side = 0; side < 2; ++side) add_elem(w_.iface_elems[2 * static_cast<size_t>(q) + side]);
  const size_t e1 = els.size();
  for (size_t j = 0; j < e1; ++j)  // the closure: every element at a node of E1
    for (int a = 0; a < npe_; ++a) {
      const int n = enode(els[j], a);
      for (int k = n2e_.start[n]; k < n2e_.start[n + 1]; ++k) add_elem(n2e_.items[k]);
    }
}

// The ghost nodes: the nodes of the part's elements that are not its own, in order of first use.
void Decomposer::list_ghost_nodes(int p, PartItems& it) {
  for (int n : own_.own_nodes[p]) nmark_[n] = p;  // orphans included
  for (int e : it.els)
    for (int a = 0; a < npe_; ++a)
      if (nmark_[enode(e, a)] != p) {
        nmark_[enode(e, a)] = p;
        it.nds.push_back(enode(e, a));
      }
}

// Elements: own, then the ghosts at an own node (their bulk forces count), then the other ghosts
// (sides of interfaces, masses: no bulk force). Each group in the whole mesh's order.
void Decomposer::order_elements(int p, PartItems& it) const {
  auto eclass = [&](int e) {
    if (elem_part_[e] == p) return 0;
    for (int a = 0; a < npe_; ++a)
      if (own_.owner[enode(e, a)] == p) return 1;
    return 2;
  };
  std::vector<std::pair<int, int>> keyed;
  keyed.reserve(it.els.size());
  for (int e : it.els) keyed.push_back({eclass(e), e});
  std::sort(keyed.begin(), keyed.end());
  int eo = 0, eb = 0;
  for (size_t j = 0; j < keyed.size(); ++j) {
    it.els[j] = keyed[j].second;
    eo += keyed[j].first == 0;
    eb += keyed[j].first <= 1;
  }
  it.eo = eo;
  it.eb = eb;
}

// Ghost nodes: those a step reads (of the elements with a bulk force, of the interfaces) are
// exchanged; the others (only of elements without one) never move from where they start. Then the
// part's nodes: its own, then the ghosts.
void Decomposer::order_ghost_nodes(int p, PartItems& it) {
  std::vector<int>& nds = it.nds;
  // (nlocal_ as scratch: 1 for a node a step reads)
  for (int j = 0; j < it.eb; ++j)
    for (int a = 0; a < npe_; ++a) nlocal_[enode(it.els[j], a)] = 1;
  for (int q : it.ifs)
    for (int a = 0; a < 2 * D_; ++a) nlocal_[inode(q, a)] = 1;
  if (zoned_)  // contact reads every ghost (the faces and nodes of the zone, their velocities)
    for (int n : nds) nlocal_[n] = 1;
  // (the nodes a step reads first, each group in the whole mesh's order: sorted as one key each)
  std::vector<std::uint64_t> key(nds.size());
  for (size_t j = 0; j < nds.size(); ++j)
    key[j] = (static_cast<std::uint64_t>(nlocal_[nds[j]] == 1 ? 0 : 1) << 32) | static_cast<std::uint32_t>(nds[j]);
  sort_keys(key);
  for (size_t j = 0; j < nds.size(); ++j) nds[j] = static_cast<int>(key[j] & 0xffffffffu);
  for (int n : nds) it.inert += nlocal_[n] != 1;
  for (int n : nds) nlocal_[n] = -1;
  for (int n : own_.own_nodes[p]) nlocal_[n] = -1;
  it.nodes.reserve(own_.own_nodes[p].size() + nds.size());
  it.nodes = own_.own_nodes[p];
  it.nodes.insert(it.nodes.end(), nds.begin(), nds.end());
  std::vector<int>().swap(nds);
}

// Interfaces: the counted ones, then the others; each group in order of its side-A element's local
// index (the force pass's chunks), then the whole mesh's order.
void Decomposer::order_interfaces(int p, PartItems& it) {
  const std::vector<int>& owner = own_.owner;
  for (size_t j = 0; j < it.els.size(); ++j) elocal_[it.els[j]] = static_cast<int>(j);
  // one key per interface (counted first; the side-A element's local index, -1 first; the whole
  // mesh's index), sorted as integers: the order of comparing the three in turn, without looking
  // them up again at every comparison (a quarter of the cut's time at 3.9e6 own elements)
  std::vector<std::uint64_t> key(it.ifs.size());
  for (size_t j = 0; j < key.size(); ++j) {
    const int q = it.ifs[j];
    const std::uint64_t counted = owner[inode(q, 0)] == p ? 0 : 1;
    const auto la = static_cast<std::uint64_t>(elocal_[w_.iface_elems[2 * static_cast<size_t>(q)]] + 1);
    key[j] = (counted << 63) | (la << 31) | static_cast<std::uint64_t>(q);
  }
  sort_keys(key);
  for (size_t j = 0; j < key.size(); ++j) it.ifs[j] = static_cast<int>(key[j] & 0x7fffffffu);
  it.io = static_cast<int>(
      std::count_if(it.ifs.begin(), it.ifs.end(), [&](int q) { return owner[inode(q, 0)] == p; }));
}

// The local mesh (the items in their order, renumbered; with contact the outer faces it holds) and
// the positions the zones were taken at.
void Decomposer::local_mesh(const PartItems& it, SubMesh& s) {
  const std::vector<int>& nodes = it.nodes;
  const std::vector<int>& els = it.els;
  const std::vector<int>& ifs = it.ifs;
  const int D = D_, npe = npe_;
  HostMesh& m = s.mesh;
  m.dim = D;
  m.region_names = w_.region_names;
  m.warnings = w_.warnings;
  m.bodies = w_.bodies;
  m.owned_nodes = static_cast<int>(own_.own_nodes[s.part].size());
  m.owned_elems = it.eo;
  m.owned_ifaces = it.io;
  m.bulk_elems = it.eb;
  for (size_t j = 0; j < nodes.size(); ++j) nlocal_[nodes[j]] = static_cast<int>(j);
  for (size_t j = 0; j < els.size(); ++j) elocal_[els[j]] = static_cast<int>(j);
  for (size_t j = 0; j < ifs.size(); ++j) ilocal_[ifs[j]] = static_cast<int>(j);
  // (every array sized before it is filled: a vector grown by doubling touches about twice its
  // pages, and at 1e7 tetrahedra the set-up's time is mostly first touches)
  m.X.reserve(nodes.size() * D);
  m.node_origin.reserve(nodes.size());
  m.elem_region.reserve(els.size());
  m.ifaces.reserve(ifs.size() * 2 * D);
  m.iface_elems.reserve(ifs.size() * 2);
  for (int n : nodes) {
    for (int k = 0; k < D; ++k) m.X.push_back(w_.X[static_cast<size_t>(n) * D + k]);
    m.node_origin.push_back(w_.node_origin.empty() ? n : w_.node_origin[n]);
  }
  m.elems.reserve(els.size() * npe);
  for (int e : els) {
    for (int a = 0; a < npe; ++a) m.elems.push_back(nlocal_[enode(e, a)]);
    m.elem_region.push_back(w_.elem_region[e]);
  }
  for (int q : ifs) {
    for (int a = 0; a < 2 * D; ++a) m.ifaces.push_back(nlocal_[inode(q, a)]);
    for (int side = 0; side < 2; ++side)
      m.iface_elems.push_back(elocal_[w_.iface_elems[2 * static_cast<size_t>(q) + side]]);
  }
  if (zoned_) {
    const WholeContact& c = contact_;
    m.pieces = c.pieces;
    m.whole_min_size = c.min_size;
    const size_t nbf = c.outer.size() / D;
    for (size_t f = 0; f < nbf; ++f) {
      // held: its element (and so its nodes)
      const bool held = c.outer_elem[f] >= 0 && elocal_[c.outer_elem[f]] >= 0;
      if (held)
        for (int a = 0; a < D; ++a) m.outer_faces.push_back(nlocal_[c.outer[f * D + a]]);
    }
  }
  if (at_) {
    s.cut_x.resize(nodes.size() * static_cast<size_t>(D));
    for (size_t j = 0; j < nodes.size(); ++j)
      for (int k = 0; k < D; ++k) s.cut_x[j * D + k] = (*at_)[static_cast<size_t>(nodes[j]) * D + k];
  }
}

// The sets: node sets of the own nodes, interface sets of the counted interfaces (local indices).
void Decomposer::local_sets(int p, const PartItems& it, HostMesh& m) const {
  for (const auto& [name, set] : w_.node_sets) {
    m.whole_set_size[name] = static_cast<long>(set.size());
    auto& local = m.node_sets[name];
    for (int n : set)
      if (own_.owner[n] == p) local.push_back(own_.own_index[n]);
  }
  for (const auto& [name, set] : w_.iface_sets) {
    auto& local = m.iface_sets[name];
    for (int q : set)
      if (imark_[q] == p && ilocal_[q] < it.io) local.push_back(ilocal_[q]);
    std::sort(local.begin(), local.end());
  }
}

// The exchange lists: receive lists by owner (ghosts ascending), and the owners' send lists in the
// same order.
void Decomposer::exchange_lists(int p, const PartItems& it, SubMesh& s) {
  const std::vector<int>& nodes = it.nodes;
  std::vector<std::vector<int>> recv(parts_);
  for (size_t j = own_.own_nodes[p].size(); j + s.inert_ghosts < nodes.size(); ++j) {
    const int n = nodes[j], q = own_.owner[n];
    recv[q].push_back(static_cast<int>(j));
    sends_[q][p].push_back(own_.own_index[n]);
  }
  for (int q = 0; q < parts_; ++q)
    if (!recv[q].empty()) {
      s.neighbours.push_back(q);
      s.recv.push_back(std::move(recv[q]));
    }
}

// A part's neighbours: the parts it receives from and those it sends to (where several parts share
// nodes the two need not be the same), and what it sends to each.
PartLists Decomposer::lists(int q) {
  PartLists l;
  l.neighbours = recv_from_[q];
  for (int p = 0; p < parts_; ++p)
    if (!sends_[q][p].empty() && !std::binary_search(recv_from_[q].begin(), recv_from_[q].end(), p))
      l.neighbours.push_back(p);
  std::sort(l.neighbours.begin(), l.neighbours.end());
  for (int p : l.neighbours) l.send.push_back(std::move(sends_[q][p]));
  return l;
}

}  // namespace

void complete_lists(SubMesh& s, PartLists lists) {
  std::vector<std::vector<int>> recv(lists.neighbours.size());
  for (size_t k = 0; k < lists.neighbours.size(); ++k) {
    const auto it = std::lower_bound(s.neighbours.begin(), s.neighbours.end(), lists.neighbours[k]);
    if (it != s.neighbours.end() && *it == lists.neighbours[k]) recv[k] = std::move(s.recv[it - s.neighbours.begin()]);
  }
  s.neighbours = std::move(lists.neighbours);
  s.recv = std::move(recv);
  s.send = std::move(lists.send);
}

std::vector<SubMesh> decompose(const HostMesh& whole, const std::vector<int>& elem_part, int parts,
                               double contact_reach, const std::vector<double>* at) {
  return Decomposer(whole, elem_part, parts, contact_reach, at).run();
}

struct PartBuilder::Impl {
  Decomposer d;
};

PartBuilder::PartBuilder(const HostMesh& whole, const std::vector<int>& elem_part, int parts, double contact_reach,
                         const std::vector<double>* at, int only)
    : impl_(new Impl{Decomposer(whole, elem_part, parts, contact_reach, at, only)}) {}

PartBuilder::~PartBuilder() = default;

SubMesh PartBuilder::part(int p) { return impl_->d.part(p); }

PartLists PartBuilder::lists(int p) { return impl_->d.lists(p); }

}  // namespace fdem
