#pragma once
// When the parts of a run over processes with contact are to be cut anew (docs/parallel.md,
// "Contact" and "Rebalancing"), checked on the steps the contact systems poll for failed
// interfaces (the same on every process):
// - the contact zones: a process holds every element that came within the zone reach of its own
//   nodes where the parts were cut; a face it does not hold stays beyond the search distance while
//   2 (d + N v dt) < reach - search distance, with d the largest displacement since the cut, v the
//   largest speed of any node and N = kContactPollEvery (the steps to the next check). When that
//   fails the parts are cut anew at the current positions (reason "zones"; d is 0 after it),
//   unless the speed alone (2 N v dt) fills the zone: then no cut helps and the run stops with an
//   InputError naming contact.zone;
// - the balance: each process's modelled work of a step (WorkModel: its bulk elements, interfaces,
//   own nodes and the narrow phase's work of its own surface points), and how far the largest
//   exceeds the mean (max / mean - 1). When that excess passes the case's parallel.rebalance_above
//   and twice the excess at the first check after the last cut (a cut that could not do better is
//   not repeated at once), the parts are cut anew weighted by the work (reason "work");
// - the test hook FDEM_TEST_RECUT=N (tests/mpi/check_runs.py): a cut every N steps (reason "test").
// Every process takes the same decisions from the same sums. Owned by Simulation. A run on one
// process (never started) holds the trivial checks: surfaces may meet as soon as its contact
// system says so, and nothing is ever to be cut.
#include <vector>

#include "io/work_model.hpp"
#include "kernels/model.hpp"
#include "parallel/decompose.hpp"
#include "parallel/parts.hpp"

namespace fdem {

template <int D>
class ContactSystem;

template <int D>
class CutChecks {
 public:
  struct Balance {
    double excess = 0;      // at the last check
    double after_cut = -1;  // at the first check after the last cut (or the start); -1: none yet
    double largest = 0;     // the largest seen
    double work_most = 0, work_mean = 0;  // ns per step, at the last check
  };

  // The case's settings (parallel.rebalance_above, parallel.work_model).
  void configure(double rebalance_above, const WorkModel& work_model) {
    rebalance_above_ = rebalance_above;
    work_model_ = work_model;
  }
  // A part joins the run: its zone reach and, with contact, where its zones were taken (the
  // reference positions, or those of a cut during the run: part.cut_x). Throws InputError when the
  // cut positions do not match the part's nodes.
  void start(const SubMesh& part, const Model<D>& m, bool contact);

  // On a poll step: the agreement whether surfaces may meet on any process (returned), the zones'
  // check and the balance (collective: every process calls it on the same step). Not started (one
  // process): the contact system's word.
  bool check(const Model<D>& m, const ContactSystem<D>& contact, const Parts<D>& parts, double dt,
             long step, double t);

  // Whether surfaces may meet anywhere (contact's stable step then applies): over processes as
  // `agreed` on the last check, so that every process changes its step on the same step; not
  // started (one process): the contact system's word at once.
  bool may_meet(bool agreed, const ContactSystem<D>& contact) const;

  // The parts are to be cut anew (set on the same step on every process), and why: "work",
  // "zones" or "test", the first of them on the step it was asked.
  bool due() const { return due_; }
  const char* reason() const { return reason_; }
  const Balance& balance() const { return balance_; }
  void restore_balance(const std::vector<double>& after_cut_largest) {  // (a checkpoint's: RunLoop)
    balance_.after_cut = after_cut_largest.at(0);
    balance_.largest = after_cut_largest.at(1);
  }
  // The own nodes' positions where the parts were cut (checkpoints keep them).
  const Kokkos::View<double* [D]>& cut_positions() const { return xcut_; }

  // This process's modelled work of a step (ns); with a non-empty `node_work` (m.nn entries) the
  // own surface points' contact work is also added there per node. contact: null without.
  double modelled_work(const Model<D>& m, const ContactSystem<D>* contact,
                       const Kokkos::View<double*>& node_work = {}) const;
  // Collective, at a cut: each node's contact work (ns per step) in the whole mesh's order, on
  // process 0 (empty elsewhere): the weights of the next cut.
  std::vector<double> node_work_whole(const Model<D>& m, const ContactSystem<D>* contact,
                                      const Parts<D>& parts) const;

 private:
  bool started_ = false;   // start(): a part of a run over processes
  double zone_reach_ = 0;  // SubMesh::contact_reach
  Kokkos::View<double* [D]> xcut_;
  bool due_ = false;
  const char* reason_ = "";
  double rebalance_above_ = 0.2;
  WorkModel work_model_;
  Balance balance_;
  long test_every_ = 0, next_test_cut_ = -1;  // FDEM_TEST_RECUT
  void ask(const char* why) {
    if (!due_) reason_ = why;
    due_ = true;
  }
};

extern template class CutChecks<2>;
extern template class CutChecks<3>;

}  // namespace fdem
