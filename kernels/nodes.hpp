#pragma once
// The node update of one explicit step (docs/theory.md section 2): central differences
// (leap-frog) with local and mass-proportional damping and velocity boundary conditions, and the
// sums the energy ledger needs (docs/theory.md section 7).
#include "kernels/model.hpp"

namespace fdem {

constexpr int kLoadRampSlots = 8;  // distinct ramp times of the point loads (kMaxLoadRamps, io/case.hpp)

struct NodeUpdateParams {
  double gravity[3];
  double alpha;      // local non-viscous damping
  double cmass;      // mass-proportional damping (1/s)
  double t, dt;      // time of the current positions, step to the next positions
  // Velocity step: the time between v(n-1/2) and v(n+1/2), (dt_old + dt) / 2; = dt except on the
  // step where dt changes (Simulation: contact's stable step applies once surfaces can meet).
  double dtv;
  bool has_fext;
  // Ramped point loads (Model::fext_ramp): load_ramps groups, group g reaches its full force at
  // load_ramp[g] s; load_scale[g] = min(1, t / load_ramp[g]) at the time t, load_scale_next[g] at
  // t + dt (set by load_scales).
  int load_ramps;
  double load_ramp[kLoadRampSlots];
  double load_scale[kLoadRampSlots], load_scale_next[kLoadRampSlots];
};

// The parameters with the ramped loads' factors at the time p.t of the current positions and at
// p.t + p.dt, that of the next.
inline NodeUpdateParams load_scales(NodeUpdateParams p) {
  for (int g = 0; g < p.load_ramps; ++g) {
    const double T = p.load_ramp[g], tn = p.t + p.dt;
    p.load_scale[g] = p.t >= T ? 1.0 : p.t / T;
    p.load_scale_next[g] = tn >= T ? 1.0 : tn / T;
  }
  return p;
}

// Sums of one node update: energy dissipated by damping and work of the velocity BCs and of the
// ramped point loads over this step (accumulated every step; the ramped loads' from x(n) to
// x(n+1), the others centred on x(n)); on sampled steps also the kinetic
// energy 0.5 m v(n-1/2).v(n+1/2) (the leap-frog's conserved form), the work of gravity and of the
// constant point loads at x(n) (F . u: path-independent for a constant force), and the
// linear momentum sum m (v(n-1/2) + v(n+1/2)) / 2 at time n (components beyond D stay 0).
// A parallel_reduce result type in Kokkos 3.4.1 (volatile join) and 4.x (plain join).
struct NodeSums {
  double damping = 0, bc_work = 0, ramp_work = 0;
  double kinetic = 0, gravity_work = 0, load_work = 0;
  double momentum[3] = {0, 0, 0};
  KOKKOS_INLINE_FUNCTION NodeSums() {}
  KOKKOS_INLINE_FUNCTION NodeSums& operator+=(const NodeSums& o) {
    damping += o.damping;
    bc_work += o.bc_work;
    ramp_work += o.ramp_work;
    kinetic += o.kinetic;
    gravity_work += o.gravity_work;
    load_work += o.load_work;
    for (int k = 0; k < 3; ++k) momentum[k] += o.momentum[k];
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile NodeSums& o) volatile {
    damping += o.damping;
    bc_work += o.bc_work;
    ramp_work += o.ramp_work;
    kinetic += o.kinetic;
    gravity_work += o.gravity_work;
    load_work += o.load_work;
    for (int k = 0; k < 3; ++k) momentum[k] += o.momentum[k];
  }
#endif
};

// Central-difference update of one node with damping and velocity BCs; zeroes its force for the
// next step. The work of a force over the step is F . (v(n-1/2) + v(n+1/2)) dt / 2, which makes
// the kinetic-energy change of a node exactly the work of the forces on it.
// Damp = false: the scene has no damping (alpha = c = 0): no damping force, no damping work (the
// results are the same as with Damp = true at zero damping). Ramp: the scene has ramped point
// loads (p.load_ramps > 0; without, the update is the one of constant loads alone).
template <int D, bool Sample, bool Damp, bool Ramp>
struct NodeUpdate {
  Kokkos::View<double* [D]> x, X, v, f, fext;
  Kokkos::View<double** [D]> fext_ramp;
  Kokkos::View<double*> mass;
  Kokkos::View<int*> node_bc;
  Kokkos::View<BCDev*> bcs;
  NodeUpdateParams p;
  double th;  // velocities live at half steps

  KOKKOS_INLINE_FUNCTION void operator()(const int i, NodeSums& s) const {
    // the parameters as locals: the compiler cannot tell that the stores to the Views leave them alone
    const double dt = p.dt, dtv = p.dtv, alpha = p.alpha, cmass = p.cmass;
    const double mi = mass(i);
    const int bc = node_bc(i);
    for (int k = 0; k < D; ++k) {
      double F = f(i, k) + mi * p.gravity[k];
      const double fe = p.has_fext ? fext(i, k) : 0.0;
      F += fe;
      double fr = 0.0, frn = 0.0;  // ramped point loads at time p.t and p.t + p.dt
      if (Ramp) {
        for (int g = 0; g < p.load_ramps; ++g) {
          const double a = fext_ramp(g, i, k);
          fr += a * p.load_scale[g];
          frn += a * p.load_scale_next[g];
        }
        F += fr;
      }
      const double vo = v(i, k);
      double vn;
      if (bc >= 0 && (bcs(bc).mask >> k & 1)) {
        const double r = bcs(bc).ramp > 0 ? kmin(1.0, th / bcs(bc).ramp) : 1.0;
        vn = bcs(bc).vel[k] * r;
        s.bc_work += (mi * (vn - vo) / dtv - F) * 0.5 * (vo + vn) * dtv;
      } else if (Damp) {
        double fd = -cmass * mi * vo;
        if (alpha > 0) {  // without branches on the signs: they are random from node to node
          const double sign_v = static_cast<double>((vo > 0) - (vo < 0));
          fd -= alpha * kmath::fabs(F + fd) * sign_v;
        }
        vn = vo + dtv * (F + fd) / mi;
        s.damping -= fd * 0.5 * (vo + vn) * dtv;
      } else {
        vn = vo + dtv * F / mi;
      }
      if (Ramp) {
        if (bc >= 0 && (bcs(bc).mask >> k & 1))  // with the reaction's work, as the BC's work counts it
          s.bc_work += fr * 0.5 * (vo + vn) * dtv;
        else  // over the straight path x(n) -> x(n+1) with the force linear in time on it
          s.ramp_work += 0.5 * (fr + frn) * vn * dt;
      }
      if (Sample) {
        const double u = x(i, k) - X(i, k);
        s.kinetic += 0.5 * mi * vo * vn;
        s.gravity_work += mi * p.gravity[k] * u;
        s.load_work += fe * u;
        s.momentum[k] += 0.5 * mi * (vo + vn);
      }
      v(i, k) = vn;
      x(i, k) += dt * vn;
      f(i, k) = 0.0;
    }
  }
};

// The same without sums (an unsampled step of a scene without damping and velocity BCs).
template <class Update>
struct NodeUpdateNoSums {
  Update u;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const {
    NodeSums s;
    u(i, s);
  }
};

// Update of the own nodes (all but the ghosts of a decomposed run: NodeData::nn_own). The sums are reduced only when there is something to sum: on sampled
// steps, or when the scene has damping, velocity BCs or ramped point loads (their work is
// accumulated every step); otherwise the pass is a plain parallel_for.
template <int D, bool Sample, bool Damp, bool Ramp>
NodeSums update_nodes(const Model<D>& m, const NodeUpdateParams& prm_t) {
  const NodeUpdateParams prm = load_scales(prm_t);
  const NodeUpdate<D, Sample, Damp, Ramp> fn{
      m.x, m.X, m.v, m.f, m.fext, m.fext_ramp, m.mass, m.node_bc, m.bcs, prm, prm.t + 0.5 * prm.dt};
  NodeSums out;
  const bool reduce = Sample || Damp || Ramp || m.bcs.extent(0) > 0;
  if (reduce) {
    Kokkos::parallel_reduce("fdem::nodes", Kokkos::RangePolicy<ExecSpace>(0, m.owned_nodes()), fn, out);
  } else {
    Kokkos::parallel_for("fdem::nodes", Kokkos::RangePolicy<ExecSpace>(0, m.owned_nodes()),
                         NodeUpdateNoSums<NodeUpdate<D, Sample, Damp, Ramp>>{fn});
  }
  return out;
}

// The update of an unsampled step (Sample = false) without a wait for the host: the sums are
// reduced into device memory (`sums`) and the damping, velocity-BC and ramped-load works added to
// `work` (0: damping, 1: velocity BCs, 2: ramped point loads) there, in step order (Simulation
// reads them on sampled steps).
template <int D, bool Damp, bool Ramp>
void update_nodes_unsampled(const Model<D>& m, const NodeUpdateParams& prm_t,
                            const Kokkos::View<NodeSums>& sums, const Kokkos::View<double[3]>& work) {
  const NodeUpdateParams prm = load_scales(prm_t);
  const NodeUpdate<D, false, Damp, Ramp> fn{
      m.x, m.X, m.v, m.f, m.fext, m.fext_ramp, m.mass, m.node_bc, m.bcs, prm, prm.t + 0.5 * prm.dt};
  if (!(Damp || Ramp || m.bcs.extent(0) > 0)) {
    Kokkos::parallel_for("fdem::nodes", Kokkos::RangePolicy<ExecSpace>(0, m.owned_nodes()),
                         NodeUpdateNoSums<NodeUpdate<D, false, Damp, Ramp>>{fn});
    return;
  }
  Kokkos::parallel_reduce("fdem::nodes [device]", Kokkos::RangePolicy<ExecSpace>(0, m.owned_nodes()), fn, sums);
  auto s = sums;
  auto w = work;
  Kokkos::parallel_for(
      "fdem::nodes::work", Kokkos::RangePolicy<ExecSpace>(0, 1), KOKKOS_LAMBDA(const int) {
        w(0) += s().damping;
        w(1) += s().bc_work;
        w(2) += s().ramp_work;
      });
}

// A sampled step's works (the host sums `s` of update_nodes) added to the device accumulators
// `work`, as update_nodes_unsampled adds an unsampled step's: the accumulators stay on the device
// and the host only reads them.
inline void add_node_works(const Kokkos::View<double[3]>& work, const NodeSums& s) {
  auto w = work;
  const double damping = s.damping, bc = s.bc_work, ramp = s.ramp_work;
  Kokkos::parallel_for(
      "fdem::nodes::work [sampled]", Kokkos::RangePolicy<ExecSpace>(0, 1), KOKKOS_LAMBDA(const int) {
        w(0) += damping;
        w(1) += bc;
        w(2) += ramp;
      });
}

}  // namespace fdem

namespace Kokkos {
template <>
struct reduction_identity<fdem::NodeSums> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::NodeSums sum() { return fdem::NodeSums(); }
};
}  // namespace Kokkos
