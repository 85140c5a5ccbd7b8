// The two decompositions of a run as the run loop sees them (solver/run_parts.hpp): one process,
// and the parts of a run over processes.
#include "solver/run_parts.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "solver/summary.hpp"
#include "solver/whole_state.hpp"

namespace fdem {

namespace {

// One process: its Simulation's state is the run's; it labels the fragments of its own model and
// looks for a signal at every step.
template <int D>
class OnePart final : public RunParts<D> {
 public:
  explicit OnePart(Simulation<D>& sim) : sim_(sim) {}
  void load(const StateArrays& r) override { sim_.load_state(r); }
  bool save(StateArrays& st, std::vector<RowPart>*) const override {
    sim_.save_state(st);
    return true;
  }
  long long checkpoint_access() const override { return -1; }
  std::unique_ptr<RunFragments<D>> fragments(const std::string& out, const RunState* restart,
                                             const std::string& file) const override {
    return std::make_unique<RunFragments<D>>(sim_.m, out, restart, file);
  }
  long interrupt_poll() const override { return 1; }
  const char* restart_note() const override { return ""; }
  const char* exit_note() const override { return ""; }
  void announce() const override {}
  void report(nlohmann::json&, const Case&, std::chrono::steady_clock::time_point, double) const override {}

 private:
  Simulation<D>& sim_;
};

// A part of a run over processes: the whole run's state gathered on process 0 and given back to
// the parts (solver/whole_state.hpp), checked after every cut; each process labels the fragments
// of its part and process 0 joins them (solver/fragment_parts.hpp).
template <int D>
class ManyParts final : public RunParts<D> {
 public:
  ManyParts(Simulation<D>& sim, CutHistory& cuts, bool began_at_cut)
      : sim_(sim), cuts_(cuts), began_at_cut_(began_at_cut), writes_(sim.parts().root()) {}

  // Each part takes its rows; after a cut it checks them; from a checkpoint on as many processes
  // the balance is as it was (the excess after the last cut decides the next rebalance; on another
  // count the first check measures it anew).
  void load(const StateArrays& r) override {
    load_whole_state(sim_, r);
    if (began_at_cut_)
      check_cut(r);
    else if (r.f64.count("processes/balance") && r.has("processes/count") &&
             r.get_int("processes/count") == sim_.parts().size())
      sim_.restore_balance(r.array("processes/balance", 2));
  }
  // The whole run's state on process 0 with the cuts so far (how a restart cuts its parts:
  // solver/run_processes.cpp) and the balance.
  bool save(StateArrays& st, std::vector<RowPart>* rows) const override {
    save_whole_state(sim_, st, rows);
    if (!writes_) return false;
    cuts_.save(st);
    st.f64["processes/balance"] = {sim_.balance().after_cut, sim_.balance().largest};
    return true;
  }
  // with the parallel HDF5 each process writes its rows (collective), unless asked to gather
  long long checkpoint_access() const override {
    return gather_outputs() ? -1 : sim_.parts().comm().h5_parallel_access();
  }
  std::unique_ptr<RunFragments<D>> fragments(const std::string& out, const RunState* restart,
                                             const std::string& file) const override {
    return std::make_unique<RunFragments<D>>(sim_, out, writes_, restart, file);
  }
  // A signal reaches each process at its own moment: they look together, every kInterruptPoll
  // steps, and stop at the same step if any has one (else some would wait forever for the others'
  // exchange).
  long interrupt_poll() const override { return kInterruptPoll; }
  const char* restart_note() const override { return "; under mpirun with any number of processes, or without"; }
  // Kept as it is on purpose: mpirun decides its own exit status.
  const char* exit_note() const override {
    return "fdem: every process exits with 128 + the signal, which mpirun passes on when the signal reached the "
           "processes (srun, a kill of the processes); Open MPI's mpirun exits with 1 when the signal was sent to "
           "mpirun itself: summary.json's stop_reason \"interrupted\" and the checkpoint say the run stopped\n";
  }
  void announce() const override {
    const Model<D>& m = sim_.m;
    std::fprintf(stderr,
                 "fdem: %d processes; this one (0) holds %d of the nodes (%d ghosts), %d elements (%d ghosts); "
                 "ghost positions sent per step: %ld bytes\n",
                 sim_.parts().size(), m.nn, m.nn - m.owned_nodes(), m.ne, m.ne - m.owned_elems(),
                 sim_.exchange_bytes());
  }
  void report(nlohmann::json& summary, const Case& c, std::chrono::steady_clock::time_point loop_start,
              double cut_setup) const override {
    summary["processes"] = processes_report(c, sim_, cuts_, loop_start, cut_setup);
  }

 private:
  static constexpr long kInterruptPoll = 64;
  Simulation<D>& sim_;
  CutHistory& cuts_;
  const bool began_at_cut_;  // the parts began at a cut: their state is the cut's, not a checkpoint's
  const bool writes_;        // process 0

  // After a cut (every cut: the check costs one more gather of the state): the new parts hold the
  // state they were given, and the same mass and momentum (summed in another order: to 1e-12 of
  // the mass, and of the sum of m |v_k|).
  void check_cut(const StateArrays& given) const {
    check_whole_state(sim_, given);
    std::vector<double> before(5, 0.0);
    if (writes_) before = given.array("recut/mass_momentum", 5);
    const std::vector<double> after = whole_mass_momentum(sim_);
    if (!writes_) return;
    bool ok = std::fabs(after[0] - before[0]) <= 1e-12 * before[0];
    for (int k = 1; k < 4; ++k) ok = ok && std::fabs(after[k] - before[k]) <= 1e-12 * before[4];
    if (ok) return;
    char msg[320];
    std::snprintf(msg, sizeof msg,
                  "internal error: the parts cut anew hold mass %.17g and momentum (%.17g, %.17g, %.17g), "
                  "not %.17g and (%.17g, %.17g, %.17g)",
                  after[0], after[1], after[2], after[3], before[0], before[1], before[2], before[3]);
    throw std::logic_error(msg);
  }
};

}  // namespace

template <int D>
std::unique_ptr<RunParts<D>> make_run_parts(Simulation<D>& sim, const RunOptions& opt, const SubMesh* part,
                                            CutHistory& cuts, const StateArrays* restart) {
  if (!part) return std::make_unique<OnePart<D>>(sim);
  // the processes agree on the time step, the ghosts take their owners' state
  sim.set_decomposition(opt.comm, *part);
  return std::make_unique<ManyParts<D>>(sim, cuts, restart && restart == &cuts.state);
}

template std::unique_ptr<RunParts<2>> make_run_parts<2>(Simulation<2>&, const RunOptions&, const SubMesh*,
                                                        CutHistory&, const StateArrays*);
template std::unique_ptr<RunParts<3>> make_run_parts<3>(Simulation<3>&, const RunOptions&, const SubMesh*,
                                                        CutHistory&, const StateArrays*);

}  // namespace fdem
