// The bodies of a mesh before interface insertion (mesh.hpp, check_bodies): duplicate nodes and
// bodies that overlap at the start. Both searches use a hash grid of cells about one mean edge
// long, so they take time in proportion to the mesh size.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

namespace {

using mesh_detail::fmt;

using mesh_detail::UnionFind;

// Cells of size `h` keyed by their integer coordinates (21 bits each, wrapped: a collision only
// adds candidates, which the exact tests then reject).
struct HashGrid {
  int dim;
  double h;
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  std::array<long long, 3> cell_of(const double* x) const {
    std::array<long long, 3> c{0, 0, 0};
    for (int k = 0; k < dim; ++k) c[k] = static_cast<long long>(std::floor(x[k] / h));
    return c;
  }
  static std::uint64_t key(const std::array<long long, 3>& c) {
    const std::uint64_t m = (1u << 21) - 1;
    return (static_cast<std::uint64_t>(c[0]) & m) | ((static_cast<std::uint64_t>(c[1]) & m) << 21) |
           ((static_cast<std::uint64_t>(c[2]) & m) << 42);
  }
};

std::string point(const HostMesh& m, int n) {
  const double* x = &m.X[static_cast<size_t>(n) * m.dim];
  std::string s = "(" + fmt(x[0]) + ", " + fmt(x[1]);
  if (m.dim == 3) s += ", " + fmt(x[2]);
  return s + ")";
}

std::string region_of(const HostMesh& m, int e) {
  const int r = m.elem_region[e];
  return r >= 0 && r < static_cast<int>(m.region_names.size()) ? m.region_names[r] : std::to_string(r);
}

// Barycentric coordinates of x in element e (dim + 1 values) and the element's altitudes over its
// faces (the altitude from vertex a onto the face opposite it); false for a degenerate element.
bool barycentric(const HostMesh& m, int e, const double* x, double* lam, double* alt) {
  const int d = m.dim;
  const int* n = &m.elems[static_cast<size_t>(e) * (d + 1)];
  const double* p0 = &m.X[static_cast<size_t>(n[0]) * d];
  double A[3][3];  // columns: edges from vertex 0
  for (int a = 1; a <= d; ++a)
    for (int k = 0; k < d; ++k) A[k][a - 1] = m.X[static_cast<size_t>(n[a]) * d + k] - p0[k];
  double r[3] = {0, 0, 0};
  for (int k = 0; k < d; ++k) r[k] = x[k] - p0[k];
  if (d == 2) {
    const double det = A[0][0] * A[1][1] - A[0][1] * A[1][0];
    if (!(std::fabs(det) > 0)) return false;
    lam[1] = (r[0] * A[1][1] - r[1] * A[0][1]) / det;
    lam[2] = (A[0][0] * r[1] - A[1][0] * r[0]) / det;
    lam[0] = 1 - lam[1] - lam[2];
    for (int a = 0; a < 3; ++a) {  // altitude = 2 area / length of the opposite edge
      const double* q1 = &m.X[static_cast<size_t>(n[(a + 1) % 3]) * 2];
      const double* q2 = &m.X[static_cast<size_t>(n[(a + 2) % 3]) * 2];
      alt[a] = std::fabs(det) / std::hypot(q2[0] - q1[0], q2[1] - q1[1]);
    }
    return true;
  }
  // 3D: Cramer's rule; face areas from cross products
  auto det3 = [](const double c0[3], const double c1[3], const double c2[3]) {
    return c0[0] * (c1[1] * c2[2] - c1[2] * c2[1]) - c1[0] * (c0[1] * c2[2] - c0[2] * c2[1]) +
           c2[0] * (c0[1] * c1[2] - c0[2] * c1[1]);
  };
  const double c0[3] = {A[0][0], A[1][0], A[2][0]}, c1[3] = {A[0][1], A[1][1], A[2][1]},
               c2[3] = {A[0][2], A[1][2], A[2][2]};
  const double det = det3(c0, c1, c2);
  if (!(std::fabs(det) > 0)) return false;
  lam[1] = det3(r, c1, c2) / det;
  lam[2] = det3(c0, r, c2) / det;
  lam[3] = det3(c0, c1, r) / det;
  lam[0] = 1 - lam[1] - lam[2] - lam[3];
  for (int a = 0; a < 4; ++a) {  // altitude = 3 volume / area of the opposite face
    const double* q[3];
    for (int j = 0; j < 3; ++j) q[j] = &m.X[static_cast<size_t>(n[(a + 1 + j) % 4]) * 3];
    const double u[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
    const double v[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
    const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2],
                 cz = u[0] * v[1] - u[1] * v[0];
    alt[a] = std::fabs(det) / std::sqrt(cx * cx + cy * cy + cz * cz);
  }
  return true;
}

// The used nodes, the body of each (-1 for an unused node) and the mean edge length.
struct Bodies {
  std::vector<char> used;
  std::vector<int> body;
  double h = 0;
};

// Bodies: elements joined through shared nodes (a union-find); counts them in out.bodies.
Bodies find_bodies(const HostMesh& mesh, BodyCheck& out) {
  const int d = mesh.dim, nn = mesh.num_nodes(), ne = mesh.num_elems();
  UnionFind uf(nn);
  Bodies b;
  b.used.assign(nn, 0);
  double edge_sum = 0;
  long edges = 0;
  for (int e = 0; e < ne; ++e) {
    const int* n = &mesh.elems[static_cast<size_t>(e) * (d + 1)];
    for (int a = 0; a <= d; ++a) {
      b.used[n[a]] = 1;
      uf.join(n[0], n[a]);
      for (int c = a + 1; c <= d; ++c) {
        double s = 0;
        for (int k = 0; k < d; ++k) {
          const double dx =
              mesh.X[static_cast<size_t>(n[a]) * d + k] - mesh.X[static_cast<size_t>(n[c]) * d + k];
          s += dx * dx;
        }
        edge_sum += std::sqrt(s);
        ++edges;
      }
    }
  }
  b.body.assign(nn, -1);
  for (int i = 0; i < nn; ++i)
    if (b.used[i]) {
      const int r = uf.find(i);
      if (b.body[r] < 0) b.body[r] = out.bodies++;
      b.body[i] = b.body[r];
    }
  b.h = edge_sum / static_cast<double>(edges);
  return b;
}

// Duplicate nodes: used nodes closer than out.tolerance (1e-6 of the mean edge). A pair inside one
// body is an error; a pair between separate bodies a warning.
void check_duplicate_nodes(const HostMesh& mesh, const std::string& source, const Bodies& b, BodyCheck& out) {
  const int d = mesh.dim, nn = mesh.num_nodes();
  const std::vector<char>& used = b.used;
  const std::vector<int>& body = b.body;
  HashGrid nodes{d, b.h, {}};
  for (int i = 0; i < nn; ++i)
    if (used[i]) nodes.cells[HashGrid::key(nodes.cell_of(&mesh.X[static_cast<size_t>(i) * d]))].push_back(i);
  int split_a = -1, split_b = -1, touch_a = -1, touch_b = -1;
  std::vector<char> dup(nn, 0);
  for (int i = 0; i < nn; ++i) {
    if (!used[i]) continue;
    const double* xi = &mesh.X[static_cast<size_t>(i) * d];
    const auto c = nodes.cell_of(xi);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = (d == 3 ? -1 : 0); dz <= (d == 3 ? 1 : 0); ++dz) {
          const auto it = nodes.cells.find(HashGrid::key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == nodes.cells.end()) continue;
          for (int j : it->second) {
            if (j <= i) continue;
            double s = 0;
            for (int k = 0; k < d; ++k) {
              const double dd = xi[k] - mesh.X[static_cast<size_t>(j) * d + k];
              s += dd * dd;
            }
            if (!(std::sqrt(s) <= out.tolerance)) continue;
            dup[i] = dup[j] = 1;
            if (body[i] == body[j]) {
              ++out.split_pairs;
              if (split_a < 0) split_a = i, split_b = j;
            } else {
              ++out.touching_pairs;
              if (touch_a < 0) touch_a = i, touch_b = j;
            }
          }
        }
  }
  out.duplicate_nodes = std::count(dup.begin(), dup.end(), 1);
  if (out.split_pairs > 0)
    throw InputError(source + ": " + std::to_string(out.split_pairs) +
                     " pair(s) of duplicate nodes inside one body; the first, mesh nodes " +
                     std::to_string(split_a) + " and " + std::to_string(split_b) +
                     " (counted from 0), coincide at " + point(mesh, split_a) + " (within " +
                     fmt(out.tolerance) +
                     " m = 1e-6 of the mean edge). The elements around such a node are not joined there, "
                     "a mesh error (in Gmsh: Coherence Mesh; or share the points and curves between "
                     "surfaces). Bodies meant to be separate must not be joined elsewhere.");
  if (out.touching_pairs > 0)
    out.warnings.push_back(source + ": " + std::to_string(out.touching_pairs) +
                           " pair(s) of coincident nodes between separate bodies (the first, nodes " +
                           std::to_string(touch_a) + " and " + std::to_string(touch_b) + " at " +
                           point(mesh, touch_a) +
                           "): the bodies touch there but are not joined; they interact only by contact");
}

// Each element in every cell of size h that its bounding box touches (slivers spanning more than
// 4096 cells left out).
HashGrid element_grid(const HostMesh& mesh, double h) {
  const int d = mesh.dim, ne = mesh.num_elems();
  HashGrid elems{d, h, {}};
  for (int e = 0; e < ne; ++e) {
    const int* n = &mesh.elems[static_cast<size_t>(e) * (d + 1)];
    std::array<long long, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (int a = 0; a <= d; ++a) {
      const auto c = elems.cell_of(&mesh.X[static_cast<size_t>(n[a]) * d]);
      for (int k = 0; k < 3; ++k) {
        lo[k] = a == 0 ? c[k] : std::min(lo[k], c[k]);
        hi[k] = a == 0 ? c[k] : std::max(hi[k], c[k]);
      }
    }
    if ((hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1) > 4096) continue;  // a sliver
    for (long long x = lo[0]; x <= hi[0]; ++x)
      for (long long y = lo[1]; y <= hi[1]; ++y)
        for (long long z = lo[2]; z <= hi[2]; ++z) elems.cells[HashGrid::key({x, y, z})].push_back(e);
  }
  return elems;
}

// Overlapping bodies: nodes inside an element of another body, deeper than the tolerance. An error
// deeper than 1e-3 of the mean edge, else a warning.
void check_overlapping_bodies(const HostMesh& mesh, const std::string& source, const Bodies& b,
                              BodyCheck& out) {
  const int d = mesh.dim, nn = mesh.num_nodes(), ne = mesh.num_elems();
  const double h = b.h;
  const HashGrid elems = element_grid(mesh, h);
  int deep_node = -1, deep_elem = -1;
  for (int i = 0; i < nn; ++i) {
    if (!b.used[i]) continue;
    const double* xi = &mesh.X[static_cast<size_t>(i) * d];
    const auto it = elems.cells.find(HashGrid::key(elems.cell_of(xi)));
    if (it == elems.cells.end()) continue;
    double depth_i = 0;
    int elem_i = -1;
    for (int e : it->second) {
      const int* n = &mesh.elems[static_cast<size_t>(e) * (d + 1)];
      if (b.body[n[0]] == b.body[i]) continue;
      double lam[4], alt[4];
      if (!barycentric(mesh, e, xi, lam, alt)) continue;
      double depth = lam[0] * alt[0];  // distance to the element's nearest face
      for (int a = 1; a <= d; ++a) depth = std::min(depth, lam[a] * alt[a]);
      if (depth > out.tolerance && depth > depth_i) depth_i = depth, elem_i = e;
    }
    if (elem_i < 0) continue;
    ++out.overlapping_nodes;
    if (depth_i > out.overlap_depth) {
      out.overlap_depth = depth_i;
      deep_node = i;
      deep_elem = elem_i;
    }
  }
  if (out.overlapping_nodes == 0) return;
  int node_elem = -1;  // an element of the node's own body, for its region
  for (int e = 0; e < ne && node_elem < 0; ++e)
    for (int a = 0; a <= d; ++a)
      if (mesh.elems[static_cast<size_t>(e) * (d + 1) + a] == deep_node) node_elem = e;
  const std::string msg = std::to_string(out.overlapping_nodes) +
                          " node(s) lie inside another body at the start; the deepest, node " +
                          std::to_string(deep_node) + " at " + point(mesh, deep_node) + " (region '" +
                          region_of(mesh, node_elem) + "'), is at least " + fmt(out.overlap_depth) +
                          " m inside element " + std::to_string(deep_elem) + " (region '" +
                          region_of(mesh, deep_elem) +
                          "'). Overlapping bodies are pushed apart by contact with energy from nowhere";
  if (out.overlap_depth > 1e-3 * h)
    throw InputError(source + ": " + msg + " (allowed: overlaps up to 1e-3 of the mean edge, " +
                     fmt(1e-3 * h) + " m; move the bodies apart)");
  out.warnings.push_back(source + ": " + msg + " (below 1e-3 of the mean edge: a warning)");
}

}  // namespace

// Three phases: the bodies (with the mean edge h), duplicate nodes, and (with two bodies or more)
// overlapping bodies.
BodyCheck check_bodies(const HostMesh& mesh, const std::string& source) {
  BodyCheck out;
  const int nn = mesh.num_nodes(), ne = mesh.num_elems();
  if (ne == 0 || nn == 0) return out;
  const Bodies b = find_bodies(mesh, out);
  if (!(b.h > 0) || !std::isfinite(b.h)) return out;
  out.tolerance = 1e-6 * b.h;
  check_duplicate_nodes(mesh, source, b, out);
  if (out.bodies < 2) return out;
  check_overlapping_bodies(mesh, source, b, out);
  return out;
}

}  // namespace fdem
