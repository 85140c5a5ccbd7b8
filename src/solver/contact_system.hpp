#pragma once
// Contact between deformable bodies and fragments (docs/theory.md section 6b): host orchestration of
// the device kernels in kernels/contact/ (it calls their launchers only; see kernels/contact.hpp).
// Owned by Simulation<D>, called once per step after the platens and before the node update.
//
// Surfaces: the outer boundary faces of every body (always active) and both faces of every
// interface, active once the interface has failed (all its points at D = 1); the cohesive kernel
// then skips that interface ("handover"). The surface nodes are the nodes of active faces.
// A node and a face are never in contact when the node belongs to the face's element or when the
// node and a vertex of the face are copies of one mesh vertex still joined by intact interfaces
// around that vertex (they are one piece of material there). The outer boundary of a body is thus
// checked against other bodies and fragments; a single intact body is not checked against itself
// (no self-contact of a folding body), and contact does no work at all until a second body exists
// or an interface has failed.
//
// Broad phase: uniform cell grid + candidate lists, rebuilt only when a surface node has moved
// more than half the skin since the last build. The lists are those of a search at the positions
// of the last build (xb, kept for every node); a handover adds and removes the pairs of the new
// and changed surfaces by a local search at xb (kernels/contact/list_update.hpp) instead of a
// rebuild, unless a surface node is already beyond half the skin. Narrow phase every step over the
// candidates.
//
// Synchronisation (GPU readiness): a step waits for the device only on the steps that re-check
// something on the host; there the host reads one small device value, labelled kContactSyncLabel
// (two on a step that both polls the handover flag and re-checks the lists).
// - The handover flag (set by the force kernel; a part of a run over processes reads the count of
//   handovers instead) every kContactPollEvery steps while interfaces are left. A step that hands interfaces over waits for the device like a rebuild (counts, sizes);
//   after a local update of the lists (no rebuild), the next step re-checks them (its status
//   includes the new surface nodes).
// - The status of the narrow phase (ContactStatus: totals and the largest displacement since the
//   build and the largest speed) on the steps the candidate lists are re-checked. A check at step s
//   sees the pass of step s - 1 (displacement d, speed v): the lists are rebuilt when
//   d + 2 v dt > skin / 2 (the test of every step before: the displacement at the next step is
//   bounded by this one plus a step at twice the largest speed), else the next check comes after
//   K = floor((skin / 2 - d) / (2 v dt)) steps (at most kMaxRecheckInterval; not tied to the poll
//   of the handover flag). While the speeds stay below twice v, no step in between meets the
//   rebuild test, so the lists are rebuilt on the same steps as by a check on every step (checks
//   come every step as the bound nears half the skin). Passes on outdated lists (a node beyond half
//   the skin from its build position) are counted on the device (stale_passes) and lead to a
//   rebuild at the next check.
// The energies and statistics read the status when asked (sampled steps).
#include <memory>
#include <utility>
#include <vector>

#include "kernels/contact.hpp"
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"
#include "kernels/model.hpp"
#include "solver/contact_topology.hpp"

namespace fdem {

// Label of the device values the contact system reads on its re-check steps (tests/test_gpu_ready.cpp).
inline constexpr char kContactSyncLabel[] = "fdem::contact::sync";

// Steps between two polls of the handover flag (failed interfaces handed over to contact; on these
// steps the processes of a decomposed run also check their contact zones). The zone-safety check
// in src/solver/cut_checks.cpp (CutChecks::check: a node may move 2 v dt per step for this many
// steps until the next check) depends on it.
inline constexpr int kContactPollEvery = 25;

// The contact law's penetration depth (ContactLaw::dpen; also the contact zone's reach in
// src/solver/run.cpp): a node deeper than a quarter of the thinnest element behind a face is not in
// contact with it (it would be nearer the face's back side), so a quarter of the smallest element
// size (the mean size where the mesh has no positive smallest size).
inline double contact_penetration_depth(double min_size, double mean_size) {
  return 0.25 * (min_size > 0 ? min_size : mean_size);
}

// The default of ContactSystem::team_above: on GPUs kNarrowTeamAbove (the build's
// FDEM_NARROW_TEAM_ABOVE), or the environment variable of that name, a whole number >= 0 (so
// that a GPU's first minutes can compare bounds without a build each; docs/cuda.md); host
// backends 0. A malformed value is an InputError naming it.
int narrow_team_above();
// The value of FDEM_NARROW_TEAM_ABOVE as narrow_team_above reads it (null or empty: fallback).
int parse_narrow_team_above(const char* value, int fallback);

template <int D>
class ContactSystem {
 public:
  // mesh: after interface insertion; mass: lumped nodal masses (for the stable step). Allocates
  // the contact data and the interface handover flags in m.
  ContactSystem(const Case& c, const HostMesh& mesh, Model<D>& m, const std::vector<double>& mass);

  // The step's poll (Simulation::step calls it before the internal forces, so that an interface
  // handed over at the poll acts no more in that step and its nodes' contacts take its state over
  // in that step's update; every kContactPollEvery steps while interfaces are left): hands failed
  // interfaces over when the force kernel has flagged one (one process) or at every poll (a part).
  void poll(const Model<D>& m);
  // One step at positions m.x and velocities m.v (v(n-1/2)) after the poll: rebuilds the
  // candidate lists when needed, adds the contact forces to sf (the force kernel's scatter view
  // before its contribute: Simulation::step), or, without sf, to m.f (through a scatter view of
  // its own: tests).
  using Scatter = ForceScatter<D>;
  void update(const Model<D>& m, double dt, Scatter& sf);
  void update(const Model<D>& m, double dt);  // poll, then update (tests)
  // Hands every failed interface over now (update() does it when the force kernel flags one).
  void check_failures(const Model<D>& m);

  // Smallest stable step of the contact springs, 2 / omega with omega^2 = 2 max(K_n, K_s) A / m
  // per surface node (A: its tributary area on all faces that can become surfaces, m: its mass;
  // 2: the mass on the other side, see the constructor).
  double stable_step() const { return stable_; }
  // Elastic energy in the contact springs at the last update.
  double elastic_energy() const;
  // Energy dissipated by friction (and released shear springs) so far (reads the device status).
  double dissipated() const { return read_status().dissipated; }

  ContactLaw law{};      // penalty, friction, tolerances (public: tests change friction)
  // Frictionless contact (law.mu = 0, law.coh = 0) computes and stores no shear springs (same
  // results; off only for the tests and benchmarks that show it).
  bool skip_frictionless = true;
  // Tests: subsets of 1 pair per node in the narrow phase (kernels/contact/narrow_phase.hpp,
  // PairSubset), so that nodes with more relevant pairs take the overflow path (same results).
  bool small_subsets = false;
  // The narrow phase's points with more candidates than this share their gaps among a team's
  // threads (kernels/contact/narrow_phase.hpp, ContactTeamPoints): on GPUs by default
  // (kNarrowTeamAbove, or the environment's FDEM_NARROW_TEAM_ABOVE: narrow_team_above); 0, one
  // thread per point (host backends; tests set it to check the teams).
  int team_above = narrow_team_above();
  double skin = 0;       // Verlet skin (m)
  double radius = 0;     // search distance = law.dpen + skin

  // Statistics.
  bool may_meet() const { return may_meet_; }
  int surface_nodes() const { return ns_; }
  // A part of a decomposed run (the mesh's owned_nodes >= 0; docs/parallel.md "Contact"): the
  // surface nodes it owns, the first of surface_node_list(). The narrow phase computes the contacts
  // of these only (each contact once over the parts: its node's owner computes it, and the forces
  // it puts on ghost nodes go back to their owners); the others are followed for the Verlet test.
  // On one process: surface_nodes().
  int own_surface_nodes() const { return ns_own_; }
  // Whether the last update() looked for failed interfaces (every kContactPollEvery steps; a part
  // does so on the same steps as every other part).
  bool polled() const { return polled_; }
  int active_faces() const { return na_; }
  int candidates() const { return cur_.size; }
  // How the candidates spread over the surface points that get contacts (the narrow phase's work
  // per point; a GPU's warp waits for its point with the most, ContactTeamPoints): the largest
  // count, and the points and their candidates above each of kSpreadBounds (the bounds of
  // spread_of_candidates, kernels/contact/narrow_phase.hpp).
  static constexpr int kSpreadBins = 4;
  static constexpr int kSpreadBounds[kSpreadBins] = {16, 32, 64, 128};
  struct CandidateSpread {
    int max = 0;
    long points = 0, pairs = 0;
    long points_above[kSpreadBins] = {}, pairs_above[kSpreadBins] = {};
  };
  CandidateSpread candidate_spread() const;
  // The narrow phase's work of this process's own surface points, in its units (kPointWork per
  // point plus the point's candidates; kernels/contact/narrow_phase.hpp), for the balance of a run
  // over processes (CutChecks::modelled_work, solver/cut_checks.hpp): the sum, and with a non-empty `w` also added per
  // node, w(node) += units * scale. 0 while no surfaces can meet (no narrow phase runs).
  double own_point_work(const Kokkos::View<double*>& w = {}, double scale = 1.0) const;
  int active_contacts() const;  // in the last pass (reads the device status)
  long builds() const { return builds_; }
  // Handovers that updated the candidate lists by a local search instead of a rebuild.
  long list_updates() const { return updates_; }
  // Host reads of device values during update() so far (the re-check steps), and passes over
  // candidate lists that were outdated (reads the device status; 0 unless the speeds grew by more
  // than the margin of the re-check schedule).
  long syncs() const { return syncs_; }
  long stale_passes() const { return static_cast<long>(read_status().stale); }
  // Changes whenever the surfaces change (active faces, surface nodes, contact areas).
  long surface_version() const { return surface_version_; }
  // Each node's largest possible contact area for rigid platens (its share of every face it can
  // ever be part of: outer boundary and both faces of interfaces; host), handed over once (the
  // set-up's platen step needs it; a node's double not held through the run).
  std::vector<double> take_potential_area() { return std::move(potential_area_); }
  long handed_over() const { return handed_; }
  // Handover checks that found the flag set (the step waits for the device: counts, sizes).
  long handover_checks() const { return checks_; }
  int bodies() const { return bodies_; }

  // Device data (read by tests).
  const PairList<D>& pairs() const { return cur_; }
  const Kokkos::View<int*>& surface_node_list() const { return slaves_; }
  // Each node's place in surface_node_list() plus one (0: not a surface node; every node id).
  const Kokkos::View<int*>& surface_places() const { return mark_; }
  const ContactSurface<D>& surface() const { return surf_; }
  const Kokkos::View<double* [D]>& build_positions() const { return xb_; }

  // Checkpoint: everything that changes during a run (pair lists with their history, positions at
  // the last build, node contact areas, counters), under "contact/". load_state needs the model's
  // interface handover flags (m.icontact) loaded first: it recomputes the surfaces from them.
  // Also "contact/pairs": the pairs of the own surface nodes that hold a history (a spring, a gap
  // or a force not zero), kPairRow values each: the node's whole-mesh id, its face's vertices'
  // whole-mesh ids (sorted), fn, ac, g0, fs (ids: local node to whole-mesh id; empty on one
  // process). A state without the lists themselves ("contact/pair_count": the whole state of a run
  // over processes restarted on another count, load_whole_state, solver/whole_state.hpp) is loaded from those
  // rows: the pairs of the own nodes whose face this process holds, rebuilt into candidate lists at
  // the first step, which carries their histories over.
  static constexpr int kPairRow = 4 + 2 * D;
  void save_state(StateArrays& s, const std::vector<int>& ids = {}) const;
  void load_state(const StateArrays& s, const Model<D>& m, const std::vector<int>& ids = {});

  // Rebuilds the grid and the candidate lists now (update() does it when a node has moved more
  // than half the skin; public for the tests: the history must survive rebuilds).
  void build(const Model<D>& m);

 private:
  // Constructor steps (the host topology of the surfaces: solver/contact_topology.hpp): the
  // contact law and search distances from the case (defaults from the mesh and materials); the
  // contact springs' stable step; device copies of the topology; work arrays.
  void set_law(const Case& c, const HostMesh& mesh);
  double contact_stable_step(const std::vector<double>& area, const std::vector<double>& mass) const;
  void upload(ContactFaces& F, FaceShares& H, HostVertexGroups& G, const Model<D>& m, double thick);
  void check_face_nodes(const ContactFaces& F) const;
  void allocate_work();
  void ensure_grid(CellGrid<D>& g, int nfaces, bool touched);
  void ensure_update_arrays();
  // Recomputes active faces, clusters, surface nodes and contact areas (from m.icontact).
  void refresh_surfaces(const Model<D>& m);
  // After a handover (surfaces refreshed; before_: the surfaces of the lists): the lists updated by
  // a local search at the build positions, when every surface node is within half the skin of its
  // build position (else need_build_ stays set).
  void update_lists(const Model<D>& m);
  // Room for `cap` candidate pairs in P and in the narrow phase's scratch (which only grows).
  void reserve_pairs(PairList<D>& P, int cap);
  // The checkpoint fields other than the pair lists (save_state and load_state visit the same
  // list): f(dataset name, View or scalar member).
  template <class Self, class F>
  static void state_fields(Self& self, F&& f);
  // "contact/pairs" (save_state) and the lists from them (load_state without the lists).
  std::vector<double> pair_rows(const std::vector<int>& ids) const;
  void load_pair_rows(const StateArrays& s, const std::vector<int>& ids);

  int nn_ = 0, ni_ = 0, nf_ = 0, ne_ = 0, nfree_ = 0;
  bool part_ = false;  // a part of a decomposed run: nodes from nown_ on are ghosts
  int nown_ = 0, ns_own_ = 0;
  bool polled_ = false;
  bool seeding_ = false;  // interfaces handed over at this step's poll: the narrow pass takes their state
  double stable_ = 0;
  ContactSurface<D> surf_;
  PairFilter<D> filter_;
  VertexGroups groups_;  // vertex groups with interfaces
  Kokkos::View<int*> afaces_, slaves_, mark_;
  int na_ = 0, ns_ = 0;
  CellGrid<D> grid_;
  long cell_cap_ = 0;
  PairList<D> cur_, next_;
  PairScratch<D> scratch_;
  Kokkos::View<double* [D]> xb_;  // positions at the last build (every node)
  bool xb_all_ = false;           // xb_ holds every node (false: restored from a checkpoint before this rule)
  SurfacesBefore before_;         // surfaces of the lists, at a handover
  Kokkos::View<int*> tnode_, tface_, tlist_;  // touched nodes and faces (list_update.hpp)
  CellGrid<D> tgrid_;                         // grid of the touched faces
  Kokkos::View<ContactBox<D>> treach_;        // the box of the touched faces (LocalSearch::treach)
  bool may_meet_ = false, need_build_ = true;
  bool friction_before_ = true;  // the last narrow-phase pass computed shear springs
  bool joint_friction_ = false;  // some face has its own friction above 0 (surf_.fmu: a joint's, a residual one)
  int bodies_ = 0;
  int check_every_ = 1, since_check_ = 0;
  int until_recheck_ = 0;  // steps to the next re-check of the candidate lists (0: this step)
  // The most steps between two re-checks of the candidate lists (recheck(); "Synchronisation"
  // above): a bound on how long a speed that grows goes unseen. Equal to kContactPollEvery by
  // choice only: nothing depends on the two being the same.
  static constexpr int kMaxRecheckInterval = 25;
  double stale_seen_ = 0;  // stale passes at the last re-check
  long builds_ = 0, handed_ = 0, surface_version_ = 0, syncs_ = 0, updates_ = 0, checks_ = 0;
  std::vector<double> potential_area_;
  Scatter own_scatter_;  // update() without a scatter view
  const double* own_scatter_f_ = nullptr;  // the forces it adds into (the host scatter's first thread writes them)
  Kokkos::View<ContactSums> pass_;      // sums of the last narrow-phase pass
  Kokkos::View<ContactStatus> status_;  // totals on the device (contact_account)
  ContactStatus read_status() const;
  // The re-check of the candidate lists (see "Synchronisation" above) from the last pass.
  void recheck(double dt);
};

extern template class ContactSystem<2>;
extern template class ContactSystem<3>;

}  // namespace fdem
