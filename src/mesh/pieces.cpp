#include "mesh/pieces.hpp"

#include <vector>

#include "common/union_find.hpp"

namespace fdem {

int count_bodies(const HostMesh& mesh) {
  const int nn = mesh.num_nodes(), ne = mesh.num_elems(), ni = mesh.num_ifaces(), d = mesh.dim;
  UnionFind uf(nn);
  for (int e = 0; e < ne; ++e)
    for (int a = 1; a <= d; ++a)
      uf.join(mesh.elems[static_cast<size_t>(e) * (d + 1)], mesh.elems[static_cast<size_t>(e) * (d + 1) + a]);
  for (int q = 0; q < ni; ++q)
    for (int k = 0; k < d; ++k)
      uf.join(mesh.ifaces[static_cast<size_t>(q) * 2 * d + k],
              mesh.ifaces[static_cast<size_t>(q) * 2 * d + d + k]);
  std::vector<char> seen(nn, 0);
  int n = 0;
  for (int e = 0; e < ne; ++e) {
    const int r = uf.find(mesh.elems[static_cast<size_t>(e) * (d + 1)]);
    if (!seen[r]) {
      seen[r] = 1;
      ++n;
    }
  }
  return n;
}

}  // namespace fdem
