// The rotation and the interior node jitter of a built mesh (mesh.hpp, transform_mesh): what an
// ensemble (src/solver/ensemble.cpp) varies between realisations of one case through the keys
// mesh.rotation and mesh.jitter (docs/case-format.md).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "common/random.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {
namespace {

using P3 = std::array<double, 3>;

P3 point(const HostMesh& m, int n) {
  P3 p{0, 0, 0};
  for (int k = 0; k < m.dim; ++k) p[k] = m.X[static_cast<std::size_t>(n) * m.dim + k];
  return p;
}
P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
P3 cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const P3& a) { return std::sqrt(dot(a, a)); }

// Rodrigues' rotation of every node about the axis through the centre.
void rotate(HostMesh& m, const MeshSpec& s) {
  P3 c = s.rotation_center;
  if (!s.has_rotation_center) {
    P3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (int n = 0; n < m.num_nodes(); ++n) {
      const P3 x = point(m, n);
      for (int k = 0; k < m.dim; ++k) {
        lo[k] = std::min(lo[k], x[k]);
        hi[k] = std::max(hi[k], x[k]);
      }
    }
    for (int k = 0; k < 3; ++k) c[k] = k < m.dim ? 0.5 * (lo[k] + hi[k]) : 0.0;
  }
  P3 u = m.dim == 2 ? P3{0, 0, 1} : s.rotation_axis;
  const double len = norm(u);
  for (double& v : u) v /= len;
  const double a = s.rotation_deg * M_PI / 180, ca = std::cos(a), sa = std::sin(a);
  for (int n = 0; n < m.num_nodes(); ++n) {
    const P3 r = sub(point(m, n), c), ur = cross(u, r);
    const double ud = dot(u, r);
    for (int k = 0; k < m.dim; ++k)
      m.X[static_cast<std::size_t>(n) * m.dim + k] = c[k] + r[k] * ca + ur[k] * sa + u[k] * ud * (1 - ca);
  }
}

// An element's signed measure (area, volume) and shortest altitude (2 A / longest edge in 2D,
// 3 V / largest face in 3D); the altitude is negative for an inverted element.
double altitude(const HostMesh& m, int e) {
  const int npe = m.dim + 1;
  P3 x[4];
  for (int a = 0; a < npe; ++a) x[a] = point(m, m.elems[static_cast<std::size_t>(e) * npe + a]);
  if (m.dim == 2) {
    const double area2 = cross(sub(x[1], x[0]), sub(x[2], x[0]))[2];
    double longest = 0;
    for (int a = 0; a < 3; ++a) longest = std::max(longest, norm(sub(x[(a + 1) % 3], x[a])));
    return area2 / longest;
  }
  const double vol6 = dot(cross(sub(x[1], x[0]), sub(x[2], x[0])), sub(x[3], x[0]));
  const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  double largest = 0;
  for (const auto& f : faces)
    largest = std::max(largest, 0.5 * norm(cross(sub(x[f[1]], x[f[0]]), sub(x[f[2]], x[f[0]]))));
  return 0.5 * vol6 / largest;  // 3 V / A = 3 (vol6 / 6) / A
}

// Nodes that stay: the outer boundary's, every face set's, every node set's but "all".
std::vector<char> fixed_nodes(const HostMesh& m) {
  std::vector<char> fixed(m.num_nodes(), 0);
  for (int n : boundary_faces(m)) fixed[n] = 1;
  for (const auto& [name, faces] : m.face_sets)
    for (int n : faces) fixed[n] = 1;
  for (const auto& [name, nodes] : m.node_sets)
    if (name != "all")
      for (int n : nodes) fixed[n] = 1;
  return fixed;
}

// A random vector in the unit ball (dim components) from node n's own stream.
P3 ball_draw(unsigned long seed, int n, int dim) {
  SplitMixStream rng(splitmix64(seed) ^ splitmix64(static_cast<std::uint64_t>(n) + 1));
  for (;;) {
    P3 v{0, 0, 0};
    for (int k = 0; k < dim; ++k) v[k] = 2 * rng.uniform() - 1;
    if (dot(v, v) <= 1) return v;
  }
}

long jitter(HostMesh& m, const MeshSpec& s) {
  const int nn = m.num_nodes(), ne = m.num_elems(), npe = m.dim + 1;
  // the elements at each node: node_elems.item holds entries of m.elems (element = entry / npe)
  const mesh_detail::Csr node_elems(nn, ne * npe, [&](int i) { return m.elems[i]; });
  const std::vector<int>& off = node_elems.off;
  std::vector<int> item(node_elems.item.size());
  for (size_t j = 0; j < item.size(); ++j) item[j] = node_elems.item[j] / npe;
  std::vector<double> floor(ne);
  for (int e = 0; e < ne; ++e) floor[e] = 0.7 * altitude(m, e);
  const std::vector<char> fixed = fixed_nodes(m);
  long moved = 0;
  for (int n = 0; n < nn; ++n) {
    if (fixed[n] || off[n] == off[n + 1]) continue;
    double shortest = 1e300;
    for (int j = off[n]; j < off[n + 1]; ++j)
      for (int a = 0; a < npe; ++a) {
        const int o = m.elems[static_cast<std::size_t>(item[j]) * npe + a];
        if (o != n) shortest = std::min(shortest, norm(sub(point(m, o), point(m, n))));
      }
    const P3 dir = ball_draw(s.jitter_seed, n, m.dim), x0 = point(m, n);
    double scale = s.jitter * shortest;
    for (int tries = 0; tries < 4; ++tries, scale *= 0.5) {
      for (int k = 0; k < m.dim; ++k) m.X[static_cast<std::size_t>(n) * m.dim + k] = x0[k] + scale * dir[k];
      bool ok = true;
      for (int j = off[n]; ok && j < off[n + 1]; ++j) ok = altitude(m, item[j]) >= floor[item[j]];
      if (ok) {
        ++moved;
        break;
      }
      for (int k = 0; k < m.dim; ++k) m.X[static_cast<std::size_t>(n) * m.dim + k] = x0[k];
    }
  }
  return moved;
}

}  // namespace

long transform_mesh(HostMesh& mesh, const MeshSpec& spec) {
  if (spec.rotation_deg != 0) rotate(mesh, spec);
  return spec.jitter > 0 ? jitter(mesh, spec) : 0;
}

}  // namespace fdem
