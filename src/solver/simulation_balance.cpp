// Simulation's side of the balance of a run over processes (docs/parallel.md "Rebalancing"): the
// modelled work of a step (WorkModel) and each node's contact work for the weights of a cut.
#include <vector>

#include "kernels/parts.hpp"
#include "parallel/partition.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
double Simulation<D>::modelled_work(const Kokkos::View<double*>& node_work) const {
  // the interfaces handed over to contact (or failed with contact off) return at their flag: about
  // nothing (the late stage of the default 3D impact: force pass 2.62 ms a step measured, 2.62
  // modelled without them, 2.91 with them; docs/parallel.md "Rebalancing")
  const long live = m.ni - count_handed(m.icontact, m.ni);
  const WorkModel& wm = work_model_;
  double w = wm.element * m.bulk_elems() + wm.interface * static_cast<double>(live) +
             wm.node * m.owned_nodes();
  if (contact_) w += wm.contact_unit * contact_->own_point_work(node_work, wm.contact_unit);
  return w;
}

template <int D>
std::vector<double> Simulation<D>::node_work_whole() const {
  Kokkos::View<double*> w("fdem::parts::node_work", m.nn);
  if (contact_) contact_->own_point_work(w, work_model_.contact_unit);
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w);
  return gather_rows(parts_.comm(), h.data(), static_cast<size_t>(m.owned_nodes()), 1, parts_.node_global(),
                     static_cast<size_t>(parts_.whole_nodes()));
}

template double Simulation<2>::modelled_work(const Kokkos::View<double*>&) const;
template double Simulation<3>::modelled_work(const Kokkos::View<double*>&) const;
template std::vector<double> Simulation<2>::node_work_whole() const;
template std::vector<double> Simulation<3>::node_work_whole() const;

}  // namespace fdem
