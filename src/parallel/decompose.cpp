#include "parallel/decompose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "common/error.hpp"
#include "solver/contact_topology.hpp"

namespace fdem {

namespace {

// Compressed rows: the items of key k are items[start[k] .. start[k + 1]).
struct Rows {
  std::vector<int> start, items;
};

// key(j) for j < count, each j listed `per` times (the keys of item j: key(j, a), a < per).
template <class Key>
Rows rows_of(int keys, int count, int per, Key key) {
  Rows r;
  r.start.assign(static_cast<size_t>(keys) + 1, 0);
  for (int j = 0; j < count; ++j)
    for (int a = 0; a < per; ++a) ++r.start[key(j, a) + 1];
  for (int k = 0; k < keys; ++k) r.start[k + 1] += r.start[k];
  r.items.resize(r.start[keys]);
  std::vector<int> fill(r.start.begin(), r.start.end() - 1);
  for (int j = 0; j < count; ++j)
    for (int a = 0; a < per; ++a) r.items[fill[key(j, a)]++] = j;
  return r;
}

// For each part, the elements of the other parts that come within `reach` of one of its own nodes
// (the distance from the node to the element's bounding box, at the positions X), each
// list ascending. Nodes binned in a uniform grid of cells at least `reach` and the mean element
// extent wide (at most about 4 cells per node).
std::vector<std::vector<int>> contact_zones(const HostMesh& whole, const std::vector<double>& X,
                                            const std::vector<int>& elem_part, const std::vector<int>& owner,
                                            int parts, double reach) {
  const int D = whole.dim, npe = D + 1, nn = whole.num_nodes(), ne = whole.num_elems();
  std::vector<std::vector<int>> zone(parts);
  if (ne == 0 || nn == 0) return zone;
  std::vector<double> lo(static_cast<size_t>(ne) * D), hi(static_cast<size_t>(ne) * D);
  double glo[3] = {0, 0, 0}, ghi[3] = {0, 0, 0}, ext = 0;
  for (int k = 0; k < D; ++k) {
    glo[k] = std::numeric_limits<double>::infinity();
    ghi[k] = -glo[k];
  }
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < D; ++k) {
      glo[k] = std::min(glo[k], X[static_cast<size_t>(n) * D + k]);
      ghi[k] = std::max(ghi[k], X[static_cast<size_t>(n) * D + k]);
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
      lo[static_cast<size_t>(e) * D + k] = l;
      hi[static_cast<size_t>(e) * D + k] = h;
      emax = std::max(emax, h - l);
    }
    ext += emax;
  }
  double cell = std::max({reach, ext / ne, 1e-300});
  long dims[3] = {1, 1, 1};
  for (;;) {
    long total = 1;
    for (int k = 0; k < D; ++k) {
      dims[k] = static_cast<long>(std::floor((ghi[k] - glo[k]) / cell)) + 1;
      total *= dims[k];
    }
    if (total <= 4L * nn + 64) break;
    cell *= 1.5;
  }
  auto coord = [&](double x, int k) {
    const long c = static_cast<long>(std::floor((x - glo[k]) / cell));
    return std::clamp<long>(c, 0, dims[k] - 1);
  };
  auto cell_id = [&](const long* c) { return D == 2 ? c[0] + dims[0] * c[1] : c[0] + dims[0] * (c[1] + dims[1] * c[2]); };
  const long ncell = dims[0] * dims[1] * dims[2];
  std::vector<long> start(static_cast<size_t>(ncell) + 1, 0);
  std::vector<long> key(nn);
  for (int n = 0; n < nn; ++n) {
    long c[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) c[k] = coord(X[static_cast<size_t>(n) * D + k], k);
    key[n] = cell_id(c);
    ++start[key[n] + 1];
  }
  for (long c = 0; c < ncell; ++c) start[c + 1] += start[c];
  std::vector<int> items(nn);
  {
    std::vector<long> fill(start.begin(), start.end() - 1);
    for (int n = 0; n < nn; ++n) items[fill[key[n]]++] = n;
  }
  std::vector<int> stamp(parts, -1);
  const double r2 = reach * reach;
  for (int e = 0; e < ne; ++e) {
    const double* l = &lo[static_cast<size_t>(e) * D];
    const double* h = &hi[static_cast<size_t>(e) * D];
    long c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) {
      c0[k] = coord(l[k] - reach, k);
      c1[k] = coord(h[k] + reach, k);
    }
    long c[3] = {0, 0, 0};
    for (c[2] = c0[2]; c[2] <= c1[2]; ++c[2])
      for (c[1] = c0[1]; c[1] <= c1[1]; ++c[1])
        for (c[0] = c0[0]; c[0] <= c1[0]; ++c[0]) {
          const long id = cell_id(c);
          for (long j = start[id]; j < start[id + 1]; ++j) {
            const int n = items[j], p = owner[n];
            if (p == elem_part[e] || stamp[p] == e) continue;
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

}  // namespace

std::vector<SubMesh> decompose(const HostMesh& whole, const std::vector<int>& elem_part, int parts,
                               double contact_reach, const std::vector<double>* at) {
  const int D = whole.dim, npe = D + 1, nn = whole.num_nodes(), ne = whole.num_elems(),
            ni = whole.num_ifaces();
  if (parts < 1) throw InputError("decompose: parts must be at least 1 (got " + std::to_string(parts) + ")");
  if (static_cast<int>(elem_part.size()) != ne)
    throw InputError("decompose: " + std::to_string(elem_part.size()) + " part ids for " +
                     std::to_string(ne) + " elements");
  for (int e = 0; e < ne; ++e)
    if (elem_part[e] < 0 || elem_part[e] >= parts)
      throw InputError("decompose: element " + std::to_string(e) + " has part " +
                       std::to_string(elem_part[e]) + ", outside [0, " + std::to_string(parts - 1) + "]");
  if (whole.owned_nodes >= 0) throw InputError("decompose: the mesh is already one part of a decomposition");
  auto enode = [&](int e, int a) { return whole.elems[static_cast<size_t>(e) * npe + a]; };
  auto inode = [&](int q, int a) { return whole.ifaces[static_cast<size_t>(q) * 2 * D + a]; };

  // node owners: the part of the first element holding the node (orphan nodes: part 0)
  std::vector<int> owner(nn, -1);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a)
      if (owner[enode(e, a)] < 0) owner[enode(e, a)] = elem_part[e];
  for (int& o : owner)
    if (o < 0) o = 0;
  // own items per part (ascending) and each node's index among its owner's own nodes
  std::vector<std::vector<int>> own_nodes(parts), own_elems(parts);
  std::vector<int> own_index(nn);
  for (int n = 0; n < nn; ++n) {
    own_index[n] = static_cast<int>(own_nodes[owner[n]].size());
    own_nodes[owner[n]].push_back(n);
  }
  for (int e = 0; e < ne; ++e) own_elems[elem_part[e]].push_back(e);
  const Rows n2e = rows_of(nn, ne, npe, enode);
  const Rows n2i = rows_of(nn, ni, 2 * D, inode);
  // contact: each part's zone, the whole mesh's outer faces and connected pieces
  const bool zoned = contact_reach > 0;
  if (zoned && !std::isfinite(contact_reach))
    throw InputError("decompose: the contact reach must be finite (got " + std::to_string(contact_reach) + ")");
  if (at && at->size() != whole.X.size())
    throw InputError("decompose: " + std::to_string(at->size()) + " position values for " +
                     std::to_string(whole.X.size()));
  const std::vector<std::vector<int>> zones =
      zoned ? contact_zones(whole, at ? *at : whole.X, elem_part, owner, parts, contact_reach)
            : std::vector<std::vector<int>>();
  const std::vector<int> outer = zoned ? boundary_faces(whole) : std::vector<int>();
  std::vector<int> outer_elem(outer.size() / std::max(D, 1), -1);  // the element of each outer face
  for (size_t f = 0; f < outer_elem.size(); ++f) {
    const int n0 = outer[f * D];
    for (int k = n2e.start[n0]; k < n2e.start[n0 + 1] && outer_elem[f] < 0; ++k) {
      const int e = n2e.items[k];
      int found = 0;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < npe; ++b) found += enode(e, b) == outer[f * D + a];
      if (found == D) outer_elem[f] = e;
    }
  }
  const int pieces = zoned ? count_bodies(whole) : -1;
  const double min_size = zoned ? mesh_quality(whole).min_size : 0.0;

  std::vector<SubMesh> out(parts);
  std::vector<int> emark(ne, -1), imark(ni, -1), nmark(nn, -1);  // stamped with the part
  std::vector<int> elocal(ne, -1), nlocal(nn, -1), ilocal(ni, -1);
  // sends[q][p]: q's own local nodes that p needs, in p's order
  std::vector<std::vector<std::vector<int>>> sends(parts, std::vector<std::vector<int>>(parts));
  for (int p = 0; p < parts; ++p) {
    SubMesh& s = out[p];
    s.part = p;
    s.parts = parts;
    s.whole_nodes = nn;
    s.whole_elems = ne;
    s.whole_ifaces = whole.num_ifaces();
    s.contact_reach = contact_reach;
    std::vector<int> ifs, els, nds;
    auto add_ifaces_at = [&](int n) {
      for (int k = n2i.start[n]; k < n2i.start[n + 1]; ++k)
        if (imark[n2i.items[k]] != p) {
          imark[n2i.items[k]] = p;
          ifs.push_back(n2i.items[k]);
        }
    };
    auto add_elem = [&](int e) {
      if (emark[e] != p) {
        emark[e] = p;
        els.push_back(e);
      }
    };
    for (int e : own_elems[p]) add_elem(e);
    for (int n : own_nodes[p])
      for (int k = n2e.start[n]; k < n2e.start[n + 1]; ++k) add_elem(n2e.items[k]);
    if (zoned) {  // the contact zone, and the interfaces at every node held so far
      for (int e : zones[p]) add_elem(e);
      for (size_t j = 0; j < els.size(); ++j)
        for (int a = 0; a < npe; ++a) add_ifaces_at(enode(els[j], a));
    } else {
      for (int n : own_nodes[p]) add_ifaces_at(n);
    }
    for (int q : ifs)
      for (int side = 0; side < 2; ++side) add_elem(whole.iface_elems[2 * static_cast<size_t>(q) + side]);
    const size_t e1 = els.size();
    for (size_t j = 0; j < e1; ++j)  // the closure: every element at a node of E1
      for (int a = 0; a < npe; ++a) {
        const int n = enode(els[j], a);
        for (int k = n2e.start[n]; k < n2e.start[n + 1]; ++k) add_elem(n2e.items[k]);
      }
    for (int n : own_nodes[p]) nmark[n] = p;  // orphans included
    for (int e : els)
      for (int a = 0; a < npe; ++a)
        if (nmark[enode(e, a)] != p) {
          nmark[enode(e, a)] = p;
          nds.push_back(enode(e, a));
        }
    // Elements: own, then the ghosts at an own node (their bulk forces count), then the other
    // ghosts (sides of interfaces, masses: no bulk force). Each group in the whole mesh's order.
    auto eclass = [&](int e) {
      if (elem_part[e] == p) return 0;
      for (int a = 0; a < npe; ++a)
        if (owner[enode(e, a)] == p) return 1;
      return 2;
    };
    std::vector<std::pair<int, int>> keyed;
    for (int e : els) keyed.push_back({eclass(e), e});
    std::sort(keyed.begin(), keyed.end());
    int eo = 0, eb = 0;
    for (size_t j = 0; j < keyed.size(); ++j) {
      els[j] = keyed[j].second;
      eo += keyed[j].first == 0;
      eb += keyed[j].first <= 1;
    }
    // Ghost nodes: those a step reads (of the elements with a bulk force, of the interfaces) are
    // exchanged; the others (only of elements without one) never move from where they start.
    // (nlocal as scratch: 1 for a node a step reads)
    for (int j = 0; j < eb; ++j)
      for (int a = 0; a < npe; ++a) nlocal[enode(els[j], a)] = 1;
    for (int q : ifs)
      for (int a = 0; a < 2 * D; ++a) nlocal[inode(q, a)] = 1;
    if (zoned)  // contact reads every ghost (the faces and nodes of the zone, their velocities)
      for (int n : nds) nlocal[n] = 1;
    std::sort(nds.begin(), nds.end(), [&](int a, int b) {
      const bool ra = nlocal[a] == 1, rb = nlocal[b] == 1;
      return ra != rb ? ra : a < b;
    });
    for (int n : nds) s.inert_ghosts += nlocal[n] != 1;
    for (int n : nds) nlocal[n] = -1;
    for (int n : own_nodes[p]) nlocal[n] = -1;
    std::vector<int> nodes = own_nodes[p];
    nodes.insert(nodes.end(), nds.begin(), nds.end());
    // Interfaces: the counted ones, then the others; each group in order of its side-A element's
    // local index (the force pass's chunks), then the whole mesh's order.
    for (size_t j = 0; j < els.size(); ++j) elocal[els[j]] = static_cast<int>(j);
    std::sort(ifs.begin(), ifs.end(), [&](int a, int b) {
      const bool ca = owner[inode(a, 0)] == p, cb = owner[inode(b, 0)] == p;
      if (ca != cb) return ca;
      const int la = elocal[whole.iface_elems[2 * static_cast<size_t>(a)]];
      const int lb = elocal[whole.iface_elems[2 * static_cast<size_t>(b)]];
      return la != lb ? la < lb : a < b;
    });
    const int io =
        static_cast<int>(std::count_if(ifs.begin(), ifs.end(), [&](int q) { return owner[inode(q, 0)] == p; }));

    HostMesh& m = s.mesh;
    m.dim = D;
    m.region_names = whole.region_names;
    m.warnings = whole.warnings;
    m.bodies = whole.bodies;
    m.owned_nodes = static_cast<int>(own_nodes[p].size());
    m.owned_elems = eo;
    m.owned_ifaces = io;
    m.bulk_elems = eb;
    for (size_t j = 0; j < nodes.size(); ++j) nlocal[nodes[j]] = static_cast<int>(j);
    for (size_t j = 0; j < els.size(); ++j) elocal[els[j]] = static_cast<int>(j);
    for (size_t j = 0; j < ifs.size(); ++j) ilocal[ifs[j]] = static_cast<int>(j);
    m.X.reserve(nodes.size() * D);
    for (int n : nodes) {
      for (int k = 0; k < D; ++k) m.X.push_back(whole.X[static_cast<size_t>(n) * D + k]);
      m.node_origin.push_back(whole.node_origin.empty() ? n : whole.node_origin[n]);
    }
    m.elems.reserve(els.size() * npe);
    for (int e : els) {
      for (int a = 0; a < npe; ++a) m.elems.push_back(nlocal[enode(e, a)]);
      m.elem_region.push_back(whole.elem_region[e]);
    }
    for (int q : ifs) {
      for (int a = 0; a < 2 * D; ++a) m.ifaces.push_back(nlocal[inode(q, a)]);
      for (int side = 0; side < 2; ++side)
        m.iface_elems.push_back(elocal[whole.iface_elems[2 * static_cast<size_t>(q) + side]]);
    }
    if (zoned) {
      m.pieces = pieces;
      m.whole_min_size = min_size;
      const size_t nbf = outer.size() / D;
      for (size_t f = 0; f < nbf; ++f) {
        const bool held = outer_elem[f] >= 0 && elocal[outer_elem[f]] >= 0;  // its element (and so its nodes)
        if (held)
          for (int a = 0; a < D; ++a) m.outer_faces.push_back(nlocal[outer[f * D + a]]);
      }
    }
    for (const auto& [name, set] : whole.node_sets) {
      m.whole_set_size[name] = static_cast<long>(set.size());
      auto& local = m.node_sets[name];
      for (int n : set)
        if (owner[n] == p) local.push_back(own_index[n]);
    }
    for (const auto& [name, set] : whole.iface_sets) {
      auto& local = m.iface_sets[name];
      for (int q : set)
        if (imark[q] == p && ilocal[q] < io) local.push_back(ilocal[q]);
      std::sort(local.begin(), local.end());
    }
    s.node_global = nodes;
    if (at) {
      s.cut_x.resize(nodes.size() * static_cast<size_t>(D));
      for (size_t j = 0; j < nodes.size(); ++j)
        for (int k = 0; k < D; ++k) s.cut_x[j * D + k] = (*at)[static_cast<size_t>(nodes[j]) * D + k];
    }
    s.elem_global = els;
    s.iface_global = ifs;
    // receive lists by owner (ghosts ascending), and the owners' send lists in the same order
    std::vector<std::vector<int>> recv(parts);
    for (size_t j = own_nodes[p].size(); j + s.inert_ghosts < nodes.size(); ++j) {
      const int n = nodes[j], q = owner[n];
      recv[q].push_back(static_cast<int>(j));
      sends[q][p].push_back(own_index[n]);
    }
    for (int q = 0; q < parts; ++q)
      if (!recv[q].empty()) {
        s.neighbours.push_back(q);
        s.recv.push_back(std::move(recv[q]));
      }
    for (int n : nodes) nlocal[n] = -1;
    for (int e : els) elocal[e] = -1;
    for (int q : ifs) ilocal[q] = -1;
  }
  // a part's neighbours: the parts it receives from and those it sends to (where several parts
  // share nodes the two need not be the same)
  for (int q = 0; q < parts; ++q) {
    SubMesh& s = out[q];
    std::vector<int> nb = s.neighbours;
    for (int p = 0; p < parts; ++p)
      if (!sends[q][p].empty() && !std::binary_search(s.neighbours.begin(), s.neighbours.end(), p))
        nb.push_back(p);
    std::sort(nb.begin(), nb.end());
    std::vector<std::vector<int>> recv(nb.size()), send(nb.size());
    for (size_t k = 0; k < nb.size(); ++k) {
      const auto it = std::lower_bound(s.neighbours.begin(), s.neighbours.end(), nb[k]);
      if (it != s.neighbours.end() && *it == nb[k]) recv[k] = std::move(s.recv[it - s.neighbours.begin()]);
      send[k] = std::move(sends[q][nb[k]]);
    }
    s.neighbours = nb;
    s.recv = std::move(recv);
    s.send = std::move(send);
  }
  return out;
}

}  // namespace fdem
