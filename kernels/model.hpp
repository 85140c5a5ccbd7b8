#pragma once
// Device data of a run: nodes, elements and interfaces as structures of arrays in Kokkos Views,
// specialised on the dimension D (2: triangles and 4-node interfaces; 3: tetrahedra and 6-node
// interfaces) so that a 2D run does no 3D work. Built once on the host (src/solver/model_builder.cpp);
// during a run nothing moves between host and device except output.
#include "kernels/cohesive.hpp"
#include "kernels/fdem_kokkos.hpp"

namespace fdem {

// A velocity boundary condition as the kernels see it: components in `mask` (bit k = component k)
// move at vel * min(1, t / ramp).
struct BCDev {
  int mask;
  double vel[3];
  double ramp;
};

// Rigid platen: plane through p0 + shift(t) with unit normal n pointing into the body; it moves at
// vel until time tc and at vel2 after it (platens[i].change of the case; tc = +inf without one).
struct PlatenDev {
  double p0[3], n[3], vel[3];
  double vel2[3];       // velocity after tc
  double tc;            // time of the velocity change
  double kn, ks;        // Pa/m, times the node's contact area
  double mu, coh;       // friction coefficient, cohesion (Pa)
  // A platen with a mass (platens[i].mass: a guided drop weight) moves along n as the body's force
  // and gravity drive it: inv_mass > 0, its travel along n and its speed along n are state
  // (Model::platen_motion), its velocity across n stays vt; shift and mean_velocity do not apply.
  double inv_mass = 0;        // 1 / kg; 0: the prescribed motion above
  double vt[3] = {0, 0, 0};   // driven: the velocity across n (m/s)
  double gn = 0;              // driven: gravity along n (m/s^2)

  // Displacement of the plane from p0, component k, at time t.
  KOKKOS_INLINE_FUNCTION double shift(const int k, const double t) const {
    return t <= tc ? vel[k] * t : vel[k] * tc + vel2[k] * (t - tc);
  }
  // Its mean velocity over [t0, t0 + h], h > 0 (vel itself, to the bit, away from tc).
  KOKKOS_INLINE_FUNCTION double mean_velocity(const int k, const double t0, const double h) const {
    if (t0 + h <= tc) return vel[k];
    if (t0 >= tc) return vel2[k];
    return (vel[k] * (tc - t0) + vel2[k] * (t0 + h - tc)) / h;
  }
};
constexpr int kMaxPlatens = 8;
struct PlatenSet {
  int count = 0;
  PlatenDev p[kMaxPlatens];
};
// The columns of Model::platen_motion (a driven platen's state, the same on every process): its
// travel along n from p0 + vt t, and its speed along n over the last half step (leap-frog, as the
// nodes' velocities: v(n - 1/2) from the node update of one step to that of the next); and, for the
// output, the travel and the speed at the time of the last step's forces (x(n), where the ledger
// takes the nodes' momentum as the mean of v(n - 1/2) and v(n + 1/2)).
constexpr int kPlatenTravel = 0, kPlatenSpeed = 1, kPlatenTravelAtForces = 2, kPlatenSpeedAtForces = 3;
constexpr int kPlatenMotion = 4;

// Platen p's displacement from p0, component k, at time t: the prescribed motion, or a driven
// platen's state (valid at the time of the nodes' positions only).
template <class MotionView>
KOKKOS_INLINE_FUNCTION double platen_shift(const PlatenDev& P, const MotionView& motion, int p, int k, double t) {
  return P.inv_mass > 0 ? P.vt[k] * t + motion(p, kPlatenTravel) * P.n[k] : P.shift(k, t);
}
// Its mean velocity over [t0, t0 + h]; a driven platen: its velocity over the half step stored
// (before the node update the one before t, after it the one after t).
template <class MotionView>
KOKKOS_INLINE_FUNCTION double platen_velocity(const PlatenDev& P, const MotionView& motion, int p, int k, double t0,
                                              double h) {
  return P.inv_mass > 0 ? P.vt[k] + motion(p, kPlatenSpeed) * P.n[k] : P.mean_velocity(k, t0, h);
}
// Per-platen accumulators (device), the columns of Model::platen_acc: force on the body this step
// (kPlatenForce + 0..2), cumulative work done by the platen, cumulative friction dissipation,
// contacts this step.
constexpr int kPlatenAcc = 8;
constexpr int kPlatenForce = 0, kPlatenWork = 3, kPlatenFriction = 4, kPlatenContacts = 5;

// The model's data in four bundles, each a structure of arrays that a kernel can capture by value
// on its own (`const NodeData<D> n = m;`): nodes, elements, interfaces, and the platens with the
// boundary nodes they act on. Model<D> is all four.
template <int D>
struct NodeData {
  int nn = 0;
  // One part of a decomposed run (src/parallel/decompose.hpp): its first nn_own nodes are its own,
  // the others ghosts, whose state comes from their owners after each step (kernels/halo.hpp):
  // the node update and its sums cover the own nodes only. -1: all nodes are its own.
  int nn_own = -1;
  int owned_nodes() const { return nn_own < 0 ? nn : nn_own; }
  Kokkos::View<double* [D]> X, x, v, f;  // reference, current position, velocity, force
  Kokkos::View<double*> mass;
  Kokkos::View<int*> node_bc;      // -1: free; else index into bcs
  Kokkos::View<BCDev*> bcs;
  Kokkos::View<double* [D]> fext;  // constant point loads (extent 0 when there are none)
  // Ramped point loads: fext_ramp(g, i, k) is node i's full force of the loads with the g-th ramp
  // time (Simulation's load ramp table; extent 0 when no load ramps)
  Kokkos::View<double** [D]> fext_ramp;
};

template <int D>
struct ElementData {
  int ne = 0;
  int ne_own = -1;  // decomposed run: the own elements come first (energies, checks); -1: all
  int owned_elems() const { return ne_own < 0 ? ne : ne_own; }
  // decomposed run: the elements whose bulk forces count (own, then ghosts at an own node) come
  // first; the ghosts after them only carry interfaces' sides. -1: all
  int ne_bulk = -1;
  KOKKOS_INLINE_FUNCTION int bulk_elems() const { return ne_bulk < 0 ? ne : ne_bulk; }
  double thickness = 1.0;  // 2D: out-of-plane thickness; 3D: 1
  bool plane_stress = false;
  Kokkos::View<int* [D + 1]> elem;
  Kokkos::View<double* [D][D]> grad;  // reference shape-function gradients of nodes 1..D
  Kokkos::View<double*> vol0;         // reference volume (2D: area * thickness)
  Kokkos::View<int*> emat;            // material index
  Kokkos::View<double* [3]> mat;      // per material: lambda (plane-stress corrected), mu, density
};

// Interfaces: node pairs (A0..A{D-1}, B0..B{D-1}); per integration point (one per node pair) the
// history dmax, dm0, dmf, wd (kPointHistory values, cohesive.hpp; read and written through
// load_point / store_point).
template <int D>
struct InterfaceData {
  int ni = 0;
  int ni_own = -1;  // decomposed run: the counted interfaces come first (energies, counts); -1: all
  int owned_ifaces() const { return ni_own < 0 ? ni : ni_own; }
  Kokkos::View<int* [2 * D]> iface;
  Kokkos::View<double* [D][kPointHistory]> ihist;
  // Per integration point, when some interface material has a residual friction
  // (CohesiveParams::tanphir >= 0): its slip state (SlipPoint, kernels/cohesive.hpp; read and
  // written through load_slip / store_slip), kept for the points that have begun to soften only
  // (the others' is zero and never read). Empty otherwise.
  Kokkos::View<double* [D][D + 1]> islip;
  KOKKOS_INLINE_FUNCTION bool has_slip() const { return islip.extent(0) > 0; }
  double step_dt = 0;  // the step that brought the positions to x(n) (Simulation::step sets it)
  Kokkos::View<double*> iarea;        // reference tributary area of each integration point
  // Host backends, interfaces ordered by their side-A element: first interface of each chunk of
  // kChunk elements (ceil(ne / kChunk) + 1 entries); the force kernel then does each element
  // chunk with the interfaces whose side A lies in it. Empty: bulk and interfaces apart.
  Kokkos::View<int*> ichunk;
  CohesiveParams coh{};
  // Several interface materials or a strength scatter (docs/case-format.md, "fracture"): interface
  // q takes coh_table(imat(q)) as given, its f_t and c times iscale(q) (and its Gnc, Gsc when
  // scale_energy), its strengths divided by the strength reduction srf, and coh's rescale.
  // Empty (extent 0) in a run with one material and no scatter: every interface takes coh, and
  // the force kernel is the one-material one (no table read, no per-interface index).
  Kokkos::View<CohesiveParams*> coh_table;
  Kokkos::View<int*> imat;      // ni, with coh_table
  Kokkos::View<float*> iscale;  // ni with a scatter, else empty (factor 1)
  double srf = 1.0;
  bool scale_energy = false;
  KOKKOS_INLINE_FUNCTION bool per_interface() const { return coh_table.extent(0) > 0; }
  KOKKOS_INLINE_FUNCTION CohesiveParams params(const int q) const {
    if (!per_interface()) return coh;
    CohesiveParams p = coh_table(imat(q));
    const double w = iscale.extent(0) > 0 ? static_cast<double>(iscale(q)) : 1.0;
    p.ft *= w / srf;
    p.c *= w / srf;
    p.tanphi /= srf;
    if (p.tanphir > 0.0) p.tanphir /= srf;
    if (scale_energy) {
      p.Gnc *= w;
      p.Gsc *= w;
    }
    p.rescale = coh.rescale;
    return p;
  }
  // Per interface (extent ni): 1 once it carries nothing and stores nothing, for good: handed over
  // to contact when failed and parted (interface_parted, kernels/interface.hpp), or, without
  // contact, come apart (interface_apart). With contact (contact_handover), the force kernel
  // sets icontact_pending when it meets a failed, parted interface not handed over yet.
  Kokkos::View<int*> icontact;
  Kokkos::View<int> icontact_pending;
  // Per interface (extent ni) when some interface material is a frictional joint
  // (InterfaceMaterial::frictional) or has a residual friction: the friction
  // coefficient of the contact faces it leaves once handed over (ContactSurface::fmu): a joint's
  // tan(phi), a softening material's residual tan(phi_r); -1 for the others (the paper's law: the
  // contact law's friction); empty otherwise. Frictional joints start failed and handed over
  // (icontact = 1).
  Kokkos::View<double*> ifric;
  bool contact_handover = false;
  double handover_slip = 0;  // see interface_parted (kernels/interface.hpp)
};

// Nodes the platens act on (nb of them, ids in bnode): the outer boundary; with contact, every
// surface node, including the faces of cracks handed over to contact during the run (the contact
// system's surface nodes, see Platens::follow_surfaces in src/solver/platens.cpp; ascending ids).
// Their tributary areas (barea), the platens' shear springs (platen_fs) and allowances
// (platen_g0) are rows b of the node bnode(b): sized by the nodes the platens act on, not by every
// node (a surface is a few per cent of the nodes of a body that is mostly intact).
template <int D>
struct PlatenData {
  int nb = 0;
  Kokkos::View<int*> bnode;
  Kokkos::View<double*> barea;                  // per row of bnode
  PlatenSet platens;
  Kokkos::View<double** [D]> platen_fs;         // shear spring force per (platen, row of bnode)
  Kokkos::View<double**> platen_g0;             // penetration allowance (<= 0) per (platen, row of bnode)
  Kokkos::View<double* [kPlatenAcc]> platen_acc;
  Kokkos::View<double* [kPlatenMotion]> platen_motion;  // driven platens' travel, speed (kPlatenTravel)
};

template <int D>
struct Model : NodeData<D>, ElementData<D>, InterfaceData<D>, PlatenData<D> {
  static constexpr int dim = D;
  // case key `precision`: "mixed" (true) computes the force pass's strains, stresses and
  // interface tractions in floats on host backends (FusedForceKernel::mixed, kernels/forces.hpp)
  bool mixed_precision = false;
  const NodeData<D>& nodes() const { return *this; }
  const ElementData<D>& elements() const { return *this; }
  const InterfaceData<D>& interfaces() const { return *this; }
  const PlatenData<D>& platen_data() const { return *this; }
};

// The cohesive history of integration point k of interface q (layout of Model::ihist: dmax, dm0,
// dmf, wd, kPointHistory columns; cohesive.hpp). The one place that knows the layout: kernels and
// the host read and write the history through these.
template <class HistView>
KOKKOS_INLINE_FUNCTION CohesivePoint load_point(const HistView& ihist, int q, int k) {
  return CohesivePoint{ihist(q, k, 0), ihist(q, k, 1), ihist(q, k, 2), ihist(q, k, 3)};
}
template <class HistView>
KOKKOS_INLINE_FUNCTION void store_point(const HistView& ihist, int q, int k, const CohesivePoint& h) {
  ihist(q, k, 0) = h.dmax;
  ihist(q, k, 1) = h.dm0;
  ihist(q, k, 2) = h.dmf;
  ihist(q, k, 3) = h.wd;
}

// The slip state of integration point k of interface q (Model::islip; SlipPoint, cohesive.hpp).
template <int D, class SlipView>
KOKKOS_INLINE_FUNCTION SlipPoint<D> load_slip(const SlipView& islip, int q, int k) {
  SlipPoint<D> s;
  for (int i = 0; i < D; ++i) s.sp[i] = islip(q, k, i);
  s.wf = islip(q, k, D);
  return s;
}
template <int D, class SlipView>
KOKKOS_INLINE_FUNCTION void store_slip(const SlipView& islip, int q, int k, const SlipPoint<D>& s) {
  for (int i = 0; i < D; ++i) islip(q, k, i) = s.sp[i];
  islip(q, k, D) = s.wf;
}

// Whether two histories are the same bit for bit (a NaN compares unequal: it is written).
KOKKOS_INLINE_FUNCTION bool same_point(const CohesivePoint& a, const CohesivePoint& b) {
  return a.dmax == b.dmax && a.dm0 == b.dm0 && a.dmf == b.dmf && a.wd == b.wd;
}

// Positions of element e's nodes (xe[a], a <= D) and its reference shape-function gradients G.
template <int D, class PosView>
KOKKOS_INLINE_FUNCTION void gather_element(const PosView& x, const ElementData<D>& el, int e, double (&xe)[D + 1][D],
                                           double (&G)[D][D]) {
  for (int a = 0; a < D + 1; ++a)
    for (int i = 0; i < D; ++i) xe[a][i] = x(el.elem(e, a), i);
  for (int b = 0; b < D; ++b)
    for (int j = 0; j < D; ++j) G[b][j] = el.grad(e, b, j);
}

// Positions of interface q's node pairs: xa[k] (side A) and xb[k] (side B), k < D.
template <int D, class PosView, class IfaceView>
KOKKOS_INLINE_FUNCTION void gather_interface(const PosView& x, const IfaceView& iface, int q, double (&xa)[D][D],
                                             double (&xb)[D][D]) {
  for (int k = 0; k < D; ++k)
    for (int i = 0; i < D; ++i) {
      xa[k][i] = x(iface(q, k), i);
      xb[k][i] = x(iface(q, D + k), i);
    }
}

}  // namespace fdem
