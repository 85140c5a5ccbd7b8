// Locality reordering (mesh.hpp: reorder_for_locality): elements in Morton order of their
// centroids, nodes in order of first use by the sorted elements.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

using namespace mesh_detail;

namespace {

std::uint64_t spread2(std::uint64_t x) {  // 32 bits -> every other bit of 64
  x &= 0xffffffffull;
  x = (x | (x << 16)) & 0x0000ffff0000ffffull;
  x = (x | (x << 8)) & 0x00ff00ff00ff00ffull;
  x = (x | (x << 4)) & 0x0f0f0f0f0f0f0f0full;
  x = (x | (x << 2)) & 0x3333333333333333ull;
  x = (x | (x << 1)) & 0x5555555555555555ull;
  return x;
}

std::uint64_t spread3(std::uint64_t x) {  // 21 bits -> every third bit of 63
  x &= 0x1fffffull;
  x = (x | (x << 32)) & 0x1f00000000ffffull;
  x = (x | (x << 16)) & 0x1f0000ff0000ffull;
  x = (x | (x << 8)) & 0x100f00f00f00f00full;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
  x = (x | (x << 2)) & 0x1249249249249249ull;
  return x;
}

// Morton code of each element's centroid in the centroids' bounding box.
std::vector<std::uint64_t> morton_codes(const HostMesh& mesh) {
  const int dim = mesh.dim;
  const int ne = mesh.num_elems();
  std::vector<std::array<double, 3>> c(ne);
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -std::numeric_limits<double>::infinity();
  }
  for (int e = 0; e < ne; ++e) {
    c[e] = centroid(mesh, e);
    for (int k = 0; k < dim; ++k) {
      lo[k] = std::min(lo[k], c[e][k]);
      hi[k] = std::max(hi[k], c[e][k]);
    }
  }
  // Same scale on all axes so that the curve does not stretch thin domains.
  double ext = 0;
  for (int k = 0; k < dim; ++k) ext = std::max(ext, hi[k] - lo[k]);
  const double cells = dim == 2 ? 4294967295.0 : 2097151.0;
  const double scale = ext > 0 ? cells / ext : 0.0;
  std::vector<std::uint64_t> code(ne);
  for (int e = 0; e < ne; ++e) {
    std::uint64_t q[3] = {0, 0, 0};
    for (int k = 0; k < dim; ++k) {
      double v = std::floor((c[e][k] - lo[k]) * scale);
      v = std::max(0.0, std::min(cells, v));
      q[k] = static_cast<std::uint64_t>(v);
    }
    code[e] = dim == 2 ? (spread2(q[0]) | (spread2(q[1]) << 1))
                       : (spread3(q[0]) | (spread3(q[1]) << 1) | (spread3(q[2]) << 2));
  }
  return code;
}

// Nodes in order of first use by the elements in `order` (order[new] = old); unused nodes keep
// their relative order at the end. Returns old -> new.
std::vector<int> number_by_first_use(const HostMesh& mesh, const std::vector<int>& order) {
  const int npe = mesh.dim + 1;
  const int nn = mesh.num_nodes();
  std::vector<int> node_new(nn, -1);
  int next = 0;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (int a = 0; a < npe; ++a) {
      const int n = mesh.elems[static_cast<std::size_t>(order[i]) * npe + a];
      if (node_new[n] < 0) node_new[n] = next++;
    }
  for (int n = 0; n < nn; ++n)
    if (node_new[n] < 0) node_new[n] = next++;
  return node_new;
}

// Interfaces (only if someone reorders after insertion): remap, keep each interface's sides, and
// sort them again by their A-side element.
void reorder_interfaces(HostMesh& mesh, const std::vector<int>& node_new, const std::vector<int>& elem_new) {
  const int dim = mesh.dim;
  const int ni = mesh.num_ifaces();
  if (ni == 0) return;
  std::vector<int> idx(ni);
  std::iota(idx.begin(), idx.end(), 0);
  for (int& n : mesh.ifaces) n = node_new[n];
  for (int& e : mesh.iface_elems) e = elem_new[e];
  std::stable_sort(idx.begin(), idx.end(),
                   [&](int a, int b) { return mesh.iface_elems[2 * a] < mesh.iface_elems[2 * b]; });
  std::vector<int> ifaces(mesh.ifaces.size()), iface_elems(mesh.iface_elems.size());
  for (int i = 0; i < ni; ++i) {
    for (int k = 0; k < 2 * dim; ++k)
      ifaces[static_cast<std::size_t>(2 * dim) * i + k] =
          mesh.ifaces[static_cast<std::size_t>(2 * dim) * idx[i] + k];
    iface_elems[2 * i] = mesh.iface_elems[2 * idx[i]];
    iface_elems[2 * i + 1] = mesh.iface_elems[2 * idx[i] + 1];
  }
  mesh.ifaces.swap(ifaces);
  mesh.iface_elems.swap(iface_elems);
}

}  // namespace

void reorder_for_locality(HostMesh& mesh, bool elements) {
  const int dim = mesh.dim;
  const int npe = dim + 1;
  const int ne = mesh.num_elems();
  const int nn = mesh.num_nodes();
  if (ne == 0) return;
  std::vector<int> order(ne);  // order[new] = old
  std::iota(order.begin(), order.end(), 0);
  if (elements) {
    const std::vector<std::uint64_t> code = morton_codes(mesh);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return code[a] < code[b]; });
  }
  std::vector<int> elem_new(ne);  // old -> new
  for (int i = 0; i < ne; ++i) elem_new[order[i]] = i;
  const std::vector<int> node_new = number_by_first_use(mesh, order);

  std::vector<double> X(mesh.X.size());
  std::vector<int> origin(nn);
  for (int n = 0; n < nn; ++n) {
    for (int k = 0; k < dim; ++k)
      X[static_cast<std::size_t>(node_new[n]) * dim + k] = mesh.X[static_cast<std::size_t>(n) * dim + k];
    origin[node_new[n]] = mesh.node_origin.size() == static_cast<std::size_t>(nn) ? mesh.node_origin[n] : n;
  }
  std::vector<int> elems(mesh.elems.size());
  std::vector<int> region(ne);
  for (int i = 0; i < ne; ++i) {
    for (int a = 0; a < npe; ++a)
      elems[static_cast<std::size_t>(i) * npe + a] =
          node_new[mesh.elems[static_cast<std::size_t>(order[i]) * npe + a]];
    region[i] = mesh.elem_region[order[i]];
  }
  for (auto& [name, set] : mesh.node_sets) {
    for (int& n : set) n = node_new[n];
    std::sort(set.begin(), set.end());
  }
  for (auto& [name, faces] : mesh.face_sets)
    for (int& n : faces) n = node_new[n];
  reorder_interfaces(mesh, node_new, elem_new);
  mesh.X.swap(X);
  mesh.elems.swap(elems);
  mesh.elem_region.swap(region);
  mesh.node_origin.swap(origin);
}

}  // namespace fdem
