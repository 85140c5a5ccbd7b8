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
  const int ncorner = (nx + 1) * (ny + 1);
  const int nn = ncorner + nx * ny;
  m.X.resize(2 * static_cast<std::size_t>(nn));
  auto corner = [&](int i, int j) { return j * (nx + 1) + i; };
  auto centre = [&](int i, int j) { return ncorner + j * nx + i; };
  const double dx = w / nx, dy = h / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const int n = corner(i, j);
      m.X[2 * n] = i == nx ? x0 + w : x0 + i * dx;
      m.X[2 * n + 1] = j == ny ? y0 + h : y0 + j * dy;
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int n = centre(i, j);
      m.X[2 * n] = x0 + (i + 0.5) * dx;
      m.X[2 * n + 1] = y0 + (j + 0.5) * dy;
    }
  m.elems.reserve(12 * static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int p00 = corner(i, j), p10 = corner(i + 1, j), p11 = corner(i + 1, j + 1),
                p01 = corner(i, j + 1), c = centre(i, j);
      // bottom, right, top, left; all counter-clockwise
      const int tri[4][3] = {{p00, p10, c}, {p10, p11, c}, {p11, p01, c}, {p01, p00, c}};
      for (const auto& t : tri) m.elems.insert(m.elems.end(), t, t + 3);
    }
  m.elem_region.assign(m.num_elems(), 0);
  std::vector<int> left, right, bottom, top;
  for (int j = 0; j <= ny; ++j) {
    left.push_back(corner(0, j));
    right.push_back(corner(nx, j));
  }
  for (int i = 0; i <= nx; ++i) {
    bottom.push_back(corner(i, 0));
    top.push_back(corner(i, ny));
  }
  m.node_sets["left"] = left;
  m.node_sets["xmin"] = left;
  m.node_sets["right"] = right;
  m.node_sets["xmax"] = right;
  m.node_sets["bottom"] = bottom;
  m.node_sets["ymin"] = bottom;
  m.node_sets["top"] = top;
  m.node_sets["ymax"] = top;
  add_all_set(m);
  m.node_origin.resize(nn);
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
  const int nn = (nx + 1) * (ny + 1) * (nz + 1);
  auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  const int n[3] = {nx, ny, nz};
  m.X.resize(3 * static_cast<std::size_t>(nn));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const int id = node(i, j, k);
        const int ijk[3] = {i, j, k};
        for (int d = 0; d < 3; ++d)
          m.X[3 * static_cast<std::size_t>(id) + d] =
              ijk[d] == n[d] ? origin[d] + size[d] : origin[d] + ijk[d] * (size[d] / n[d]);
      }
  // Kuhn (Freudenthal) split: one tetrahedron per path (0,0,0) -> (1,1,1) along the axes in the
  // order of a permutation. Every cell is split the same way, so faces conform across cells.
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.elems.reserve(24 * static_cast<std::size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          int tet[4];
          tet[0] = node(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            tet[s + 1] = node(c[0], c[1], c[2]);
          }
          m.elems.insert(m.elems.end(), tet, tet + 4);
        }
  m.elem_region.assign(m.num_elems(), 0);
  mesh_detail::orient_positively(m);
  const char* names[3][2] = {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}};
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      std::vector<int> set;
      const int want = side ? n[d] : 0;
      for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j)
          for (int i = 0; i <= nx; ++i) {
            const int ijk[3] = {i, j, k};
            if (ijk[d] == want) set.push_back(node(i, j, k));
          }
      m.node_sets[names[d][side]] = std::move(set);
    }
  add_all_set(m);
  m.node_origin.resize(nn);
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
