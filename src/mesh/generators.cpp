// Structured generators: crossed-diagonal rectangle (triangles) and Kuhn-split box (tetrahedra).
#include <cmath>
#include <numeric>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

namespace {

void check_positive(const std::string& who, const char* what, double v) {
  if (!(v > 0) || !std::isfinite(v))
    throw InputError(who + ": " + what + " must be positive and finite (got " +
                     mesh_detail::fmt(v) + ")");
}

void check_cells(const std::string& who, const char* what, int n) {
  if (n < 1) throw InputError(who + ": " + what + " must be at least 1 (got " + std::to_string(n) + ")");
}

void add_all_set(HostMesh& m) {
  std::vector<int> all(m.num_nodes());
  std::iota(all.begin(), all.end(), 0);
  m.node_sets["all"] = std::move(all);
}

// Node ids of the crossed rectangle: cell corners row by row, then cell centres.
struct CrossedGrid {
  int nx, ny;
  int ncorner() const { return (nx + 1) * (ny + 1); }
  int corner(int i, int j) const { return j * (nx + 1) + i; }
  int centre(int i, int j) const { return ncorner() + j * nx + i; }
};

void crossed_coordinates(HostMesh& m, const CrossedGrid& g, double x0, double y0, double w, double h) {
  const int nx = g.nx, ny = g.ny;
  m.X.resize(2 * static_cast<std::size_t>(g.ncorner() + nx * ny));
  const double dx = w / nx, dy = h / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const int n = g.corner(i, j);
      m.X[2 * n] = i == nx ? x0 + w : x0 + i * dx;
      m.X[2 * n + 1] = j == ny ? y0 + h : y0 + j * dy;
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int n = g.centre(i, j);
      m.X[2 * n] = x0 + (i + 0.5) * dx;
      m.X[2 * n + 1] = y0 + (j + 0.5) * dy;
    }
}

void crossed_elements(HostMesh& m, const CrossedGrid& g) {
  m.elems.reserve(12 * static_cast<std::size_t>(g.nx) * g.ny);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const int p00 = g.corner(i, j), p10 = g.corner(i + 1, j), p11 = g.corner(i + 1, j + 1),
                p01 = g.corner(i, j + 1), c = g.centre(i, j);
      // bottom, right, top, left; all counter-clockwise
      const int tri[4][3] = {{p00, p10, c}, {p10, p11, c}, {p11, p01, c}, {p01, p00, c}};
      for (const auto& t : tri) m.elems.insert(m.elems.end(), t, t + 3);
    }
}

void crossed_node_sets(HostMesh& m, const CrossedGrid& g) {
  std::vector<int> left, right, bottom, top;
  for (int j = 0; j <= g.ny; ++j) {
    left.push_back(g.corner(0, j));
    right.push_back(g.corner(g.nx, j));
  }
  for (int i = 0; i <= g.nx; ++i) {
    bottom.push_back(g.corner(i, 0));
    top.push_back(g.corner(i, g.ny));
  }
  m.node_sets["left"] = left;
  m.node_sets["xmin"] = left;
  m.node_sets["right"] = right;
  m.node_sets["xmax"] = right;
  m.node_sets["bottom"] = bottom;
  m.node_sets["ymin"] = bottom;
  m.node_sets["top"] = top;
  m.node_sets["ymax"] = top;
}

// Node ids of the box: (nx + 1) x (ny + 1) x (nz + 1) grid points, x fastest.
struct BoxGrid {
  int n[3];
  int num_nodes() const { return (n[0] + 1) * (n[1] + 1) * (n[2] + 1); }
  int node(int i, int j, int k) const { return (k * (n[1] + 1) + j) * (n[0] + 1) + i; }
};

void box_coordinates(HostMesh& m, const BoxGrid& g, const std::array<double, 3>& origin,
                     const std::array<double, 3>& size) {
  const int* n = g.n;
  m.X.resize(3 * static_cast<std::size_t>(g.num_nodes()));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) {
        const int id = g.node(i, j, k);
        const int ijk[3] = {i, j, k};
        for (int d = 0; d < 3; ++d)
          m.X[3 * static_cast<std::size_t>(id) + d] =
              ijk[d] == n[d] ? origin[d] + size[d] : origin[d] + ijk[d] * (size[d] / n[d]);
      }
}

// Kuhn (Freudenthal) split: one tetrahedron per path (0,0,0) -> (1,1,1) along the axes in the
// order of a permutation. Every cell is split the same way, so faces conform across cells.
void kuhn_elements(HostMesh& m, const BoxGrid& g) {
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.elems.reserve(24 * static_cast<std::size_t>(g.n[0]) * g.n[1] * g.n[2]);
  for (int k = 0; k < g.n[2]; ++k)
    for (int j = 0; j < g.n[1]; ++j)
      for (int i = 0; i < g.n[0]; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          int tet[4];
          tet[0] = g.node(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            tet[s + 1] = g.node(c[0], c[1], c[2]);
          }
          m.elems.insert(m.elems.end(), tet, tet + 4);
        }
}

void box_node_sets(HostMesh& m, const BoxGrid& g) {
  const int* n = g.n;
  const char* names[3][2] = {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}};
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      std::vector<int> set;
      const int want = side ? n[d] : 0;
      for (int k = 0; k <= n[2]; ++k)
        for (int j = 0; j <= n[1]; ++j)
          for (int i = 0; i <= n[0]; ++i) {
            const int ijk[3] = {i, j, k};
            if (ijk[d] == want) set.push_back(g.node(i, j, k));
          }
      m.node_sets[names[d][side]] = std::move(set);
    }
}

}  // namespace

HostMesh generate_crossed_rectangle(double x0, double y0, double w, double h, int nx, int ny,
                                    const std::string& region) {
  const std::string who = "rectangle generator";
  check_positive(who, "width", w);
  check_positive(who, "height", h);
  check_cells(who, "nx", nx);
  check_cells(who, "ny", ny);
  const double total = (static_cast<double>(nx) + 1) * (ny + 1) + static_cast<double>(nx) * ny;
  if (total * 2 > 2.0e9 || 12.0 * nx * ny > 2.0e9)
    throw InputError(who + ": " + std::to_string(nx) + " x " + std::to_string(ny) +
                     " cells is too many");
  HostMesh m;
  m.dim = 2;
  m.region_names = {region.empty() ? std::string("body") : region};
  const CrossedGrid g{nx, ny};
  crossed_coordinates(m, g, x0, y0, w, h);
  crossed_elements(m, g);
  m.elem_region.assign(m.num_elems(), 0);
  crossed_node_sets(m, g);
  add_all_set(m);
  m.node_origin.resize(m.num_nodes());
  std::iota(m.node_origin.begin(), m.node_origin.end(), 0);
  return m;
}

HostMesh generate_box(const std::array<double, 3>& origin, const std::array<double, 3>& size,
                      int nx, int ny, int nz, const std::string& region) {
  const std::string who = "box generator";
  check_positive(who, "size x", size[0]);
  check_positive(who, "size y", size[1]);
  check_positive(who, "size z", size[2]);
  check_cells(who, "nx", nx);
  check_cells(who, "ny", ny);
  check_cells(who, "nz", nz);
  if (24.0 * nx * ny * nz > 2.0e9 || 3.0 * (nx + 1.0) * (ny + 1.0) * (nz + 1.0) > 2.0e9)
    throw InputError(who + ": too many cells");
  HostMesh m;
  m.dim = 3;
  m.region_names = {region.empty() ? std::string("body") : region};
  const BoxGrid g{{nx, ny, nz}};
  box_coordinates(m, g, origin, size);
  kuhn_elements(m, g);
  m.elem_region.assign(m.num_elems(), 0);
  mesh_detail::orient_positively(m);
  box_node_sets(m, g);
  add_all_set(m);
  m.node_origin.resize(g.num_nodes());
  std::iota(m.node_origin.begin(), m.node_origin.end(), 0);
  return m;
}

HostMesh merge_meshes(const HostMesh& a, const HostMesh& b, const std::string& prefix_a,
                      const std::string& prefix_b) {
  HostMesh m = a;
  const int na = a.num_nodes(), ea = a.num_elems();
  m.node_sets.clear();
  for (const auto& [name, nodes] : a.node_sets) m.node_sets[prefix_a + "." + name] = nodes;
  m.X.insert(m.X.end(), b.X.begin(), b.X.end());
  for (int n : b.elems) m.elems.push_back(n + na);
  const int ra = static_cast<int>(a.region_names.size());
  for (int r : b.elem_region) m.elem_region.push_back(r + ra);
  m.region_names.insert(m.region_names.end(), b.region_names.begin(), b.region_names.end());
  for (const auto& [name, nodes] : b.node_sets) {
    std::vector<int> s;
    for (int n : nodes) s.push_back(n + na);
    m.node_sets[prefix_b + "." + name] = s;
  }
  m.face_sets.clear();
  for (const auto& [name, faces] : a.face_sets) m.face_sets[prefix_a + "." + name] = faces;
  for (const auto& [name, faces] : b.face_sets) {
    std::vector<int> s;
    for (int n : faces) s.push_back(n + na);
    m.face_sets[prefix_b + "." + name] = s;
  }
  for (int n : b.ifaces) m.ifaces.push_back(n + na);
  for (int e : b.iface_elems) m.iface_elems.push_back(e + ea);
  if (m.node_origin.size() != static_cast<size_t>(na)) {
    m.node_origin.resize(na);
    for (int i = 0; i < na; ++i) m.node_origin[i] = i;
  }
  for (int i = 0; i < b.num_nodes(); ++i)
    m.node_origin.push_back((static_cast<int>(b.node_origin.size()) > i ? b.node_origin[i] : i) + na);
  return m;
}

}  // namespace fdem
