// Simulation's side of a run over several processes (docs/parallel.md): the set-up of a part
// (time step, energy floor, the first exchange), the exchange of the ghost positions after each
// node update, and the gathering of the own fields on process 0 for the snapshots.
#include <vector>

#include "common/error.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
void Simulation<D>::set_decomposition(std::shared_ptr<const Comm> comm, const SubMesh& part) {
  if (step_count > 0) throw InputError("set_decomposition: the run has started");
  if (part.mesh.num_nodes() != m.nn || part.mesh.num_elems() != m.ne || part.mesh.num_ifaces() != m.ni)
    throw InputError("set_decomposition: the model was not built from this part's mesh");
  comm_ = std::move(comm);
  halo_ = std::make_unique<Halo<D>>(part.neighbours, part.send, part.recv);
  node_global_.assign(part.node_global.begin(), part.node_global.begin() + m.owned_nodes());
  elem_global_.assign(part.elem_global.begin(), part.elem_global.begin() + m.owned_elems());
  iface_global_.assign(part.iface_global.begin(), part.iface_global.begin() + m.owned_ifaces());
  double counts[3] = {static_cast<double>(m.owned_nodes()), static_cast<double>(m.owned_elems()),
                      static_cast<double>(m.owned_ifaces())};
  comm_->sum(counts, 3);
  whole_nn_ = static_cast<long>(counts[0]);
  whole_ne_ = static_cast<long>(counts[1]);
  whole_ni_ = static_cast<long>(counts[2]);
  // the time step: the smallest contributions over the processes, decided as one run would
  StepContributions& sc = step_sources_;
  double v[5] = {sc.bulk, sc.interfaces, sc.platens, sc.contact, sc.platens_on_surfaces};
  comm_->min(v, 5);
  StepContributions all = sc;
  all.bulk = v[0];
  all.interfaces = v[1];
  all.platens = v[2];
  all.contact = v[3];
  all.platens_on_surfaces = v[4];
  all.bulk_element = -1;
  agree_time_step(all);
  // the energy floor from the whole body's volume (each element once)
  auto vol = Kokkos::create_mirror_view(m.vol0);
  Kokkos::deep_copy(vol, m.vol0);
  double own[2] = {0, 0};
  for (int e = 0; e < m.ne; ++e) own[e < m.owned_elems() ? 0 : 1] += vol(e);
  double whole = own[0];
  comm_->sum(&whole, 1);
  if (own[0] + own[1] > 0) energy_floor_ *= whole / (own[0] + own[1]);
  exchange_ghosts();
}

template <int D>
void Simulation<D>::exchange_ghosts() {
  Kokkos::Timer clock;
  halo_->pack(m);
  fence("fdem::halo: packed");  // MPI reads the buffer
  comm_->exchange(halo_->neighbours, halo_->send_buf, halo_->send_off, halo_->recv_buf, halo_->recv_off, D);
  halo_->unpack(m);  // runs before the next force pass on the same execution space: no fence
  phase_times_.exchange += clock.seconds();  // pack, MPI and the unpack's launch
}

// The own part of each array (with the whole mesh's index) gathered on process 0 and put in the
// whole mesh's order there; empty arrays on the other processes.
template <int D>
void Simulation<D>::gather_whole(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                                 std::vector<double>& stress, std::vector<double>& damage) {
  std::vector<double> mine, all;
  // nodes: id, x, u, v
  for (size_t i = 0; i < node_global_.size(); ++i) {
    mine.push_back(node_global_[i]);
    for (const auto* a : {&x, &u, &v})
      for (int k = 0; k < D; ++k) mine.push_back((*a)[i * D + k]);
  }
  comm_->gather(mine, all);
  const bool root = comm_->rank() == 0;
  for (auto* a : {&x, &u, &v}) a->assign(root ? static_cast<size_t>(whole_nn_) * D : 0, 0.0);
  for (size_t j = 0; root && j < all.size(); j += 1 + 3 * D) {
    const size_t n = static_cast<size_t>(all[j]);
    for (int k = 0; k < D; ++k) {
      x[n * D + k] = all[j + 1 + k];
      u[n * D + k] = all[j + 1 + D + k];
      v[n * D + k] = all[j + 1 + 2 * D + k];
    }
  }
  // elements: id, 6 stress components
  mine.clear();
  for (size_t e = 0; e < elem_global_.size(); ++e) {
    mine.push_back(elem_global_[e]);
    mine.insert(mine.end(), stress.begin() + e * 6, stress.begin() + e * 6 + 6);
  }
  comm_->gather(mine, all);
  stress.assign(root ? static_cast<size_t>(whole_ne_) * 6 : 0, 0.0);
  for (size_t j = 0; root && j < all.size(); j += 7)
    std::copy(all.begin() + j + 1, all.begin() + j + 7, stress.begin() + static_cast<size_t>(all[j]) * 6);
  // interfaces: id, damage
  mine.clear();
  for (size_t q = 0; q < iface_global_.size(); ++q) {
    mine.push_back(iface_global_[q]);
    mine.push_back(damage[q]);
  }
  comm_->gather(mine, all);
  damage.assign(root ? static_cast<size_t>(whole_ni_) : 0, 0.0);
  for (size_t j = 0; root && j < all.size(); j += 2) damage[static_cast<size_t>(all[j])] = all[j + 1];
}

#define FDEM_SIMULATION_PARALLEL(D)                                                            \
  template void Simulation<D>::set_decomposition(std::shared_ptr<const Comm>, const SubMesh&); \
  template void Simulation<D>::exchange_ghosts();                                              \
  template void Simulation<D>::gather_whole(std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&);
FDEM_SIMULATION_PARALLEL(2)
FDEM_SIMULATION_PARALLEL(3)
#undef FDEM_SIMULATION_PARALLEL

}  // namespace fdem
