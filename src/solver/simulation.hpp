#pragma once
// One run's state on the device and the explicit time loop's building blocks. Templated on the
// dimension (2, 3) and instantiated for both: the constructor in model_builder.cpp (one build
// step per module, solver/model_builder.hpp), the rest in simulation.cpp.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "kernels/checks.hpp"
#include "kernels/forces.hpp"
#include "kernels/halo.hpp"
#include "kernels/model.hpp"
#include "kernels/nodes.hpp"
#include "kernels/outputs.hpp"
#include "kernels/platens.hpp"
#include "mesh/mesh.hpp"
#include "parallel/comm.hpp"
#include "parallel/decompose.hpp"
#include "parallel/parts.hpp"
#include "solver/contact_system.hpp"
#include "solver/cut_checks.hpp"
#include "solver/ledger.hpp"
#include "solver/loads.hpp"
#include "solver/platens.hpp"
#include "solver/stable_step.hpp"

namespace fdem {

// Wall time of each phase of step(), summed over the timed steps so far (s): the sampled ones (an
// unsampled step waits for no clock). The kernels of a phase are fenced before its clock stops, so
// on a GPU backend the figures are the phases' own times.
struct PhaseTimes {
  double forces = 0;   // bulk elements and cohesive interfaces (the fused force kernel)
  double platens = 0;  // rigid platens
  double contact = 0;  // handover, broad phase, narrow phase, and the one contribute of the forces
  double ledger = 0;   // energies, reactions and momentum on sampled steps
  double nodes = 0;    // node update (damping, velocity BCs, leap-frog)
  // A run over several processes: the exchange of the ghost positions (pack, MPI, unpack), timed
  // on every step (it waits for the step's kernels anyway).
  double exchange = 0;
  long steps = 0;  // all steps
  long timed = 0;  // the timed ones
};

template <int D>
class Simulation {
 public:
  // mesh: after interface insertion. The case supplies materials, loads, platens, damping.
  Simulation(const Case& c, const HostMesh& mesh);

  Model<D> m;
  double t = 0, dt = 0;  // time; step from the present positions to the next
  long step_count = 0;
  StableStep stable;

  // One explicit step. With sample = true the energies at the step's start time are computed
  // (full reductions: do it on output and check steps only) and kept for energies().
  void step(bool sample = false);
  // The node update of step(): advances x and v from the forces in m.f and zeroes m.f (public for
  // the benchmarks; step() calls it). Unsampled: the sums stay on the device (zeros returned).
  NodeSums update_nodes_now(bool sample);
  // The velocity step of the last node update: (dt before + dt after) / 2 on the step where dt
  // changed, dt otherwise (the momentum change of a node over a step is its force times this).
  double last_velocity_step() const { return prm_.dtv; }
  // Step on which the time step last changed (contact's stable step applied), -1 if never; the
  // step before the change.
  long dt_changed_at() const { return dt_changed_at_; }
  // Applies contact's stable step now instead of when surfaces can meet (the benchmark's "skip
  // off"; call it before the first step).
  void use_contact_step_now() {
    if (stable.contact_pending) take_contact_step();
  }
  double dt_before_change() const { return dt_before_change_; }
  // What the time step was decided from (this model's smallest bulk, spring and platen steps).
  const StepContributions& step_contributions() const { return step_sources_; }
  // One part of a decomposed run, before its first step: decides the time step from the
  // contributions of all parts (`all`: smallest() over them), so that every part takes the step
  // of the whole run.
  void agree_time_step(const StepContributions& all);
  // One part of a run over several processes (this model built from part.mesh,
  // src/parallel/decompose.hpp), before the first step: the processes agree on the time step,
  // the ghosts take their owners' positions, and from then on every step ends with that exchange
  // and every sum the run reports (energies, momentum, counts, platen forces, reactions, inverted
  // elements) is over all processes, the same on each.
  void set_decomposition(std::shared_ptr<const Comm> comm, const SubMesh& part);
  // The decomposition (src/parallel/parts.hpp): on one process the trivial one.
  const Parts<D>& parts() const { return parts_; }
  // Over several processes: the whole mesh's index of each local interface (the counted ones,
  // first owned_ifaces() of m, then the others).
  const std::vector<int>& ifaces_global() const { return parts_.iface_global(); }
  // Bytes of ghost positions this process sends per step (0 on one process).
  long exchange_bytes() const { return parts_.exchange_bytes(); }
  // Work skipped because the scene does not need it (the results are the same either way; the
  // switches exist for the tests and benchmarks that show it): no damping force or damping work
  // while both damping coefficients are zero.
  struct Skips {
    bool damping = true;
  } skips;
  // Wall time per phase of step() so far (run summary: seconds and share per phase).
  const PhaseTimes& phase_times() const { return phase_times_; }
  // Energies at the last sampled step (the first step is always sampled).
  const Energies& energies() const { return energies_; }
  // Takes the state at the next step as the energy reference (after changing x or v by hand).
  void reset_energy_reference() { have_reference_ = false; }
  // Throws NumericalError naming the step, time and the first node whose state is not finite.
  void check_finite();
  // Number of elements whose orientation has flipped (turned inside out); with `where`, a message
  // naming the first of them and its position. check_stability warns once per run.
  long check_inverted(std::string* where = nullptr);
  // check_finite, then the energy balance: energy appearing from nowhere (more than half the
  // energy scale) means the integration is unstable. Throws NumericalError with step, time and dt.
  void check_stability();
  // The rigid platens (solver/platens.hpp).
  const Platens<D>& platens() const { return platens_; }
  // Platen force on the body (3 components) of the last step, and its displacement along its
  // velocity direction at time `at`.
  std::array<double, 3> platen_force(int p) const { return platen_forces()[p]; }
  // The same for every platen, with one copy from the device (none when the ledger took it).
  std::vector<std::array<double, 3>> platen_forces() const { return platens_.forces(m, parts_, step_count); }
  double platen_displacement(int p, double at) const { return platens_.displacement(m, p, at); }
  // Reaction force of velocity BC b (sum over its node set of minus the internal force), from the
  // forces of the last step (call before step() clears them: use sample_reactions()).
  const std::vector<std::array<double, 3>>& reactions() const { return loads_.reactions(); }
  void set_sample_reactions(bool on) { sample_reactions_ = on; }

  // Host copies for snapshots. Over several processes (set_decomposition) every process must call
  // it: the own items are gathered into the whole mesh's order on process 0, whose arrays are then
  // the whole run's; the others' are left empty.
  // gather = false: every process keeps its own rows (the first m.owned_*() of each array; see
  // whole_rows()), for each to write them itself (src/io/snapshot_parallel.hpp).
  void download(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                std::vector<double>& stress, std::vector<double>& damage, bool gather = true);
  // Over several processes: the whole mesh's index of each local node, element and interface (own
  // ones first), and the whole mesh's counts of each.
  struct WholeRows {
    const std::vector<int>&nodes, &elems, &ifaces;
    long nn, ne, ni;
  };
  WholeRows whole_rows() const {
    return {parts_.node_global(), parts_.elem_global(), parts_.iface_global(),
            parts_.whole_nodes(), parts_.whole_elems(), parts_.whole_ifaces()};
  }

  // Contact between bodies and fragments (null when the case has it off; see solver/contact_system.hpp).
  ContactSystem<D>* contact() { return contact_.get(); }
  const ContactSystem<D>* contact() const { return contact_.get(); }
  // The force kernel's scatter view (benchmarks: contact updates timed on their own add into it).
  ForceScatter<D>& force_scatter() { return scatter_; }
  // Changes the damping from the next step on (e.g. settle quasi-statically, then run dynamically).
  void set_damping(double local, double mass_proportional) {
    prm_.alpha = local;
    prm_.cmass = mass_proportional;
  }

  // Strength reduction (slope stability): divides the interface strengths f_t, c and tan(phi) of
  // the case, and the friction coefficient of the contacts (crack faces of the same rock), by
  // `factor` (> 0) from the next step on. Points whose damage has initiated follow it: their
  // softening envelope moves with the strength at the next force computation, the damage rises
  // at fixed separation and the energy released is fracture dissipation (cohesive_update,
  // CohesiveParams::rescale). The fracture energies stay.
  void set_strength_reduction(double factor);
  double strength_reduction() const { return srf_; }

  // Checkpoint: everything in the model and this object that changes during a run (time, step,
  // positions, velocities, forces, interface history and handover flags, platen springs and
  // accumulators, damping and strength parameters, energy accumulators and reference, the last
  // sampled energies, and the contact system), under "simulation/", "model/" and "contact/".
  // load_state checks the sizes and throws InputError naming the checkpoint file. Over several
  // processes this is one process's state; the whole run's is gathered from them and given back by
  // solver/whole_state.hpp (load_state is then collective: it ends with the ghosts taking their
  // owners' state and the processes agreeing whether surfaces may meet).
  void save_state(StateArrays& s) const;
  void load_state(const StateArrays& s);

  const std::vector<std::string>& platen_names() const { return platens_.names(); }
  const std::vector<std::string>& bc_names() const { return loads_.names(); }
  // Boundary conditions and loads (solver/loads.hpp).
  const Loads<D>& loads() const { return loads_; }

 private:
  ForceScatter<D> scatter_;
  Parts<D> parts_;  // one process: the trivial decomposition
  bool force_pass_contributes_ = true;  // Parts::force_pass_contributes
  void gather_whole(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                    std::vector<double>& stress, std::vector<double>& damage);

 public:  // (nvcc: a function that holds a device lambda must be public)
  // Contact over several processes (docs/parallel.md "Contact"): each process computes the contacts
  // of its own surface nodes against every face it holds (its contact zone); the forces they put on
  // ghost nodes go back to the owners (Parts::return_ghost_forces). contact_meet_: whether surfaces
  // can meet on any process, agreed by agree_on_contact on the steps the contact systems poll for
  // failed interfaces (the only steps on which a contact system's word changes), with the checks
  // of the zones and of the balance (solver/cut_checks.hpp). Called by step() on the poll steps.
  // One process agrees with itself and has no zones to check.
  void agree_on_contact();
  // contact_meet_ from every process's contact system (collective).
  void agree_on_meeting();
  // Whether surfaces can meet anywhere (contact's stable step then applies): over several
  // processes as agreed on the last poll step, so that every process changes its step on the same
  // step; on one process its contact system's word, at once (CutChecks::may_meet).
  bool surfaces_may_meet() const { return cuts_.may_meet(contact_meet_, *contact_); }
  // Over several processes with contact: whether the parts are to be cut anew, why, and the
  // balance, checked on contact's poll steps (solver/cut_checks.hpp); the run loop then cuts them
  // anew at the current positions (solver/run.cpp).
  using Balance = typename CutChecks<D>::Balance;
  bool recut_due() const { return cuts_.due(); }
  const char* recut_reason() const { return cuts_.reason(); }
  const Balance& balance() const { return cuts_.balance(); }
  const CutChecks<D>& cut_checks() const { return cuts_; }
  void restore_balance(const std::vector<double>& after_cut_largest) { cuts_.restore_balance(after_cut_largest); }
  // This process's modelled work of a step (ns; WorkModel); with a non-empty `node_work` (m.nn
  // entries) the own surface points' contact work is also added there per node.
  double modelled_work(const Kokkos::View<double*>& node_work = {}) const {
    return cuts_.modelled_work(m, contact_.get(), node_work);
  }
  // Over several processes (collective, at a cut): each node's contact work (ns per step) in the
  // whole mesh's order, on process 0 (empty elsewhere): the weights of the next cut.
  std::vector<double> node_work_whole() const { return cuts_.node_work_whole(m, contact_.get(), parts_); }

 private:
  bool contact_meet_ = false;
  CutChecks<D> cuts_;  // over several processes with contact: when to cut the parts anew
  CohesiveParams coh0_{};  // interface parameters as given (before strength reduction)
  double mu0_ = 0;         // contact friction coefficient as given
  double srf_ = 1;         // strength reduction factor now
  double srf_hist_ = 1;    // the factor the interface histories were last updated under
  std::unique_ptr<ContactSystem<D>> contact_;
  Platens<D> platens_;
  bool warned_inverted_ = false;
  NodeUpdateParams prm_{};
  double dtv_next_ = 0;  // velocity step of the next node update when dt has just changed
  long dt_changed_at_ = -1;
  double dt_before_change_ = 0;
  StepContributions step_sources_;  // what the stable step is decided from (solver/stable_step.hpp)
  void take_contact_step();   // dt and the stable-step estimates become those with contact
  void apply_contact_step();  // the same during a run (the velocity step of the change)
  // The ledger of step(): the energies stored at time t (sample: else only time and step); after
  // the node update, the works and the balance (sample).
  Energies sample_energies(bool sample);
  void book_energies(Energies& e, const NodeSums& w, bool sample);
  // The checkpoint entries under "simulation/" and "model/", one list walked by save_state
  // (StateSaver) and load_state (StateLoader) (solver/state_fields.hpp).
  template <class Fields>
  void checkpoint_fields(Fields& f);
  // Works of damping, velocity BCs and ramped point loads so far: on the device (work_dev_:
  // 0 damping, 1 BCs, 2 ramped loads, summed there on every step: kernels/nodes.hpp); the host
  // copies are read on sampled steps and for a checkpoint (pull_works), and written only by a
  // restart (push_works).
  mutable double work_damping_ = 0, work_bc_ = 0, work_ramp_ = 0;
  Kokkos::View<double[3]> work_dev_{"fdem::work"};
  Kokkos::View<NodeSums> node_sums_{"fdem::node_sums"};
  void pull_works() const;
  void push_works();
  double reference_ = 0;  // energy minus external work at the reference step
  bool have_reference_ = false;
  double energy_floor_ = 0;  // energies below this are round-off (strain energy at strain 1e-6)
  Energies energies_;
  PhaseTimes phase_times_;
  Loads<D> loads_;
  bool sample_reactions_ = false;
};

extern template class Simulation<2>;
extern template class Simulation<3>;

}  // namespace fdem
