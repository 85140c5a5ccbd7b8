#include "solver/contact_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "kernels/host_loops.hpp"
#include "kernels/parts.hpp"

namespace fdem {

template <int D>
ContactSystem<D>::ContactSystem(const Case& c, const HostMesh& mesh, Model<D>& m,
                                const std::vector<double>& mass) {
  if (mesh.dim != D) throw InputError(c.file + ": contact: mesh dimension does not match");
  nn_ = mesh.num_nodes();
  ni_ = mesh.num_ifaces();
  ne_ = mesh.num_elems();
  part_ = mesh.owned_nodes >= 0;
  nown_ = part_ ? mesh.owned_nodes : nn_;
  if (part_ && mesh.pieces < 0)
    throw InputError(c.file + ": contact: a part of a decomposed mesh needs its contact zone (decompose with a "
                     "contact reach)");
  set_law(c, mesh);
  ContactFaces faces = contact_faces<D>(c, mesh);
  nf_ = faces.nf;
  const double thick = D == 2 ? c.thickness : 1.0;
  FaceShares shares = face_shares<D>(mesh, faces, thick);
  stable_ = contact_stable_step(shares.area, mass);
  potential_area_ = std::move(shares.area);
  HostVertexGroups groups = vertex_groups<D>(mesh);
  bodies_ = part_ ? mesh.pieces : count_bodies(mesh);  // a part: the whole mesh's
  may_meet_ = bodies_ > 1;
  upload(faces, shares, groups, m, thick);
  allocate_work();

  m.contact_handover = true;
  m.handover_slip = law.dpen;
  m.icontact_pending = Kokkos::View<int>(std::string(kContactSyncLabel) + "::icontact_pending");
  // Failed, parted interfaces are handed over every kContactPollEvery steps (a failed interface
  // keeps its compression penalty until then): each handover refreshes the surfaces and updates the
  // candidate lists by a local search (update_lists; docs/performance-impact.md section 2). On
  // GPUs the check also costs a copy of the pending flag to the host.
  check_every_ = kContactPollEvery;
  if (m.ifric.extent(0) > 0) {  // the faces of interfaces take their own friction (Model::ifric)
    surf_.fmu = Kokkos::View<double*>("fdem::contact::fmu", nf_);
    joint_friction_ = joint_face_friction<D>(surf_, m.ifric, nf_) > 0;
    // frictional joints, handed over from the start: the pieces they separate may meet
    may_meet_ = may_meet_ || count_handed(m.icontact, ni_) > 0;
  }
  refresh_surfaces(m);
}

// Parameters (docs/case-format.md, "contact").
template <int D>
void ContactSystem<D>::set_law(const Case& c, const HostMesh& mesh) {
  const ElementSizes mq = mesh_sizes(mesh);
  const double hmean = mq.mean_size;
  // kn, ks, friction and skin as derived by resolve_defaults (io/case.hpp) when not given
  law.kn = c.contact.kn;
  law.ks = c.contact.ks;
  law.mu = c.contact.friction;
  law.coh = c.contact.cohesion;
  // Penetration depth: a quarter of the thinnest element (contact_penetration_depth); coplanar
  // faces are within 30 degrees.
  // (a part of a decomposed mesh: the whole mesh's thinnest element, as on one process)
  const double min_size = mesh.owned_nodes >= 0 ? mesh.whole_min_size : mq.min_size;
  law.dpen = contact_penetration_depth(min_size, hmean);
  law.tol = 0.01;
  law.cos_same = std::cos(30.0 * M_PI / 180.0);
  skin = c.contact.skin;
  radius = law.dpen + skin;
}

// Stable step of the contact springs: omega^2 = 2 max(K_n, K_s) A_i / m_i with A_i the node's
// share of every face it can ever be part of (about twice its contact area: room for two
// contacts at full weight) and the factor 2 for the mass on the other side (a contact between two
// copies of one vertex acts on both nodes; docs/theory.md section 6b).
template <int D>
double ContactSystem<D>::contact_stable_step(const std::vector<double>& area,
                                             const std::vector<double>& mass) const {
  double dt = std::numeric_limits<double>::infinity();
  const double kmax = std::max(law.kn, law.ks);
  for (int i = 0; i < nown_; ++i)  // a part: its own nodes (a ghost's mass may lack elements it does not hold)
    if (area[i] > 0 && mass[i] > 0) dt = std::min(dt, 2.0 / std::sqrt(2.0 * kmax * area[i] / mass[i]));
  return dt;
}

// Device copies of the host topology; each host array is freed once copied (the set-up's peak
// memory holds the device arrays and what is left of the host ones, not both in full).
template <int D>
void ContactSystem<D>::upload(ContactFaces& F, FaceShares& H, HostVertexGroups& G, const Model<D>& m,
                              double thick) {
  auto fill = [](auto& d, auto&& at) {       // d(i) = at(i) for every entry, on the host's threads
    auto h = Kokkos::create_mirror_view(d);  // d itself on a host backend
    host_for("fdem::contact::upload", static_cast<int>(h.extent(0)), [&](const int i) { at(h, i); });
    Kokkos::deep_copy(d, h);
  };
  auto upload_int = [&fill](std::vector<int>& v, const char* name) {
    Kokkos::View<int*> d(Kokkos::view_alloc(Kokkos::WithoutInitializing, std::string(name)), v.size());
    fill(d, [&v](const auto& h, int i) { h(i) = v[i]; });
    std::vector<int>().swap(v);
    return d;
  };
  // (the outer faces' nodes stored, the interfaces' faces' taken from m.iface: FaceNodes)
  surf_.fnode.outer =
      Kokkos::View<int* [D]>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "fdem::contact::fnode"), F.nb);
  fill(surf_.fnode.outer, [&F](const auto& h, int f) {
    for (int a = 0; a < D; ++a) h(f, a) = F.fnode[static_cast<size_t>(f) * D + a];
  });
  surf_.fnode.iface = m.iface;
  surf_.fnode.nb = F.nb;
  surf_.fnode.nf = nf_;
  check_face_nodes(F);
  std::vector<int>().swap(F.fnode);
  surf_.fslot = Kokkos::View<int*>("fdem::contact::fslot", nf_);
  surf_.X = m.X;  // (the faces' shares computed from it: face_share)
  surf_.thick = thick;
  surf_.icontact = m.icontact;  // (which faces are active: ContactSurface::active)
  // (no offsets where every node is on D faces: ContactSurface::faces_begin)
  bool uniform = true;
  for (size_t i = 0; i < H.nfoff.size() && uniform; ++i) uniform = H.nfoff[i] == D * static_cast<long>(i);
  surf_.face_stride = uniform ? D : 0;
  if (uniform) std::vector<int>().swap(H.nfoff);
  surf_.nfoff = upload_int(H.nfoff, "fdem::contact::nfoff");
  surf_.nface = upload_int(H.nface, "fdem::contact::nface");
  surf_.vgrp = upload_int(G.vgrp, "fdem::contact::vgrp");
  surf_.clus =
      Kokkos::View<int*>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "fdem::contact::clus"), nn_);
  fill(surf_.clus, [](const auto& h, int i) { h(i) = i; });
  surf_.nb = F.nb;
  surf_.narea = Kokkos::View<double*>("fdem::contact::narea", 0);  // (sized by refresh_surfaces)
  groups_.off = upload_int(G.off, "fdem::contact::goff");
  groups_.ent = upload_int(G.ent, "fdem::contact::gent");
  groups_.copy_off = upload_int(G.copy_off, "fdem::contact::gcopy_off");
  groups_.copy = upload_int(G.copy, "fdem::contact::gcopy");
  groups_.n = G.n;
  filter_.use = true;
  filter_.elem = m.elem;
  filter_.fowner = upload_int(F.fowner, "fdem::contact::fowner");
  surf_.elem = m.elem;
  surf_.fowner = filter_.fowner;
  surf_.efree = Kokkos::View<int*>("fdem::contact::efree", ne_);
  filter_.nb = F.nb;
  filter_.vgrp = surf_.vgrp;
  filter_.clus = surf_.clus;
}

// The faces' nodes as FaceNodes gives them (the interfaces' from the model's) against the
// topology's table F.fnode: the same for every face, else the model's interfaces are not the
// mesh's in its order (a logic error, not an input error). Face by face, not through a second
// table (face_node_table, contact_system_state.cpp): the set-up's peak holds F.fnode already.
template <int D>
void ContactSystem<D>::check_face_nodes(const ContactFaces& F) const {
  const auto outer = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), surf_.fnode.outer);
  const auto iface = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), surf_.fnode.iface);
  long wrong = 0;
  host_reduce_sum("fdem::contact::check_face_nodes", nf_, [&](const int f, long& w) {
    for (int a = 0; a < D; ++a)
      w += face_node_of<D>(outer, iface, F.nb, f, a) != F.fnode[static_cast<size_t>(f) * D + a];
  }, wrong);
  if (wrong > 0)
    throw std::logic_error("contact: " + std::to_string(wrong) + " face nodes differ from the interfaces' nodes");
}

// Work arrays: active faces, surface nodes, positions at the last build, pair offsets. The cell
// grids and the arrays of the local list update are sized when first needed (ensure_grid,
// ensure_update_arrays): a grid needs a few cells per active face, not per face that may ever
// become active, and a run in which no interface fails never updates its lists.
template <int D>
void ContactSystem<D>::allocate_work() {
  afaces_ = Kokkos::View<int*>("fdem::contact::afaces", 0);  // (sized by refresh_surfaces)
  slaves_ = Kokkos::View<int*>("fdem::contact::nodes", 0);
  mark_ = Kokkos::View<int*>("fdem::contact::mark", nn_);
  xb_ = Kokkos::View<double* [D]>("fdem::contact::xb", nn_);
  cell_cap_ = std::max<long>(64, 4L * nf_);  // the most cells a grid may have (grid_geometry)
  for (PairList<D>* p : {&cur_, &next_}) p->off = Kokkos::View<int*>("fdem::contact::pair_off", nn_ + 1);
  pass_ = Kokkos::View<ContactSums>("fdem::contact::pass");
  status_ = Kokkos::View<ContactStatus>(std::string(kContactSyncLabel) + "::status");
}

namespace {

// Room for n entries in v (grown by half again when it grows; contents not kept, not initialised:
// the grids count and fill what they use).
void ensure_ints(Kokkos::View<int*>& v, long n, const char* label) {
  if (static_cast<long>(v.extent(0)) >= n) return;
  const long cap = std::min<long>(std::numeric_limits<int>::max(), n + n / 2 + 64);
  v = Kokkos::View<int*>(Kokkos::view_alloc(Kokkos::WithoutInitializing, std::string(label)), cap);
}

}  // namespace

// Room in grid g for its g.ncell cells and nfaces faces (g.ncell from grid_geometry).
template <int D>
void ContactSystem<D>::ensure_grid(CellGrid<D>& g, int nfaces, bool touched) {
  ensure_ints(g.count, g.ncell, touched ? "fdem::contact::tcell_count" : "fdem::contact::cell_count");
  ensure_ints(g.offset, g.ncell + 1L, touched ? "fdem::contact::tcell_offset" : "fdem::contact::cell_offset");
  ensure_ints(g.faces, std::max(nfaces, 1),
              touched ? "fdem::contact::tcell_faces" : "fdem::contact::cell_faces");
  if (g.box.extent(0) < g.faces.extent(0))
    g.box = Kokkos::View<double* [2 * D]>(
        Kokkos::view_alloc(Kokkos::WithoutInitializing,
                           std::string(touched ? "fdem::contact::tcell_box" : "fdem::contact::cell_box")),
        g.faces.extent(0));
}

// The arrays of the local list update (update_lists), at the first handover with lists.
template <int D>
void ContactSystem<D>::ensure_update_arrays() {
  if (tnode_.extent(0) > 0) return;
  before_.mark = Kokkos::View<int*>("fdem::contact::mark_before", nn_);
  before_.clus = Kokkos::View<int*>("fdem::contact::clus_before", nn_);
  tnode_ = Kokkos::View<int*>("fdem::contact::tnode", nn_);
  tface_ = Kokkos::View<int*>("fdem::contact::tface", nf_);
  tlist_ = Kokkos::View<int*>("fdem::contact::tlist", 0);  // (sized by update_lists)
}

template <int D>
void ContactSystem<D>::refresh_surfaces(const Model<D>& m) {
  update_clusters<D>(groups_, surf_, m.iface, m.icontact);
  na_ = compact_where_grown("fdem::contact::active_faces", ActiveFaces<D>{surf_}, afaces_, nf_);
  if (static_cast<int>(surf_.fgeo.extent(0)) < na_)  // grows with the surfaces (with headroom)
    surf_.fgeo = Kokkos::View<double**>("fdem::contact::fgeo", std::min(nf_, 3 * na_ / 2 + 64), FaceGeo<D>::size);
  face_slots<D>(surf_, afaces_, na_);
  mark_surface_nodes<D>(surf_, afaces_, na_, mark_);
  nfree_ = flag_free_elements<D>(surf_, afaces_, na_, ne_);
  if (nfree_ > 0 && surf_.eplane.extent(0) == 0)
    surf_.eplane = Kokkos::View<double* [D + 1][D + 1]>("fdem::contact::eplane", ne_);
  ns_ = compact_flagged_grown("fdem::contact::surface_nodes", mark_, slaves_, nn_);
  number_listed(mark_, slaves_, ns_);  // (surface_places)
  if (static_cast<int>(surf_.narea.extent(0)) < ns_)  // (grows with the surfaces, with headroom)
    surf_.narea = Kokkos::View<double*>(Kokkos::ViewAllocateWithoutInitializing("fdem::contact::narea"),
                                        std::min(nn_, 3 * ns_ / 2 + 64));
  node_areas<D>(surf_, slaves_, ns_);
  // a part: its own surface nodes come first (ascending node ids; the own nodes are the first)
  ns_own_ = part_ ? count_below(slaves_, ns_, nown_) : ns_;
  // the narrow phase's ranges of equal work on host backends with several threads (grows with the
  // surfaces, with headroom; kernels/contact/narrow_phase.hpp, BalancedPoints)
  if (std::is_same<MemSpace, Kokkos::HostSpace>::value && ExecSpace().concurrency() > 1 &&
      static_cast<int>(scratch_.work.extent(0)) < ns_ + 1)
    scratch_.work = Kokkos::View<int*>(Kokkos::ViewAllocateWithoutInitializing("fdem::contact::narrow_work"),
                                       std::min(nn_, 3 * ns_ / 2 + 64) + 1);
  // the seeds of the passes after handovers (kernels/contact/narrow_phase.hpp, SeedRow; grows likewise)
  if (static_cast<int>(scratch_.seed.extent(0)) < ns_)
    scratch_.seed = typename SeedRow<D>::View(Kokkos::ViewAllocateWithoutInitializing("fdem::contact::narrow_seeds"),
                                              std::min(nn_, 3 * ns_ / 2 + 64));
  need_build_ = true;
  ++surface_version_;
}

template <int D>
void ContactSystem<D>::check_failures(const Model<D>& m) {
  if (ni_ == 0) return;
  const int n = hand_over_failed<D>(m, ni_);  // also clears m.icontact_pending
  ++checks_;
  if (n == 0) return;
  handed_ += n;
  seeding_ = true;  // the next narrow pass takes their state (HandoverSeed)
  // the lists are valid and the build positions known for every node: a local update will do
  const bool lists = may_meet_ && !need_build_ && xb_all_ && builds_ > 0 && ns_ > 0 && na_ > 0;
  if (lists) {
    ensure_update_arrays();
    save_surfaces<D>(mark_, surf_, before_, nn_);
  }
  may_meet_ = true;
  refresh_surfaces(m);
  if (lists) update_lists(m);
  clear_apart_marks(m.icontact, ni_);  // (the faces new at this poll told apart until here)
}

template <int D>
void ContactSystem<D>::update_lists(const Model<D>& m) {
  const double half = 0.5 * skin;
  // the pass of this step must not run on outdated lists (new surface nodes included)
  const double d2 = largest_displacement2<D>(m.x, xb_, slaves_, ns_);
  if (!(d2 <= half * half)) return;
  touched<D>(mark_, surf_, before_, tnode_, tface_, nn_, nf_);
  const int nt = compact_flagged_grown("fdem::contact::touched_faces_list", tface_, tlist_, nf_);
  LocalSearch<D> L;
  L.S.x = xb_;
  L.S.points = slaves_;
  L.S.np = ns_;
  L.S.fnode = surf_.fnode;
  L.S.faces = afaces_;
  L.S.nf = na_;
  L.S.radius = radius;
  L.S.tol = law.tol;
  const ContactBox<D> box = search_bounds<D>(L.S);
  bool finite = std::isfinite(box.ext);
  for (int k = 0; k < D; ++k) finite = finite && std::isfinite(box.lo[k]) && std::isfinite(box.hi[k]);
  if (!finite) return;
  grid_geometry<D>(grid_, box, radius, cell_cap_);
  ensure_grid(grid_, na_, false);
  grid_bin<D>(grid_, L.S);
  tgrid_.geo = grid_.geo;
  tgrid_.ncell = grid_.ncell;
  ensure_grid(tgrid_, nt, true);
  SearchSet<D> T = L.S;
  T.faces = tlist_;
  T.nf = nt;
  grid_bin<D>(tgrid_, T);
  if (!treach_.is_allocated()) treach_ = Kokkos::View<ContactBox<D>>("fdem::contact::touched_bounds");
  search_bounds<D>(T, treach_);
  L.treach = treach_;
  L.all = grid_;
  L.touched = tgrid_;
  L.tnode = tnode_;
  L.tface = tface_;
  // the candidates of the own surface points only: over several processes a ghost point's contacts
  // are its owner's (the narrow phase computes the own points', the others it only follows for the
  // displacement bound); on one process all points are own
  L.S.np = ns_own_;
  const int total = local_count<D>(L, filter_, cur_, next_.off, nn_);
  if (total > next_.capacity)
    reserve_pairs(next_,
                  static_cast<int>(std::min<long>(std::numeric_limits<int>::max(), 3L * total / 2 + 64)));
  local_fill<D>(L, filter_, cur_, next_);
  next_.size = total;
  std::swap(cur_, next_);
  need_build_ = false;
  ++updates_;
  until_recheck_ = 1;  // the next step re-checks the lists with the speeds of the new surface nodes
}

template <int D>
void ContactSystem<D>::build(const Model<D>& m) {
  SearchSet<D> S;
  S.x = m.x;
  S.points = slaves_;
  S.np = ns_;
  S.fnode = surf_.fnode;
  S.faces = afaces_;
  S.nf = na_;
  S.radius = radius;
  S.tol = law.tol;  // the distance test of face_within
  const ContactBox<D> box = search_bounds<D>(S);
  bool finite = std::isfinite(box.ext);
  for (int k = 0; k < D; ++k) finite = finite && std::isfinite(box.lo[k]) && std::isfinite(box.hi[k]);
  if (!finite) {  // a non-finite state: no contacts (the solver's stability check reports it)
    Kokkos::deep_copy(cur_.off, 0);
    cur_.size = 0;
    need_build_ = true;
    return;
  }
  grid_geometry<D>(grid_, box, radius, cell_cap_);
  ensure_grid(grid_, na_, false);
  grid_bin<D>(grid_, S);
  SearchSet<D> Q = S;  // the candidates of the own surface points only (update_lists)
  Q.np = ns_own_;
  const int total = candidates_count<D>(grid_, Q, filter_, next_.off, nn_);
  if (total > next_.capacity)  // grow with headroom (like the grids: allocations during a run)
    reserve_pairs(next_,
                  static_cast<int>(std::min<long>(std::numeric_limits<int>::max(), 3L * total / 2 + 64)));
  candidates_fill<D>(grid_, Q, filter_, next_.off, next_.face);
  next_.size = total;
  transfer_history<D>(cur_, next_, slaves_, ns_, filter_);
  std::swap(cur_, next_);
  record_all_positions<D>(m.x, xb_, nn_);
  xb_all_ = true;
  need_build_ = false;
  ++builds_;
}

template <int D>
void ContactSystem<D>::reserve_pairs(PairList<D>& P, int cap) {
  P.face = Kokkos::View<int*>("fdem::contact::pair_face", cap);
  P.fn = Kokkos::View<double*>("fdem::contact::pair_fn", cap);
  P.ac = Kokkos::View<double*>("fdem::contact::pair_ac", cap);
  P.g0 = Kokkos::View<double*>("fdem::contact::pair_g0", cap);
  P.fs = Kokkos::View<double* [D]>("fdem::contact::pair_fs", cap);
  P.capacity = cap;
  if (cap > static_cast<int>(scratch_.g.extent(0))) {
    scratch_.g = Kokkos::View<double*>("fdem::contact::scratch_g", cap);
    scratch_.phi = Kokkos::View<double*>("fdem::contact::scratch_phi", cap);
    scratch_.depth = Kokkos::View<double*>("fdem::contact::scratch_depth", cap);
    scratch_.w = Kokkos::View<double*>("fdem::contact::scratch_w", cap);
    scratch_.rel = Kokkos::View<double*>("fdem::contact::scratch_rel", cap);
    scratch_.n = Kokkos::View<double* [D]>("fdem::contact::scratch_n", cap);
  }
}

template <int D>
void ContactSystem<D>::update(const Model<D>& m, double dt) {
  poll(m);
  if (own_scatter_f_ != m.f.data()) {  // (another model's forces: a scatter of its own)
    own_scatter_ = Scatter(m.f);
    own_scatter_f_ = m.f.data();
  }
  own_scatter_.reset();
  update(m, dt, own_scatter_);
  auto f = m.f;
  contribute_forces<D>(f, own_scatter_);
}

template <int D>
void ContactSystem<D>::poll(const Model<D>& m) {
  // (a part polls on the same steps as every other part, with or without interfaces of its own:
  // the parts agree on what changed there, Simulation::step)
  polled_ = false;
  if ((ni_ > 0 || part_) && ++since_check_ >= check_every_) {
    since_check_ = 0;
    polled_ = true;
    // one process: its force pass flags a failed, parted interface (icontact_pending). A part
    // looks at every poll, flag or not: the flag covers only what its own passes met, and parts
    // set up at a restart on another count missed handovers with it (the 2D impact restarted from
    // 3 processes on 2: at its 8th poll one part had no flag but an interface due, which the run
    // on one process handed over there; the plate load then differed by 8 %,
    // tests/mpi/check_runs.py). Looking costs a pass over the flags every kContactPollEvery steps.
    int pending = part_ ? 1 : 0;
    if (ni_ > 0) {
      if (!part_) Kokkos::deep_copy(pending, m.icontact_pending);
      ++syncs_;  // (a part: the count of handovers read back)
    }
    if (pending) check_failures(m);
  }
}

template <int D>
void ContactSystem<D>::update(const Model<D>& m, double dt, Scatter& sf) {
  // after this step's pass the interfaces handed over at its poll are like the others
  const bool seeding = seeding_;
  seeding_ = false;
  if (!may_meet_ || ns_ == 0 || na_ == 0) {
    if (seeding) clear_handover_marks(m.icontact, ni_);
    return;
  }
  if (!need_build_ && until_recheck_ <= 0) recheck(dt);
  if (need_build_) {
    build(m);
    until_recheck_ = 0;  // the speed of the first pass on the new lists sets the next re-check
  }
  face_geometry<D>(m.x, surf_, afaces_, na_);
  if (nfree_ > 0) element_planes<D>(m.x, surf_, ne_);
  // Frictionless contact skips the shear springs. On the first step without friction after steps
  // with it, the full kernel runs once more: it sets every stored shear force to zero (and counts
  // the spring energy of contacts that end), so that the skipped kernel's zero history is exact.
  const bool fric = law.mu != 0.0 || law.coh != 0.0 || joint_friction_;
  const bool full = !skip_frictionless || fric || friction_before_;
  friction_before_ = fric || !skip_frictionless;
  const auto pass = small_subsets ? (full ? &contact_forces<D, true, 1> : &contact_forces<D, false, 1>)
                                  : (full ? &contact_forces<D, true> : &contact_forces<D, false>);
  pass(m, slaves_, ns_, ns_own_, cur_, scratch_, surf_, law, dt, xb_, sf, pass_, seeding, team_above);
  if (seeding) clear_handover_marks(m.icontact, ni_);
  contact_account(pass_, status_, 0.5 * skin);
  --until_recheck_;
}

// Verlet test (see "Synchronisation" in contact_system.hpp): the lists stay valid while no surface
// node has moved more than half the skin since the build; the displacement at the next step is
// bounded by the last pass's plus a step at (twice) the largest speed, and K steps on by the last
// pass's plus K such steps.
template <int D>
void ContactSystem<D>::recheck(double dt) {
  until_recheck_ = kMaxRecheckInterval;
  const ContactStatus st = read_status();
  ++syncs_;
  const double d = std::sqrt(st.d2max), step = 2.0 * std::sqrt(st.v2max) * dt, half = 0.5 * skin;
  need_build_ = d + step > half || st.stale > stale_seen_;
  stale_seen_ = st.stale;
  if (!need_build_ && step > 0)
    until_recheck_ = static_cast<int>(std::min<double>(kMaxRecheckInterval, std::floor((half - d) / step)));
}

template <int D>
ContactStatus ContactSystem<D>::read_status() const {
  ContactStatus h;
  Kokkos::deep_copy(h, status_);
  return h;
}

template <int D>
int ContactSystem<D>::active_contacts() const {
  if (!may_meet_ || ns_ == 0 || na_ == 0) return 0;
  return static_cast<int>(read_status().active);
}

int parse_narrow_team_above(const char* e, int fallback) {
  if (!e || !*e) return fallback;
  char* end = nullptr;
  const long v = std::strtol(e, &end, 10);
  if (*end != '\0' || v < 0 || v > 1000000)
    throw InputError("environment variable FDEM_NARROW_TEAM_ABOVE='" + std::string(e) +
                     "': a whole number of candidates from 0 (one thread per point) to 1000000");
  return static_cast<int>(v);
}

int narrow_team_above() {
  if (std::is_same<MemSpace, Kokkos::HostSpace>::value) return 0;
  return parse_narrow_team_above(std::getenv("FDEM_NARROW_TEAM_ABOVE"), kNarrowTeamAbove);
}

template <int D>
typename ContactSystem<D>::CandidateSpread ContactSystem<D>::candidate_spread() const {
  CandidateSpread r;
  if (ns_own_ == 0 || cur_.off.extent(0) == 0) return r;
  static_assert(kSpreadBins == kSpreadSumsBounds, "one count per bound");
  const SpreadSums s = spread_of_candidates(cur_.off, slaves_, ns_own_);
  r.max = s.max;
  r.points = s.v[0];
  r.pairs = s.v[1];
  for (int k = 0; k < kSpreadBins; ++k) {
    r.points_above[k] = s.v[2 + k];
    r.pairs_above[k] = s.v[2 + kSpreadBins + k];
  }
  return r;
}

template <int D>
double ContactSystem<D>::own_point_work(const Kokkos::View<double*>& w, double scale) const {
  if (!may_meet_ || ns_own_ == 0 || na_ == 0) return 0.0;
  return point_work(cur_.off, slaves_, ns_own_, kPointWork, w, scale);
}

template <int D>
double ContactSystem<D>::elastic_energy() const {
  if (!may_meet_ || ns_ == 0 || cur_.size == 0) return 0.0;
  return contact_energy<D>(cur_, slaves_, ns_own_, law);
}

template class ContactSystem<2>;
template class ContactSystem<3>;

}  // namespace fdem
