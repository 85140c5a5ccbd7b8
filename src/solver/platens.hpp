#pragma once
// The rigid platens' host side, in one place (docs/developing.md, "The module shape"): their build
// (the outer boundary's nodes and areas, the platens, their springs' storage and stable steps),
// the step's call, the surface nodes they act on once contact has surfaces, their terms of the
// energy ledger, their forces, loads and displacements, their history columns and their checkpoint
// entries. The device side is kernels/platens.hpp (the penalty and Coulomb spring on each node,
// the energy, the areas of new surface nodes). Simulation owns one and calls it; nothing else
// about platens lives in the solver.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "kernels/platens.hpp"
#include "mesh/mesh.hpp"
#include "parallel/parts.hpp"
#include "solver/stable_step.hpp"

namespace fdem {

template <int D>
class ContactSystem;

template <int D>
class Platens {
 public:
  // The case's platens on the outer boundary nodes of `mesh` (a part's own ones), their springs'
  // storage and the accumulators (one row even without platens); the springs' stable step on the
  // boundary nodes into sc.platens. mass: the lumped nodal masses.
  void build(const Case& c, const HostMesh& mesh, const std::vector<double>& mass, Model<D>& m,
             StepContributions& sc);
  // With contact: the springs' stable step on every potential surface node at its largest contact
  // area (ContactSystem::take_potential_area) into sc.platens_on_surfaces.
  void contact_step(const Model<D>& m, const std::vector<double>& amax, const std::vector<double>& mass,
                    StepContributions& sc);
  // With contact: the platens act on the contact system's own surface nodes with their areas (on
  // the first call and whenever the surfaces have changed since the last).
  void follow_surfaces(Model<D>& m, const ContactSystem<D>& contact, double t);
  // A decomposed run: a driven platen's stable step on the springs of the whole body at once (each
  // part's own share of them summed over the parts) into sc.platens and sc.platens_on_surfaces.
  void weight_steps(const Parts<D>& parts, const Model<D>& m, StepContributions& sc) const;
  bool surfaces_changed(const ContactSystem<D>& contact) const;

  // The step's call: the springs' forces into m.f and the accumulators (kernels/platens.hpp).
  void apply(const Model<D>& m, double t, double dt) const { apply_platens<D>(m, t, dt); }

  // The ledger's terms (solver/ledger.hpp). Stored: the springs' energy at time t. After the node
  // update of a sampled step: the work done by time t (the accumulated work less the half of this
  // step's increment after t) and the friction dissipated, from one copy of the accumulators, which
  // then serves forces() until the next step (`stamp`: the steps done after this one).
  double stored_energy(const Model<D>& m, double t) const { return platen_energy<D>(m, t); }
  void book(const Model<D>& m, double t, double dt, long stamp, double& work, double& friction) const;

  // Each platen's force on the body (3 components) of the last step, summed over the processes;
  // `stamp`: the steps done (a copy of the accumulators is taken unless book() took one for it).
  std::vector<std::array<double, 3>> forces(const Model<D>& m, const Parts<D>& parts, long stamp) const;
  // The load: the force along the platen's normal.
  static double load(const PlatenDev& P, const std::array<double, 3>& F) {
    return F[0] * P.n[0] + F[1] * P.n[1] + F[2] * P.n[2];
  }
  // Platen p's displacement (the distance it has moved) at time `at`: for a driven platen (a mass)
  // `at` is the time of the last step's forces (the history's rows and load samples).
  double displacement(const Model<D>& m, int p, double at) const;
  // After the node update: a driven platen's speed and travel from the total force on the body
  // (summed over the processes), its work of this step (kernels/platens.hpp: advance_platens);
  // dtv: the nodes' velocity step.
  void advance(const Model<D>& m, const Parts<D>& parts, double dt, double dtv) const;
  const std::vector<std::string>& names() const { return names_; }

  // history.csv: per platen its displacement, force components and load, then each driven platen's
  // speed; and a row's values.
  void add_columns(std::vector<std::string>& cols) const;
  void append_row(const Model<D>& m, const std::vector<std::array<double, 3>>& forces, double t,
                  std::vector<double>& row) const;

  // Checkpoint entries (one list for save and load: Simulation::checkpoint_fields). The springs,
  // allowances and areas are stored per node id (every node, zero where the platens do not act:
  // the layout of the checkpoints written when they were kept so), whatever list of nodes the
  // platens act on; loaded, they wait for that list (settle_loaded: follow_surfaces with contact).
  template <class Fields>
  void checkpoint_fields(Fields& f, Model<D>& m) {
    const long long np = m.platens.count, nn = m.nn;
    for (const int which : {kFs, kG0, kArea}) {
      if (which == kArea && np == 0) continue;  // (no platens: no areas)
      const long long n = (which == kArea ? 1 : np) * nn * (which == kFs ? D : 1);
      f.values(kRowNames[which], n, [&] { return node_rows(m, which); },
               [&, which](const std::vector<double>& a) {
                 if (np == 0) return;
                 loaded_[which] = a;
                 loaded_nn_ = static_cast<size_t>(nn);
               });
    }
    f.view("model/platen_acc", m.platen_acc);
    f.view("model/platen_motion", m.platen_motion, driven_);  // (the same on every process)
    cached_at_ = -1;  // (loaded: the next forces() copies)
  }
  // Loaded rows (checkpoint_fields) into the rows of the list `to` acts on (Simulation::load_state
  // without contact: m itself; with contact follow_surfaces does it); nothing when none are loaded.
  void settle_loaded(PlatenData<D>& to);

 private:
  std::vector<std::string> names_;
  bool driven_ = false;              // a platen with a mass
  // per platen: the spring stiffness of all its own boundary nodes, of all its own potential
  // surface nodes at their largest areas (N/m; its stable step as a driven platen: weight_steps)
  std::vector<double> weight_kA_, weight_kA_surfaces_;
  std::vector<bool> driven_platen_;  // per platen
  long surface_version_ = -1;  // contact surfaces the node list was taken from
  mutable long cached_at_ = -1;  // the stamp of acc_host_'s copy
  mutable decltype(Kokkos::create_mirror_view(Kokkos::View<double* [kPlatenAcc]>())) acc_host_;
  mutable decltype(Kokkos::create_mirror_view(Kokkos::View<double* [kPlatenMotion]>())) motion_host_;
  void copy_accumulators(const Model<D>& m, long stamp) const;
  // The checkpoint's per-node entries: which one (kFs, kG0, kArea), their names, the values of m's
  // rows spread over every node id (node_rows), and those loaded until settle_loaded takes them
  // (loaded_nn_: the nodes they were loaded for).
  enum { kFs = 0, kG0 = 1, kArea = 2 };
  static constexpr const char* kRowNames[3] = {"model/platen_fs", "model/platen_g0", "model/platen_area"};
  std::vector<double> node_rows(const Model<D>& m, int which) const;
  std::map<int, std::vector<double>> loaded_;
  size_t loaded_nn_ = 0;
};

extern template class Platens<2>;
extern template class Platens<3>;

}  // namespace fdem
