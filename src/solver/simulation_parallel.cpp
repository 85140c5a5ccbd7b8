// Simulation's side of a run over several processes (docs/parallel.md): the set-up of a part
// (the decomposition, the time step and energy floor agreed, the first exchange), the agreement on
// contact's poll steps (the checks of the contact zones and of the balance: solver/cut_checks.hpp),
// and the gathering of the own fields on process 0 for the snapshots (the whole run's state:
// solver/whole_state.hpp; the exchanges themselves: src/parallel/parts.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "kernels/parts.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
void Simulation<D>::set_decomposition(std::shared_ptr<const Comm> comm, const SubMesh& part) {
  if (step_count > 0) throw InputError("set_decomposition: the run has started");
  if (part.mesh.num_nodes() != m.nn || part.mesh.num_elems() != m.ne || part.mesh.num_ifaces() != m.ni)
    throw InputError("set_decomposition: the model was not built from this part's mesh");
  if (contact_ && !(part.contact_reach > contact_->radius))
    throw InputError("set_decomposition: contact over processes needs a part decomposed with a contact reach "
                     "beyond the search distance (" + std::to_string(contact_->radius) + " m; got " +
                     std::to_string(part.contact_reach) + " m)");
  // with contact the ghosts' velocities travel too (a contact's friction reads the face's)
  parts_.decompose(std::move(comm), part, /*velocities=*/contact_ != nullptr);
  force_pass_contributes_ = parts_.force_pass_contributes(contact_ != nullptr);
  cuts_.start(part, m, contact_ != nullptr);
  // the time step: the smallest contributions over the processes, decided as one run would
  StepContributions all = step_sources_;
  double v[kSmallestOverPartsCount];
  for (int i = 0; i < kSmallestOverPartsCount; ++i) v[i] = all.*kSmallestOverParts[i];
  parts_.min(v, kSmallestOverPartsCount);
  for (int i = 0; i < kSmallestOverPartsCount; ++i) all.*kSmallestOverParts[i] = v[i];
  platens_.weight_steps(parts_, m, all);  // (a drop weight on the whole body's springs)
  all.bulk_element = -1;
  if (contact_) {  // surfaces may meet on some process: on all (one time step)
    agree_on_meeting();
    all.may_meet = contact_meet_;
  }
  agree_time_step(all);
  // the energy floor from the whole body's volume (each element once)
  auto vol = Kokkos::create_mirror_view(m.vol0);
  Kokkos::deep_copy(vol, m.vol0);
  double own[2] = {0, 0};
  for (int e = 0; e < m.ne; ++e) own[e < m.owned_elems() ? 0 : 1] += vol(e);
  double whole = own[0];
  parts_.sum(&whole, 1);
  if (own[0] + own[1] > 0) energy_floor_ *= whole / (own[0] + own[1]);
  parts_.exchange_ghosts(m, phase_times_.exchange);
}

template <int D>
void Simulation<D>::agree_on_meeting() {
  double meet = contact_->may_meet() ? -1.0 : 0.0;
  parts_.min(&meet, 1);
  contact_meet_ = meet < 0;
}

// On the steps the contact systems poll for failed interfaces (the same on every process):
// whether surfaces may meet anywhere (the contact time step then applies on all), with the checks
// of the contact zones and of the balance over processes (solver/cut_checks.hpp).
template <int D>
void Simulation<D>::agree_on_contact() {
  contact_meet_ = cuts_.check(m, *contact_, parts_, dt, step_count, t);
}

// The own rows of each field gathered on process 0 in the whole mesh's order; empty elsewhere.
template <int D>
void Simulation<D>::gather_whole(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                                 std::vector<double>& stress, std::vector<double>& damage) {
  const size_t nn = static_cast<size_t>(m.owned_nodes()), ne = static_cast<size_t>(m.owned_elems()),
               ni = static_cast<size_t>(m.owned_ifaces());
  const WholeRows w = whole_rows();
  for (auto* a : {&x, &u, &v}) parts_.gather_to_root(*a, nn, D, w.nodes, w.nn);
  parts_.gather_to_root(stress, ne, 6, w.elems, w.ne);
  parts_.gather_to_root(damage, ni, 1, w.ifaces, w.ni);
}

#define FDEM_SIMULATION_PARALLEL(D)                                                            \
  template void Simulation<D>::set_decomposition(std::shared_ptr<const Comm>, const SubMesh&); \
  template void Simulation<D>::agree_on_meeting();                                             \
  template void Simulation<D>::agree_on_contact();                                             \
  template void Simulation<D>::gather_whole(std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&);
FDEM_SIMULATION_PARALLEL(2)
FDEM_SIMULATION_PARALLEL(3)
#undef FDEM_SIMULATION_PARALLEL

}  // namespace fdem
