// When the parts of a run over processes are to be cut anew (solver/cut_checks.hpp): the contact
// zones' check, the balance (the modelled work of a step) and the test hook.
#include "solver/cut_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "kernels/parts.hpp"
#include "solver/contact_system.hpp"

namespace fdem {

template <int D>
void CutChecks<D>::start(const SubMesh& part, const Model<D>& m, bool contact) {
  started_ = true;
  zone_reach_ = part.contact_reach;
  if (const char* every = std::getenv("FDEM_TEST_RECUT")) test_every_ = std::atol(every);
  if (!contact) return;
  // where the zones were taken: the reference positions (the own rows of m.X itself, which no
  // step writes: no copy, 24 B per own node in 3D), or those of a cut during the run (a copy)
  const int own = m.owned_nodes();
  if (part.cut_x.empty()) {
    xcut_ = Kokkos::subview(m.X, std::make_pair(0, own), Kokkos::ALL);
    return;
  }
  if (part.cut_x.size() != static_cast<size_t>(m.nn) * D)
    throw InputError("set_decomposition: the part's cut positions do not match its nodes");
  xcut_ = Kokkos::View<double* [D]>("fdem::contact::cut_positions", own);
  auto h = Kokkos::create_mirror_view(xcut_);
  for (int i = 0; i < own; ++i)
    for (int k = 0; k < D; ++k) h(i, k) = part.cut_x[static_cast<size_t>(i) * D + k];
  Kokkos::deep_copy(xcut_, h);
}

template <int D>
bool CutChecks<D>::check(const Model<D>& m, const ContactSystem<D>& contact, const Parts<D>& parts, double dt,
                         long step, double t) {
  if (!started_) return contact.may_meet();  // one process: no zones, no balance, its own word
  double d2 = 0, v2 = 0;
  largest_drift(m, xcut_, d2, v2);
  double work = modelled_work(m, &contact);
  double w[4] = {contact.may_meet() ? -1.0 : 0.0, -std::sqrt(d2), -std::sqrt(v2), -work};
  parts.min(w, 4);  // the largest over the processes
  parts.sum(&work, 1);
  const double d = -w[1], speed = -w[2], room = zone_reach_ - contact.radius;
  const double ahead = 2.0 * double(kContactPollEvery) * speed * dt, need = 2.0 * d + ahead;
  Balance& b = balance_;
  b.work_most = -w[3];
  b.work_mean = work / parts.size();
  b.excess = b.work_mean > 0 ? b.work_most / b.work_mean - 1.0 : 0.0;
  b.largest = std::max(b.largest, b.excess);
  if (b.after_cut < 0) b.after_cut = b.excess;
  if (b.excess > rebalance_above_ && b.excess > 2.0 * b.after_cut && ahead < room) ask("work");
  if (test_every_ > 0) {  // test hook: cut anew every that many steps (FDEM_TEST_RECUT)
    if (next_test_cut_ < 0) next_test_cut_ = step + test_every_;
    if (step >= next_test_cut_ && ahead < room) ask("test");
  }
  if (need < room) return w[0] < 0;
  if (ahead < room) {  // valid again once cut at the current positions
    ask("zones");
    return w[0] < 0;
  }
  char msg[640];
  std::snprintf(msg, sizeof msg,
                "contact over %d processes: at step %ld (t = %.4g s) nodes move at up to %.3g m/s, so far within "
                "the %d steps between two checks of the contact zones that each process's zone (contact.zone = "
                "%.3g m beyond the search distance) may miss a face its contacts can touch even right after the "
                "parts are cut anew: give a larger contact.zone (docs/parallel.md) or run on one process",
                parts.size(), step, t, speed, kContactPollEvery, room);
  throw InputError(msg);
}

template <int D>
bool CutChecks<D>::may_meet(bool agreed, const ContactSystem<D>& contact) const {
  return started_ ? agreed : contact.may_meet();
}

template <int D>
double CutChecks<D>::modelled_work(const Model<D>& m, const ContactSystem<D>* contact,
                                   const Kokkos::View<double*>& node_work) const {
  // the interfaces handed over to contact (or failed with contact off) return at their flag: about
  // nothing (the late stage of the default 3D impact: force pass 2.62 ms a step measured, 2.62
  // modelled without them, 2.91 with them; docs/parallel.md "Rebalancing")
  const long live = m.ni - count_handed(m.icontact, m.ni);
  const WorkModel& wm = work_model_;
  double w = wm.element * m.bulk_elems() + wm.interface * static_cast<double>(live) +
             wm.node * m.owned_nodes();
  if (contact) w += wm.contact_unit * contact->own_point_work(node_work, wm.contact_unit);
  return w;
}

template <int D>
std::vector<double> CutChecks<D>::node_work_whole(const Model<D>& m, const ContactSystem<D>* contact,
                                                  const Parts<D>& parts) const {
  Kokkos::View<double*> w("fdem::parts::node_work", m.nn);
  if (contact) contact->own_point_work(w, work_model_.contact_unit);
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w);
  return gather_rows(parts.comm(), h.data(), static_cast<size_t>(m.owned_nodes()), 1, parts.node_global(),
                     static_cast<size_t>(parts.whole_nodes()));
}

template class CutChecks<2>;
template class CutChecks<3>;

}  // namespace fdem
