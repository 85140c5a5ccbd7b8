// Uniform refinement (refine.hpp): the coarse mesh's numbering of edges and faces, the lattice
// point of a coarse element as a global node id, the red refinement of one coarse element on the
// lattice, and the node and face sets of the refined mesh. One file: every phase reads the same
// lattice conventions (integer barycentric coordinates b_0..b_dim summing to m = 2^levels).
#include "mesh/refine.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>

#include "common/error.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {
namespace {

using mesh_detail::face_node;
using Lattice = std::array<int, 4>;  // integer barycentric coordinates (b_3 = 0 in 2D)
using Simplex = std::array<Lattice, 4>;

constexpr int kEdges2[3][2] = {{0, 1}, {1, 2}, {2, 0}};
constexpr int kEdges3[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

int edges_per_elem(int dim) { return dim == 2 ? 3 : 6; }
const int* local_edge(int dim, int k) { return dim == 2 ? kEdges2[k] : kEdges3[k]; }

// Index of local edge (a, b) (either order) in the element's edge list.
int local_edge_index(int dim, int a, int b) {
  for (int k = 0; k < edges_per_elem(dim); ++k) {
    const int* e = local_edge(dim, k);
    if ((e[0] == a && e[1] == b) || (e[0] == b && e[1] == a)) return k;
  }
  return -1;
}

// Lattice points strictly inside a triangle (all three coordinates >= 1) and a tetrahedron (all
// four >= 1) of side m, and the index of one among them from its last coordinates less one.
std::int64_t face_points(int m) { return static_cast<std::int64_t>(m - 1) * (m - 2) / 2; }
std::int64_t interior_points(int m) { return static_cast<std::int64_t>(m - 1) * (m - 2) * (m - 3) / 6; }
// (p, q) >= 0 with p + q <= L: row p holds L - p + 1 points.
std::int64_t tri_index(int p, int q, int L) {
  return static_cast<std::int64_t>(p) * (L + 1) - static_cast<std::int64_t>(p) * (p - 1) / 2 + q;
}
// (p, q, r) >= 0 with p + q + r <= L: layer p holds the triangle of side L - p.
std::int64_t tet_index(int p, int q, int r, int L) {
  std::int64_t idx = 0;
  for (int a = 0; a < p; ++a) idx += static_cast<std::int64_t>(L - a + 1) * (L - a + 2) / 2;
  return idx + tri_index(q, r, L - p);
}

using Key2 = std::array<int, 2>;
using Key3 = std::array<int, 3>;

template <class K>
int find_key(const std::vector<K>& sorted, const K& k) {
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), k);
  return it != sorted.end() && *it == k ? static_cast<int>(it - sorted.begin()) : -1;
}

Key2 edge_key(int a, int b) { return a < b ? Key2{a, b} : Key2{b, a}; }
Key3 face_key3(int a, int b, int c) {
  Key3 k{a, b, c};
  mesh_detail::sort_face_key(k, 3);
  return k;
}

// ---------------------------------------------------------------------------------------------
// The coarse topology

// Sorted unique keys of the elements' edges (or faces), each element's index list into them, and
// how many elements hold each.
template <class K, class KeyOf>
void number_entities(int ne, int per_elem, KeyOf key_of, std::vector<K>& keys, std::vector<int>& elem_ids,
                     std::vector<int>* uses) {
  std::vector<std::pair<K, int>> all(static_cast<std::size_t>(ne) * per_elem);
  for (int e = 0; e < ne; ++e)
    for (int k = 0; k < per_elem; ++k) all[static_cast<std::size_t>(e) * per_elem + k] = {key_of(e, k), e * per_elem + k};
  std::sort(all.begin(), all.end());
  keys.clear();
  elem_ids.assign(all.size(), -1);
  if (uses) uses->clear();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i == 0 || all[i].first != all[i - 1].first) {
      keys.push_back(all[i].first);
      if (uses) uses->push_back(0);
    }
    elem_ids[all[i].second] = static_cast<int>(keys.size()) - 1;
    if (uses) ++uses->back();
  }
}

struct Facet {  // a boundary or face-set facet of the coarse mesh, sorted key
  int index;    // edge index (2D) or face index (3D)
  bool boundary;
};

std::array<double, 3> node_point(const HostMesh& m, int n) {
  std::array<double, 3> p{0, 0, 0};
  for (int k = 0; k < m.dim; ++k) p[k] = m.X[static_cast<std::size_t>(n) * m.dim + k];
  return p;
}

// The curved surface a boundary facet lies on: every vertex within 1e-6 R of it and the facet's
// normal within 60 degrees of the radial direction at its centroid (a flat face whose corners
// happen to lie on the sphere is not on it). -1: none.
int facet_surface(const HostMesh& m, const int* v, const std::vector<CurvedSurface>& surfaces) {
  const int d = m.dim;
  std::array<double, 3> x[3];
  for (int k = 0; k < d; ++k) x[k] = node_point(m, v[k]);
  std::array<double, 3> n{0, 0, 0}, c{0, 0, 0};
  if (d == 2) {
    n = {x[1][1] - x[0][1], -(x[1][0] - x[0][0]), 0};
  } else {
    const std::array<double, 3> a{x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]};
    const std::array<double, 3> b{x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]};
    n = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  }
  for (int k = 0; k < d; ++k)
    for (int j = 0; j < 3; ++j) c[j] += x[k][j] / d;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const CurvedSurface& S = surfaces[s];
    bool on = true;
    for (int k = 0; k < d && on; ++k) {
      double r2 = 0;
      for (int j = 0; j < 3; ++j) r2 += (x[k][j] - S.centre[j]) * (x[k][j] - S.centre[j]);
      on = std::abs(std::sqrt(r2) - S.radius) <= 1e-6 * S.radius;
    }
    if (!on) continue;
    double nn = 0, rr = 0, nr = 0;
    for (int j = 0; j < 3; ++j) {
      const double r = c[j] - S.centre[j];
      nn += n[j] * n[j];
      rr += r * r;
      nr += n[j] * r;
    }
    if (nn > 0 && rr > 0 && std::abs(nr) > 0.5 * std::sqrt(nn * rr)) return static_cast<int>(s);
  }
  return -1;
}

// The boundary facets (held by one element) and the facets of the face sets, by facet index.
std::vector<Facet> collect_facets(const HostMesh& m, const CoarseTopology& t, const std::vector<int>& uses) {
  std::vector<char> listed(uses.size(), 0);
  std::vector<Facet> out;
  for (std::size_t f = 0; f < uses.size(); ++f)
    if (uses[f] == 1) {
      out.push_back({static_cast<int>(f), true});
      listed[f] = 1;
    }
  for (const auto& [name, facets] : m.face_sets)
    for (std::size_t i = 0; i + m.dim <= facets.size(); i += m.dim) {
      const int f = m.dim == 2 ? find_key(t.edges, edge_key(facets[i], facets[i + 1]))
                               : find_key(t.faces, face_key3(facets[i], facets[i + 1], facets[i + 2]));
      if (f >= 0 && !listed[f]) {
        out.push_back({f, false});
        listed[f] = 1;
      }
    }
  return out;
}

const int* facet_vertices(const CoarseTopology& t, int f) { return t.dim == 2 ? t.edges[f].data() : t.faces[f].data(); }

// Which edges and faces carry the new nodes of each node set (refine.hpp): a set named like a face
// set takes that face set's facets (and their edges); another set every boundary or face-set facet
// whose vertices are all in it, and in 3D every edge of such facets with both ends in it.
void assign_sets(const HostMesh& m, CoarseTopology& t, const std::vector<Facet>& facets) {
  const int d = m.dim;
  for (const auto& [name, nodes] : m.node_sets) {
    if (name == "all") continue;
    std::vector<char> in(m.num_nodes(), 0);
    for (int n : nodes) in[n] = 1;
    std::vector<char> on_edge(t.edges.size(), 0), on_face(t.faces.size(), 0);
    auto mark_facet = [&](int f) {
      const int* v = facet_vertices(t, f);
      if (d == 2) {
        on_edge[f] = 1;
        return;
      }
      on_face[f] = 1;
      for (int k = 0; k < 3; ++k) on_edge[find_key(t.edges, edge_key(v[k], v[(k + 1) % 3]))] = 1;
    };
    const auto fs = m.face_sets.find(name);
    if (fs != m.face_sets.end()) {
      for (std::size_t i = 0; i + d <= fs->second.size(); i += d) {
        const int* v = &fs->second[i];
        const int f = d == 2 ? find_key(t.edges, edge_key(v[0], v[1])) : find_key(t.faces, face_key3(v[0], v[1], v[2]));
        if (f >= 0) mark_facet(f);
      }
    } else {
      for (const Facet& F : facets) {
        const int* v = facet_vertices(t, F.index);
        int count = 0;
        for (int k = 0; k < d; ++k) count += in[v[k]];
        if (count == d) mark_facet(F.index);
        if (d == 3)
          for (int k = 0; k < 3; ++k)
            if (in[v[k]] && in[v[(k + 1) % 3]]) on_edge[find_key(t.edges, edge_key(v[k], v[(k + 1) % 3]))] = 1;
      }
    }
    t.set_edges.emplace_back();
    t.set_faces.emplace_back();
    for (std::size_t e = 0; e < on_edge.size(); ++e)
      if (on_edge[e]) t.set_edges.back().push_back(static_cast<int>(e));
    for (std::size_t f = 0; f < on_face.size(); ++f)
      if (on_face[f]) t.set_faces.back().push_back(static_cast<int>(f));
  }
}

// The surface of each boundary facet, and in 3D of the edges of such facets.
void assign_surfaces(const HostMesh& m, CoarseTopology& t, const std::vector<Facet>& facets,
                     const std::vector<CurvedSurface>& surfaces) {
  t.edge_surface.assign(t.edges.size(), -1);
  t.face_surface.assign(t.faces.size(), -1);
  if (surfaces.empty()) return;
  for (const Facet& F : facets) {
    if (!F.boundary) continue;
    // the facet with its element's orientation does not matter for the test (|n . r|)
    const int* v = facet_vertices(t, F.index);
    const int s = facet_surface(m, v, surfaces);
    if (s < 0) continue;
    if (m.dim == 2) {
      t.edge_surface[F.index] = s;
      continue;
    }
    t.face_surface[F.index] = s;
    for (int k = 0; k < 3; ++k) t.edge_surface[find_key(t.edges, edge_key(v[k], v[(k + 1) % 3]))] = s;
  }
}

}  // namespace

std::vector<CurvedSurface> curved_surfaces(const MeshSpec& spec, int dim) {
  std::vector<CurvedSurface> out;
  const bool disc = spec.kind == "disc" || (spec.kind == "grains" && spec.shape == "disc");
  if ((dim == 2 && disc) || (dim == 3 && spec.kind == "sphere"))
    out.push_back({spec.origin, spec.radius});
  if (dim == 2)
    for (auto& s : out) s.centre[2] = 0;
  return out;
}

double refine_factor(int dim, int levels) { return std::pow(dim == 2 ? 4.0 : 8.0, levels); }

CoarseTopology coarse_topology(const HostMesh& m, int levels, const std::vector<CurvedSurface>& surfaces) {
  if (levels < 0 || levels > 10)
    throw InputError("mesh.refine = " + std::to_string(levels) + " is out of range (allowed: 0 to 10)");
  if (m.num_elems() == 0) throw InputError("mesh.refine: the mesh has no element");
  CoarseTopology t;
  const int d = m.dim, npe = d + 1, ne = m.num_elems();
  t.dim = d;
  t.levels = levels;
  t.m = 1 << levels;
  t.num_vertices = m.num_nodes();
  const int* el = m.elems.data();
  std::vector<int> uses;
  number_entities<Key2>(
      ne, edges_per_elem(d),
      [&](int e, int k) {
        const int* le = local_edge(d, k);
        return edge_key(el[e * npe + le[0]], el[e * npe + le[1]]);
      },
      t.edges, t.elem_edges, d == 2 ? &uses : nullptr);
  if (d == 3)
    number_entities<Key3>(
        ne, 4,
        [&](int e, int f) {
          return face_key3(el[e * npe + face_node(3, f, 0)], el[e * npe + face_node(3, f, 1)],
                           el[e * npe + face_node(3, f, 2)]);
        },
        t.faces, t.elem_faces, &uses);
  {  // the element across each facet
    const std::vector<int>& facet_of = d == 2 ? t.elem_edges : t.elem_faces;
    std::vector<int> first(d == 2 ? t.edges.size() : t.faces.size(), -1);
    t.elem_neighbours.assign(static_cast<std::size_t>(ne) * npe, -1);
    for (int e = 0; e < ne; ++e)
      for (int f = 0; f < npe; ++f) {
        int& at = first[facet_of[static_cast<std::size_t>(e) * npe + f]];
        if (at < 0) {
          at = e * npe + f;
        } else {
          t.elem_neighbours[static_cast<std::size_t>(e) * npe + f] = at / npe;
          t.elem_neighbours[static_cast<std::size_t>(at)] = e;
        }
      }
  }
  const std::vector<Facet> facets = collect_facets(m, t, uses);
  t.surfaces = surfaces;
  assign_surfaces(m, t, facets, surfaces);
  assign_sets(m, t, facets);
  const int mm = t.m;
  t.edge_base = t.num_vertices;
  t.face_base = t.edge_base + static_cast<std::int64_t>(t.edges.size()) * (mm - 1);
  t.interior_base = t.face_base + static_cast<std::int64_t>(t.faces.size()) * face_points(mm);
  t.num_fine_nodes = t.interior_base + static_cast<std::int64_t>(ne) * (d == 2 ? face_points(mm) : interior_points(mm));
  return t;
}

namespace {

// ---------------------------------------------------------------------------------------------
// One coarse element on the lattice

// The global id of a lattice point of coarse element e, and the coarse vertices (sorted) with
// their coordinates that place it; `entity` says where it lies: 0 vertex, 1 edge, 2 face (a 3D
// face or a 2D element's interior), 3 a tetrahedron's interior; `index` is that entity's index.
struct LatticeNode {
  std::int64_t gid = 0;
  int entity = 0, index = 0, count = 0;
  int vert[4] = {0, 0, 0, 0}, coord[4] = {0, 0, 0, 0};
};

LatticeNode lattice_node(const HostMesh& m, const CoarseTopology& t, int e, const Lattice& b) {
  const int d = m.dim, npe = d + 1, mm = t.m;
  const int* v = &m.elems[static_cast<std::size_t>(e) * npe];
  LatticeNode n;
  int local[4];
  for (int a = 0; a < npe; ++a)
    if (b[a] > 0) {
      local[n.count] = a;
      n.vert[n.count] = v[a];
      n.coord[n.count] = b[a];
      ++n.count;
    }
  for (int i = 1; i < n.count; ++i)  // sort by vertex id (insertion: at most 4)
    for (int j = i; j > 0 && n.vert[j] < n.vert[j - 1]; --j) {
      std::swap(n.vert[j], n.vert[j - 1]);
      std::swap(n.coord[j], n.coord[j - 1]);
    }
  n.entity = n.count - 1;
  if (n.count == 1) {
    n.gid = n.vert[0];
  } else if (n.count == 2) {
    n.index = t.elem_edges[static_cast<std::size_t>(e) * edges_per_elem(d) + local_edge_index(d, local[0], local[1])];
    n.gid = t.edge_base + static_cast<std::int64_t>(n.index) * (mm - 1) + (n.coord[1] - 1);
  } else if (n.count == 3) {
    const std::int64_t idx = tri_index(n.coord[1] - 1, n.coord[2] - 1, mm - 3);
    if (d == 3) {
      int missing = 0;
      while (b[missing] > 0) ++missing;
      n.index = t.elem_faces[static_cast<std::size_t>(e) * 4 + missing];
      n.gid = t.face_base + static_cast<std::int64_t>(n.index) * face_points(mm) + idx;
    } else {
      n.index = e;
      n.gid = t.interior_base + static_cast<std::int64_t>(e) * face_points(mm) + idx;
    }
  } else {
    n.index = e;
    n.gid = t.interior_base + static_cast<std::int64_t>(e) * interior_points(mm) +
            tet_index(n.coord[1] - 1, n.coord[2] - 1, n.coord[3] - 1, mm - 4);
  }
  return n;
}

// Where a lattice node lies: its coarse vertices weighted in the order of their ids (so that every
// element that holds it computes the same bits), moved onto the curved surface of its edge or face.
std::array<double, 3> lattice_point(const HostMesh& m, const CoarseTopology& t, const LatticeNode& n) {
  std::array<double, 3> x{0, 0, 0};
  for (int k = 0; k < m.dim; ++k) {
    double s = 0;
    for (int j = 0; j < n.count; ++j) s += n.coord[j] * m.X[static_cast<std::size_t>(n.vert[j]) * m.dim + k];
    x[k] = s / t.m;
  }
  int surf = -1;
  if (n.entity == 1) surf = t.edge_surface[n.index];
  if (n.entity == 2 && m.dim == 3) surf = t.face_surface[n.index];
  if (surf >= 0) {
    const CurvedSurface& S = t.surfaces[surf];
    double r2 = 0;
    for (int k = 0; k < m.dim; ++k) r2 += (x[k] - S.centre[k]) * (x[k] - S.centre[k]);
    const double scale = S.radius / std::sqrt(r2);
    for (int k = 0; k < m.dim; ++k) x[k] = S.centre[k] + (x[k] - S.centre[k]) * scale;
  }
  return x;
}

Lattice mid(const Lattice& a, const Lattice& b) {
  return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2, (a[3] + b[3]) / 2};
}

// Sign of the simplex in lattice coordinates (b_1..b_dim): the coarse element's orientation.
long long lattice_orientation(const Simplex& s, int dim) {
  if (dim == 2) {
    const long long a0 = s[1][1] - s[0][1], a1 = s[1][2] - s[0][2];
    const long long c0 = s[2][1] - s[0][1], c1 = s[2][2] - s[0][2];
    return a0 * c1 - a1 * c0;
  }
  long long u[3][3];
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) u[r][k] = s[r + 1][k + 1] - s[0][k + 1];
  return u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[2][1]) - u[0][1] * (u[1][0] * u[2][2] - u[1][2] * u[2][0]) +
         u[0][2] * (u[1][0] * u[2][1] - u[1][1] * u[2][0]);
}

void orient(Simplex& s, int dim) {
  if (lattice_orientation(s, dim) < 0) std::swap(s[dim - 1], s[dim]);
}

// The children of one simplex, in a fixed order: the corners, then (3D) the inner octahedron's four
// tetrahedra around its shortest diagonal (by the linear positions `len2` measures; ties to the
// first), or (2D) the middle triangle.
template <class Len2>
void red_children(const Simplex& s, int dim, Len2 len2, std::vector<Simplex>& out) {
  if (dim == 2) {
    const Lattice m01 = mid(s[0], s[1]), m12 = mid(s[1], s[2]), m02 = mid(s[0], s[2]);
    Simplex c[4] = {{s[0], m01, m02, {}}, {m01, s[1], m12, {}}, {m02, m12, s[2], {}}, {m01, m12, m02, {}}};
    for (Simplex& x : c) {
      orient(x, 2);
      out.push_back(x);
    }
    return;
  }
  Lattice mm[4][4];
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) mm[a][b] = mm[b][a] = mid(s[a], s[b]);
  const Simplex corners[4] = {{s[0], mm[0][1], mm[0][2], mm[0][3]},
                              {mm[0][1], s[1], mm[1][2], mm[1][3]},
                              {mm[0][2], mm[1][2], s[2], mm[2][3]},
                              {mm[0][3], mm[1][3], mm[2][3], s[3]}};
  for (Simplex x : corners) {
    orient(x, 3);
    out.push_back(x);
  }
  // diagonals (01-23), (02-13), (03-12); the ring of the other four around each
  const Lattice diag[3][2] = {{mm[0][1], mm[2][3]}, {mm[0][2], mm[1][3]}, {mm[0][3], mm[1][2]}};
  const Lattice ring[3][4] = {{mm[0][2], mm[1][2], mm[1][3], mm[0][3]},
                              {mm[0][1], mm[1][2], mm[2][3], mm[0][3]},
                              {mm[0][1], mm[1][3], mm[2][3], mm[0][2]}};
  int best = 0;
  double lbest = len2(diag[0][0], diag[0][1]);
  for (int k = 1; k < 3; ++k) {
    const double l = len2(diag[k][0], diag[k][1]);
    if (l < lbest * (1 - 1e-12)) {
      best = k;
      lbest = l;
    }
  }
  for (int j = 0; j < 4; ++j) {
    Simplex x{diag[best][0], diag[best][1], ring[best][j], ring[best][(j + 1) % 4]};
    orient(x, 3);
    out.push_back(x);
  }
}

// The fine simplices of coarse element e, in the order of their global ids.
std::vector<Simplex> refine_one(const HostMesh& m, const CoarseTopology& t, int e) {
  const int d = m.dim, npe = d + 1;
  const int* v = &m.elems[static_cast<std::size_t>(e) * npe];
  auto len2 = [&](const Lattice& a, const Lattice& b) {
    double s = 0;
    for (int k = 0; k < d; ++k) {
      double x = 0;
      for (int j = 0; j < npe; ++j) x += (a[j] - b[j]) * m.X[static_cast<std::size_t>(v[j]) * d + k];
      s += x * x;
    }
    return s;
  };
  Simplex root{};
  for (int a = 0; a < npe; ++a) root[a][a] = t.m;
  std::vector<Simplex> level{root}, next;
  for (int l = 0; l < t.levels; ++l) {
    next.clear();
    for (const Simplex& s : level) red_children(s, d, len2, next);
    level.swap(next);
  }
  return level;
}

// ---------------------------------------------------------------------------------------------
// The part's node sets and face sets

struct SetMaps {
  std::vector<std::string> names;         // node sets but "all", in map order
  std::vector<std::vector<char>> vertex;  // per set: coarse node in it
  std::vector<std::vector<char>> edge, face;
};

SetMaps set_maps(const HostMesh& m, const CoarseTopology& t) {
  SetMaps s;
  std::size_t i = 0;
  for (const auto& [name, nodes] : m.node_sets) {
    if (name == "all") continue;
    s.names.push_back(name);
    s.vertex.emplace_back(m.num_nodes(), 0);
    for (int n : nodes) s.vertex.back()[n] = 1;
    s.edge.emplace_back(t.edges.size(), 0);
    for (int e : t.set_edges[i]) s.edge.back()[e] = 1;
    s.face.emplace_back(t.faces.size(), 0);
    for (int f : t.set_faces[i]) s.face.back()[f] = 1;
    ++i;
  }
  return s;
}

bool node_in_set(const SetMaps& s, std::size_t k, const LatticeNode& n, int dim) {
  if (n.entity == 0) return s.vertex[k][n.vert[0]];
  if (n.entity == 1) return s.edge[k][n.index];
  if (n.entity == 2 && dim == 3) return s.face[k][n.index];
  return false;
}

// The global id of a lattice point of a coarse facet (its vertices `v` in the set's order, its
// coordinates `b` in the same order): through an element that holds the facet.
std::int64_t facet_gid(const HostMesh& m, const CoarseTopology& t, int elem, const int* v, const int* b) {
  const int npe = m.dim + 1;
  Lattice lb{0, 0, 0, 0};
  for (int k = 0; k < m.dim; ++k)
    for (int a = 0; a < npe; ++a)
      if (m.elems[static_cast<std::size_t>(elem) * npe + a] == v[k]) lb[a] = b[k];
  return lattice_node(m, t, elem, lb).gid;
}

// Facets of the coarse face sets cut into the fine ones, on the part's elements only.
void refine_face_sets(const HostMesh& m, const CoarseTopology& t, const std::vector<int>& coarse_elems,
                      const std::unordered_map<std::int64_t, int>& local, HostMesh& out) {
  const int d = m.dim, npe = d + 1, mm = t.m;
  // facet key -> an element of the part that holds it
  std::unordered_map<std::int64_t, int> holder;
  auto facet_of = [&](int e, int f) {
    return d == 2 ? t.elem_edges[static_cast<std::size_t>(e) * 3 + f]
                  : t.elem_faces[static_cast<std::size_t>(e) * 4 + f];
  };
  for (int e : coarse_elems)
    for (int f = 0; f < npe; ++f) holder.emplace(facet_of(e, f), e);
  for (const auto& [name, facets] : m.face_sets) {
    std::vector<int>& fine = out.face_sets[name];
    for (std::size_t i = 0; i + d <= facets.size(); i += d) {
      const int* v = &facets[i];
      const int f = d == 2 ? find_key(t.edges, edge_key(v[0], v[1])) : find_key(t.faces, face_key3(v[0], v[1], v[2]));
      const auto h = holder.find(f);
      if (f < 0 || h == holder.end()) continue;
      auto id = [&](int i0, int i1, int i2) {
        const int b[3] = {i0, i1, i2};
        return local.at(facet_gid(m, t, h->second, v, b));
      };
      if (d == 2) {
        for (int j = 0; j < mm; ++j) fine.insert(fine.end(), {id(mm - j, j, 0), id(mm - j - 1, j + 1, 0)});
        continue;
      }
      for (int p = 0; p < mm; ++p)  // up triangles, then down ones, of the facet's lattice
        for (int q = 0; p + q < mm; ++q) {
          fine.insert(fine.end(), {id(mm - p - q, p, q), id(mm - p - q - 1, p + 1, q), id(mm - p - q - 1, p, q + 1)});
          if (p + q + 2 <= mm)
            fine.insert(fine.end(), {id(mm - p - q - 1, p + 1, q), id(mm - p - q - 2, p + 1, q + 1),
                                     id(mm - p - q - 1, p, q + 1)});
        }
    }
  }
}

}  // namespace

RefinedPart refine_elements(const HostMesh& m, const CoarseTopology& t, const std::vector<int>& coarse_elems) {
  const int d = m.dim, npe = d + 1, mm = t.m;
  RefinedPart out;
  HostMesh& f = out.mesh;
  f.dim = d;
  f.region_names = m.region_names;
  const SetMaps sets = set_maps(m, t);
  std::vector<std::vector<int>> set_nodes(sets.names.size());
  std::unordered_map<std::int64_t, int> local;
  const std::int64_t per_elem = static_cast<std::int64_t>(refine_factor(d, t.levels) + 0.5);
  local.reserve(static_cast<std::size_t>(coarse_elems.size() * per_elem / (d == 2 ? 2 : 5) + 16));
  // (the arrays sized before they are filled: the elements exactly, the nodes about; a vector grown
  // by doubling touches about twice its pages, and the set-up of a large mesh is mostly first touches)
  const std::size_t kids = coarse_elems.size() * static_cast<std::size_t>(per_elem);
  f.elems.reserve(kids * npe);
  f.elem_region.reserve(kids);
  out.elem_gid.reserve(kids);
  // (the nodes are about 1/2 of the elements in 2D and 1/5 in 3D: room for more)
  const std::size_t nodes_about = kids / (d == 2 ? 1 : 4) + 16;
  f.X.reserve(nodes_about * d);
  out.node_gid.reserve(nodes_about);
  // the lattice of one element: (m+1)^dim slots by (b_1, .., b_dim)
  const int side = mm + 1;
  std::vector<int> slot(d == 2 ? side * side : side * side * side, -1);
  auto slot_of = [&](const Lattice& b) { return d == 2 ? b[1] * side + b[2] : (b[1] * side + b[2]) * side + b[3]; };
  for (int e : coarse_elems) {
    if (e < 0 || e >= m.num_elems()) throw InputError("refine_elements: coarse element " + std::to_string(e) + " out of range");
    const std::vector<Simplex> kids = refine_one(m, t, e);
    std::fill(slot.begin(), slot.end(), -1);
    for (std::size_t c = 0; c < kids.size(); ++c) {
      for (int a = 0; a < npe; ++a) {
        const Lattice& b = kids[c][a];
        int& s = slot[slot_of(b)];
        if (s < 0) {
          const LatticeNode n = lattice_node(m, t, e, b);
          const auto ins = local.emplace(n.gid, f.num_nodes());
          if (ins.second) {
            const std::array<double, 3> x = lattice_point(m, t, n);
            f.X.insert(f.X.end(), x.begin(), x.begin() + d);
            out.node_gid.push_back(n.gid);
            for (std::size_t k = 0; k < sets.names.size(); ++k)
              if (node_in_set(sets, k, n, d)) set_nodes[k].push_back(ins.first->second);
          }
          s = ins.first->second;
        }
        f.elems.push_back(s);
      }
      f.elem_region.push_back(m.elem_region[e]);
      out.elem_gid.push_back(static_cast<std::int64_t>(e) * per_elem + static_cast<std::int64_t>(c));
    }
  }
  for (std::size_t k = 0; k < sets.names.size(); ++k) {
    std::sort(set_nodes[k].begin(), set_nodes[k].end());
    f.node_sets[sets.names[k]] = std::move(set_nodes[k]);
  }
  if (m.node_sets.count("all")) {
    std::vector<int> all(f.num_nodes());
    for (int i = 0; i < f.num_nodes(); ++i) all[i] = i;
    f.node_sets["all"] = std::move(all);
  }
  refine_face_sets(m, t, coarse_elems, local, f);
  f.node_origin.resize(f.num_nodes());
  for (int i = 0; i < f.num_nodes(); ++i) f.node_origin[i] = i;
  return out;
}

std::vector<std::int64_t> refined_interface_offsets(const HostMesh& m, const CoarseTopology& t) {
  const int d = m.dim, npe = d + 1, ne = m.num_elems();
  const std::int64_t children = static_cast<std::int64_t>(refine_factor(d, t.levels) + 0.5);
  const std::int64_t per_facet = d == 2 ? t.m : static_cast<std::int64_t>(t.m) * t.m;
  const std::int64_t inside = (npe * children - npe * per_facet) / 2;
  std::vector<std::int64_t> off(static_cast<std::size_t>(ne) + 1, 0);
  for (int e = 0; e < ne; ++e) {
    std::int64_t n = inside;
    for (int f = 0; f < npe; ++f)
      if (t.elem_neighbours[static_cast<std::size_t>(e) * npe + f] > e) n += per_facet;
    off[e + 1] = off[e] + n;
  }
  return off;
}

std::vector<double> coarse_edge_sums(const HostMesh& fine, int children) {
  const int d = fine.dim, npe = d + 1, ne = fine.num_elems();
  if (children < 1 || ne % children != 0)
    throw InputError("coarse_edge_sums: " + std::to_string(ne) + " elements are not groups of " +
                     std::to_string(children));
  std::vector<double> sums(static_cast<std::size_t>(ne / children), 0.0);
  for (int e = 0; e < ne; ++e) {
    const int* n = &fine.elems[static_cast<std::size_t>(e) * npe];
    double& s = sums[static_cast<std::size_t>(e / children)];
    for (int a = 0; a < npe; ++a)
      for (int b = a + 1; b < npe; ++b) {
        double l2 = 0;
        for (int k = 0; k < d; ++k) {
          const double dx = fine.X[static_cast<std::size_t>(n[a]) * d + k] - fine.X[static_cast<std::size_t>(n[b]) * d + k];
          l2 += dx * dx;
        }
        s += std::sqrt(l2);
      }
  }
  return sums;
}

double mean_size_from_sums(const std::vector<double>& sums, long fine_elems, int dim) {
  double total = 0;
  for (double s : sums) total += s;
  const long edges = fine_elems * (dim + 1) * dim / 2;
  return edges > 0 ? total / static_cast<double>(edges) : 0.0;
}

double refined_mean_size(const HostMesh& fine, int children) {
  return mean_size_from_sums(coarse_edge_sums(fine, children), fine.num_elems(), fine.dim);
}

HostMesh refine_mesh(const HostMesh& coarse, int levels, const std::vector<CurvedSurface>& surfaces) {
  if (levels == 0) return coarse;
  const CoarseTopology t = coarse_topology(coarse, levels, surfaces);
  const double elements = coarse.num_elems() * refine_factor(coarse.dim, levels);
  if (t.num_fine_nodes > 2147483000LL || elements > 2147483000.0)
    throw InputError("mesh.refine = " + std::to_string(levels) + " makes " + std::to_string(t.num_fine_nodes) +
                     " nodes and " + mesh_detail::fmt(elements) + " elements, more than one process numbers (2^31)");
  std::vector<int> all(coarse.num_elems());
  for (int e = 0; e < coarse.num_elems(); ++e) all[e] = e;
  RefinedPart p = refine_elements(coarse, t, all);
  // renumber the nodes by their global ids; the coarse nodes no element uses keep their place
  const int d = coarse.dim, nn = static_cast<int>(t.num_fine_nodes);
  HostMesh out = std::move(p.mesh);
  std::vector<int> to(out.num_nodes());
  std::vector<double> X(static_cast<std::size_t>(nn) * d, 0.0);
  std::copy(coarse.X.begin(), coarse.X.end(), X.begin());
  for (int i = 0; i < out.num_nodes(); ++i) {
    to[i] = static_cast<int>(p.node_gid[i]);
    for (int k = 0; k < d; ++k) X[static_cast<std::size_t>(to[i]) * d + k] = out.X[static_cast<std::size_t>(i) * d + k];
  }
  out.X = std::move(X);
  for (int& n : out.elems) n = to[n];
  for (auto& [name, faces] : out.face_sets)
    for (int& n : faces) n = to[n];
  for (auto& [name, nodes] : out.node_sets) {
    for (int& n : nodes) n = to[n];
    const auto c = coarse.node_sets.find(name);  // coarse nodes of the set no element uses
    if (c != coarse.node_sets.end()) nodes.insert(nodes.end(), c->second.begin(), c->second.end());
    if (name == "all")
      for (int i = 0; i < nn; ++i) nodes.push_back(i);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }
  out.node_origin.resize(nn);
  for (int i = 0; i < nn; ++i) out.node_origin[i] = i;
  return out;
}

}  // namespace fdem
