// Simulation's side of a run over several processes (docs/parallel.md): the set-up of a part
// (time step, energy floor, the first exchange), the exchange of the ghost positions after each
// node update, contact over the parts, the checks of the contact zones and of the balance, and the
// gathering of the own fields on process 0 for the snapshots (the whole run's state:
// simulation_state_whole.cpp).
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
  zone_reach_ = part.contact_reach;
  if (const char* every = std::getenv("FDEM_TEST_RECUT")) test_recut_every_ = std::atol(every);
  if (contact_) {  // where the zones were taken: the reference positions, or those of a cut during the run
    const int own = m.owned_nodes();
    xcut_ = Kokkos::View<double* [D]>("fdem::contact::cut_positions", own);
    auto h = Kokkos::create_mirror_view(xcut_);
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
    if (!part.cut_x.empty() && part.cut_x.size() != static_cast<size_t>(m.nn) * D)
      throw InputError("set_decomposition: the part's cut positions do not match its nodes");
    for (int i = 0; i < own; ++i)
      for (int k = 0; k < D; ++k) h(i, k) = part.cut_x.empty() ? X(i, k) : part.cut_x[static_cast<size_t>(i) * D + k];
    Kokkos::deep_copy(xcut_, h);
  }
  // the time step: the smallest contributions over the processes, decided as one run would
  StepContributions all = step_sources_;
  double v[kSmallestOverPartsCount];
  for (int i = 0; i < kSmallestOverPartsCount; ++i) v[i] = all.*kSmallestOverParts[i];
  parts_.min(v, kSmallestOverPartsCount);
  for (int i = 0; i < kSmallestOverPartsCount; ++i) all.*kSmallestOverParts[i] = v[i];
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

// On the steps the contact systems poll for failed interfaces (the same on every process): whether
// surfaces may meet anywhere (the contact time step then applies on all), and the contact zones'
// check. A process holds every element that came within zone_reach_ of its own nodes where the
// parts were cut; a face it does not hold stays beyond the search distance while
// 2 (d + N v dt) < zone_reach_ - search distance, with d the largest displacement since the cut,
// v the largest speed of any node and N = kContactPollEvery (solver/contact_system.hpp: the steps
// to the next check). When that fails the parts are cut anew at the current positions
// (recut_due_; d is 0 after it), unless the speed alone (2 N v dt) fills the zone: then no cut
// helps and the run stops, naming contact.zone. On one process there is nothing to agree on and
// no zone: surfaces may meet when this process's contact system says so.
//
// The same steps check the balance (Balance): each process's modelled work of a step, its largest
// and its mean over the processes; when the largest exceeds the mean by more than
// rebalance_above_ and by more than twice what it did at the first check after the last cut (so a
// cut that could not do better is not repeated at once), the parts are cut anew, weighted by the
// work (recut_reason_ "work"; solver/run.cpp).
template <int D>
void Simulation<D>::agree_on_contact() {
  if (!parts_.many()) {  // one process: nothing to agree on, no zones or balance to check
    contact_meet_ = contact_->may_meet();
    return;
  }
  double d2 = 0, v2 = 0;
  largest_drift(m, xcut_, d2, v2);
  double work = modelled_work();
  double w[4] = {contact_->may_meet() ? -1.0 : 0.0, -std::sqrt(d2), -std::sqrt(v2), -work};
  parts_.min(w, 4);  // the largest over the processes
  parts_.sum(&work, 1);
  contact_meet_ = w[0] < 0;
  const double d = -w[1], speed = -w[2], room = zone_reach_ - contact_->radius;
  const double ahead = 2.0 * double(kContactPollEvery) * speed * dt, need = 2.0 * d + ahead;
  Balance& b = balance_;
  b.work_most = -w[3];
  b.work_mean = work / parts_.size();
  b.excess = b.work_mean > 0 ? b.work_most / b.work_mean - 1.0 : 0.0;
  b.largest = std::max(b.largest, b.excess);
  if (b.after_cut < 0) b.after_cut = b.excess;
  auto due = [this](const char* why) {
    if (!recut_due_) recut_reason_ = why;
    recut_due_ = true;
  };
  if (b.excess > rebalance_above_ && b.excess > 2.0 * b.after_cut && ahead < room) due("work");
  if (test_recut_every_ > 0) {  // test hook: cut anew every that many steps (FDEM_TEST_RECUT)
    if (next_test_cut_ < 0) next_test_cut_ = step_count + test_recut_every_;
    if (step_count >= next_test_cut_ && ahead < room) due("test");
  }
  if (need < room) return;
  if (ahead < room) {  // valid again once cut at the current positions
    due("zones");
    return;
  }
  char msg[640];
  std::snprintf(msg, sizeof msg,
                "contact over %d processes: at step %ld (t = %.4g s) nodes move at up to %.3g m/s, so far within "
                "the %d steps between two checks of the contact zones that each process's zone (contact.zone = "
                "%.3g m beyond the search distance) may miss a face its contacts can touch even right after the "
                "parts are cut anew: give a larger contact.zone (docs/parallel.md) or run on one process",
                parts_.size(), step_count, t, speed, kContactPollEvery, room);
  throw InputError(msg);
}

// The own rows of each field gathered on process 0 in the whole mesh's order; empty elsewhere.
template <int D>
void Simulation<D>::gather_whole(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                                 std::vector<double>& stress, std::vector<double>& damage) {
  if (!parts_.many()) return;  // one process: its rows are the whole mesh's, in order
  const Comm& comm = parts_.comm();
  const size_t nn = static_cast<size_t>(m.owned_nodes()), ne = static_cast<size_t>(m.owned_elems()),
               ni = static_cast<size_t>(m.owned_ifaces());
  const WholeRows w = whole_rows();
  for (auto* a : {&x, &u, &v}) *a = gather_rows(comm, a->data(), nn, D, w.nodes, w.nn);
  stress = gather_rows(comm, stress.data(), ne, 6, w.elems, w.ne);
  damage = gather_rows(comm, damage.data(), ni, 1, w.ifaces, w.ni);
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
