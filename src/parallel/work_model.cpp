// The work of each element in the work model of a run over processes (io/work_model.hpp: WorkModel;
// partition.hpp: element_work; docs/parallel.md "Rebalancing").
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "parallel/partition.hpp"

namespace fdem {

std::vector<double> element_work(const HostMesh& mesh, const std::vector<double>& node_work,
                                 const std::vector<long long>& handed, const WorkModel& model) {
  const int ne = mesh.num_elems(), nn = mesh.num_nodes(), nv = mesh.dim + 1;
  if (!node_work.empty() && node_work.size() != static_cast<size_t>(nn))
    throw InputError("element_work: " + std::to_string(node_work.size()) + " node values for " +
                     std::to_string(nn) + " nodes");
  if (!handed.empty() && handed.size() != static_cast<size_t>(mesh.num_ifaces()))
    throw InputError("element_work: " + std::to_string(handed.size()) + " handover flags for " +
                     std::to_string(mesh.num_ifaces()) + " interfaces");
  std::vector<double> w(ne, model.element + nv * model.node);
  for (int i = 0; i < mesh.num_ifaces(); ++i) {
    const int a = mesh.iface_elems[2 * static_cast<size_t>(i)];
    if (a >= 0 && a < ne && (handed.empty() || handed[i] == 0)) w[a] += model.interface;
  }
  if (node_work.empty()) return w;
  std::vector<int> at(nn, 0);  // elements at each node (one where interfaces were inserted)
  for (int n : mesh.elems) ++at[n];
  for (int e = 0; e < ne; ++e)
    for (int k = 0; k < nv; ++k) {
      const int n = mesh.elems[static_cast<size_t>(e) * nv + k];
      w[e] += node_work[n] / at[n];  // (at[n] >= 1: n is a node of e)
    }
  return w;
}

}  // namespace fdem
