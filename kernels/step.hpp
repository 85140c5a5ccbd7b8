#pragma once
// The kernels of one explicit step, and the reductions done on output/check steps only.
// Free functions that copy the Views they need into locals before each KOKKOS_LAMBDA, so that the
// same source compiles for OpenMP and CUDA (no virtual calls, no std containers, no exceptions).
#include "kernels/cohesive.hpp"
#include "kernels/elastic.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Chunk of items per work item for the scatter: 256 on host backends (one access() per chunk),
// 1 on GPUs (one thread per item, atomics).
constexpr int kChunk =
    Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible ? kScatterChunk : 1;

// Geometry of an interface: unit normal n (from side A to side B) of the mid-surface and the
// tributary area of each integration point (nodal integration: one point per node pair) in the
// current configuration. The forces use the reference area (tractions per unit reference area,
// so that they derive from a stored energy); the current one serves the set-up.
template <int D>
KOKKOS_INLINE_FUNCTION void interface_frame(const double (&xa)[D][D], const double (&xb)[D][D],
                                            double thickness, double (&n)[D], double& area_pt) {
  double m[D][D];
  for (int k = 0; k < D; ++k)
    for (int i = 0; i < D; ++i) m[k][i] = 0.5 * (xa[k][i] + xb[k][i]);
  if constexpr (D == 2) {
    const double tx = m[1][0] - m[0][0], ty = m[1][1] - m[0][1];
    const double L = kmath::sqrt(tx * tx + ty * ty);
    n[0] = ty / L;
    n[1] = -tx / L;
    area_pt = 0.5 * L * thickness;
  } else {
    const double a[3] = {m[1][0] - m[0][0], m[1][1] - m[0][1], m[1][2] - m[0][2]};
    const double b[3] = {m[2][0] - m[0][0], m[2][1] - m[0][1], m[2][2] - m[0][2]};
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double len = kmath::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int i = 0; i < D; ++i) n[i] = c[i] / len;
    area_pt = 0.5 * len / 3.0;
  }
}

// An interface has come apart when one of its failed points (D = 1) has its node pair farther
// apart than the A face's inradius (2D: half its length). Its mid-surface, and so the normal of
// its compressive penalty and of whatever cohesion its other points still have, is then no
// longer meaningful (it degenerates when one fragment has turned over against the other, and a
// penalty along a flipped normal pushes with the force of a millimetre-deep overlap: in the 3D
// multi-particle impact an interface whose one corner still held while the other two were 8 mm
// apart kicked a node to 3.5e4 m/s). From the step this is first seen on, every point of the
// interface is failed (interface_fail_all) and it carries nothing and stores nothing: without
// contact (case key contact.enabled = false) for good (Model::icontact; switching back on would
// release whatever overlap its faces reached meanwhile), with contact until the next handover
// check makes its faces contact surfaces. Faces that stay close (sliding or pressed together)
// keep the penalty; with contact, interface_parted below hands them over.
template <int D>
KOKKOS_INLINE_FUNCTION bool interface_apart(const double (&xa)[D][D], const double (&xb)[D][D],
                                            const CohesivePoint (&h)[D]) {
  bool failed = false;
  for (int k = 0; k < D; ++k) failed = failed || cohesive_damage(h[k]) >= 1.0;
  if (!failed) return false;
  double r2;
  if constexpr (D == 2) {
    const double tx = xa[1][0] - xa[0][0], ty = xa[1][1] - xa[0][1];
    r2 = 0.25 * (tx * tx + ty * ty);
  } else {
    double e[3][3], per = 0;
    for (int k = 0; k < 3; ++k) {
      double l2 = 0;
      for (int i = 0; i < 3; ++i) {
        e[k][i] = xa[(k + 1) % 3][i] - xa[k][i];
        l2 += e[k][i] * e[k][i];
      }
      per += kmath::sqrt(l2);
    }
    const double c[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                         e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    const double r = kmath::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / per;  // 2 area / perimeter
    r2 = r * r;
  }
  for (int k = 0; k < D; ++k) {
    if (cohesive_damage(h[k]) < 1.0) continue;
    double d2 = 0;
    for (int i = 0; i < D; ++i) d2 += (xb[k][i] - xa[k][i]) * (xb[k][i] - xa[k][i]);
    if (d2 > r2) return true;
  }
  return false;
}

// Fails every point of an interface that has come apart (interface_apart): a point that still
// holds releases the elastic energy it stores at its present separation, booked as fracture
// dissipation (its remaining fracture energy is never spent: the crack has run past it).
template <int D>
KOKKOS_INLINE_FUNCTION void interface_fail_all(const double (&xa)[D][D], const double (&xb)[D][D], double ap,
                                               const CohesiveParams& p, CohesivePoint (&h)[D]) {
  double n[D], ap_cur;
  interface_frame<D>(xa, xb, 1.0, n, ap_cur);
  for (int k = 0; k < D; ++k) {
    const double dmg = cohesive_damage(h[k]);
    if (dmg >= 1.0) continue;
    double d[D], dn = 0, ds2 = 0;
    for (int i = 0; i < D; ++i) {
      d[i] = xb[k][i] - xa[k][i];
      dn += d[i] * n[i];
    }
    for (int i = 0; i < D; ++i) ds2 += (d[i] - dn * n[i]) * (d[i] - dn * n[i]);
    h[k].wd += ap * cohesive_stored(p, dn, kmath::sqrt(ds2), dmg);
    if (!(h[k].dm0 > 0.0)) h[k].dm0 = 1e-300;  // never initiated: initiated now
    if (!(h[k].dmf > h[k].dm0)) h[k].dmf = 2.0 * h[k].dm0;
    h[k].dmax = h[k].dmax > h[k].dmf ? h[k].dmax : h[k].dmf;
  }
}

// A failed interface is handed over to contact once its faces have parted: open (normal gap >= 0
// at every point), or slid by more than `slip` at some point. Until then the failed interface
// keeps its compression penalty (the cohesive law at D = 1), which holds the crack faces apart
// exactly where contact between them could not yet be trusted (faces still touching at a crack
// tip, copies of a vertex still joined through other interfaces).
template <int D>
KOKKOS_INLINE_FUNCTION bool interface_parted(const double (&xa)[D][D], const double (&xb)[D][D], double slip) {
  double n[D], ap;
  interface_frame<D>(xa, xb, 1.0, n, ap);
  bool open = true, slid = false;
  for (int k = 0; k < D; ++k) {
    double d[D], dn = 0, d2 = 0;
    for (int i = 0; i < D; ++i) {
      d[i] = xb[k][i] - xa[k][i];
      dn += d[i] * n[i];
      d2 += d[i] * d[i];
    }
    open = open && dn >= 0.0;
    slid = slid || d2 - dn * dn > slip * slip;
  }
  return open || slid;
}

// Cohesive forces of one interface: updates the history of its points and returns the forces on
// its A-side (fa) and B-side (fb) nodes, and the mean damage. ap: reference tributary area of a
// point. The forces are the exact gradient of the stored energy U = ap sum_k psi(delta_k . n,
// |delta_k - (delta_k . n) n|) at fixed damage, including the change of the normal n with the
// nodes (it matters once faces have slid or opened far), so that the interface neither creates
// nor loses energy.
template <int D>
KOKKOS_INLINE_FUNCTION double interface_forces(const double (&xa)[D][D], const double (&xb)[D][D],
                                               double ap, const CohesiveParams& p,
                                               CohesivePoint (&h)[D], double (&fa)[D][D],
                                               double (&fb)[D][D]) {
  double n[D], ap_cur;
  interface_frame<D>(xa, xb, 1.0, n, ap_cur);
  double dsum = 0;
  double g[D];  // dU/dn
  for (int i = 0; i < D; ++i) g[i] = 0;
  for (int k = 0; k < D; ++k) {
    double d[D], ds[D], dn = 0;
    for (int i = 0; i < D; ++i) {
      d[i] = xb[k][i] - xa[k][i];
      dn += d[i] * n[i];
    }
    double ds2 = 0;
    for (int i = 0; i < D; ++i) {
      ds[i] = d[i] - dn * n[i];
      ds2 += ds[i] * ds[i];
    }
    double tn, kss, dmg;
    cohesive_update(p, dn, kmath::sqrt(ds2), h[k], tn, kss, dmg);
    dsum += dmg;
    for (int i = 0; i < D; ++i) {
      fa[k][i] = ap * (tn * n[i] + kss * ds[i]);
      fb[k][i] = -fa[k][i];
      g[i] += ap * (tn - kss * dn) * d[i];
    }
  }
  // dU/dn -> forces through the mid-surface points m_k = (xa_k + xb_k) / 2.
  double gp[D], gn = 0;  // projection (I - n n^T) g
  for (int i = 0; i < D; ++i) gn += g[i] * n[i];
  for (int i = 0; i < D; ++i) gp[i] = g[i] - gn * n[i];
  double dm[D][D];  // dU/dm_k
  if constexpr (D == 2) {
    // n = (t_y, -t_x) / L with t = m1 - m0: dU/dt = (1/L) R^T gp, R^T (gx, gy) = (-gy, gx)
    const double tx = 0.5 * (xa[1][0] + xb[1][0] - xa[0][0] - xb[0][0]);
    const double ty = 0.5 * (xa[1][1] + xb[1][1] - xa[0][1] - xb[0][1]);
    const double L = kmath::sqrt(tx * tx + ty * ty);
    const double Gt[2] = {-gp[1] / L, gp[0] / L};
    for (int i = 0; i < 2; ++i) {
      dm[1][i] = Gt[i];
      dm[0][i] = -Gt[i];
    }
  } else {
    // n = c / |c|, c = a x b, a = m1 - m0, b = m2 - m0: dU/dc = gp / |c|,
    // dU/da = b x hc, dU/db = hc x a
    double a[3], b[3];
    for (int i = 0; i < 3; ++i) {
      a[i] = 0.5 * (xa[1][i] + xb[1][i] - xa[0][i] - xb[0][i]);
      b[i] = 0.5 * (xa[2][i] + xb[2][i] - xa[0][i] - xb[0][i]);
    }
    const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double cl = kmath::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    const double hc[3] = {gp[0] / cl, gp[1] / cl, gp[2] / cl};
    const double da[3] = {b[1] * hc[2] - b[2] * hc[1], b[2] * hc[0] - b[0] * hc[2], b[0] * hc[1] - b[1] * hc[0]};
    const double db[3] = {hc[1] * a[2] - hc[2] * a[1], hc[2] * a[0] - hc[0] * a[2], hc[0] * a[1] - hc[1] * a[0]};
    for (int i = 0; i < 3; ++i) {
      dm[1][i] = da[i];
      dm[2][i] = db[i];
      dm[0][i] = -da[i] - db[i];
    }
  }
  for (int k = 0; k < D; ++k)
    for (int i = 0; i < D; ++i) {
      fa[k][i] -= 0.5 * dm[k][i];
      fb[k][i] -= 0.5 * dm[k][i];
    }
  return dsum / D;
}

// Internal forces of bulk elements and interfaces, fused in one kernel and scattered into m.f
// (which the node update left at zero). contribute = false: the sums stay in sf (the caller adds
// the contact forces to it and contributes).
// Work items: on host backends each chunk of kChunk elements with the interfaces whose side A
// lies in it (Model::ichunk: one pass over the nodes), else bulk chunks, then interface chunks.
template <int D>
void compute_forces(const Model<D>& m, ForceScatter<D>& sf, bool contribute = true) {
  const int ne = m.ne, ni = m.ni;
  const int nbc = (ne + kChunk - 1) / kChunk, nic = (ni + kChunk - 1) / kChunk;
  auto x = m.x;
  auto elem = m.elem;
  auto grad = m.grad;
  auto vol0 = m.vol0;
  auto emat = m.emat;
  auto mat = m.mat;
  auto iface = m.iface;
  auto ihist = m.ihist;
  auto iarea = m.iarea;
  const auto coh = m.coh;
  auto icontact = m.icontact;
  auto pending = m.icontact_pending;
  const bool handover = m.contact_handover;
  const double handover_slip = m.handover_slip;
  auto ichunk = m.ichunk;
  // fused: work item c = element chunk c and the interfaces whose side A lies in it (one pass over
  // the nodes: side A's positions and forces are still in cache); else bulk chunks, then
  // interface chunks
  const bool fused = kChunk > 1 && static_cast<int>(ichunk.extent(0)) == nbc + 1;
  sf.reset();
  Kokkos::parallel_for(
      "fdem::forces", Kokkos::RangePolicy<ExecSpace>(0, fused ? nbc : nbc + nic), KOKKOS_LAMBDA(const int c) {
        auto acc = sf.access();
        auto bulk = [&](const int e) {
          double xe[D + 1][D], G[D][D], fe[D + 1][D];
          for (int a = 0; a < D + 1; ++a)
            for (int i = 0; i < D; ++i) xe[a][i] = x(elem(e, a), i);
          for (int b = 0; b < D; ++b)
            for (int j = 0; j < D; ++j) G[b][j] = grad(e, b, j);
          const int mt = emat(e);
          element_forces<D>(xe, G, vol0(e), mat(mt, 0), mat(mt, 1), fe);
          for (int a = 0; a < D + 1; ++a)
            for (int i = 0; i < D; ++i) acc(elem(e, a), i) += fe[a][i];
        };
        auto interface = [&](const int q) {
          if (handover && icontact(q)) return;  // failed: its faces are in contact instead
          double xa[D][D], xb[D][D], fa[D][D], fb[D][D];
          CohesivePoint h[D];
          for (int k = 0; k < D; ++k) {
            for (int i = 0; i < D; ++i) {
              xa[k][i] = x(iface(q, k), i);
              xb[k][i] = x(iface(q, D + k), i);
            }
            h[k] = load_point(ihist, q, k);
          }
          // Model::icontact: 1 once the interface carries nothing (handed over to contact; or,
          // without contact, come apart for good: interface_apart).
          if (icontact(q)) return;
          if (interface_apart<D>(xa, xb, h)) {
            interface_fail_all<D>(xa, xb, iarea(q), coh, h);
            for (int k = 0; k < D; ++k) {
              store_point(ihist, q, k, h[k]);
            }
            if (handover) Kokkos::atomic_exchange(&pending(), 1);
            else icontact(q) = 1;
            return;
          }
          const double dmean = interface_forces<D>(xa, xb, iarea(q), coh, h, fa, fb);
          if (handover && dmean >= 1.0 && interface_parted<D>(xa, xb, handover_slip))
            Kokkos::atomic_exchange(&pending(), 1);
          for (int k = 0; k < D; ++k) {
            store_point(ihist, q, k, h[k]);
            for (int i = 0; i < D; ++i) {
              acc(iface(q, k), i) += fa[k][i];
              acc(iface(q, D + k), i) += fb[k][i];
            }
          }
        };
        if (fused) {
          const int e1 = kmin((c + 1) * kChunk, ne);
          for (int e = c * kChunk; e < e1; ++e) bulk(e);
          for (int q = ichunk(c); q < ichunk(c + 1); ++q) interface(q);
        } else if (c < nbc) {
          const int e1 = kmin((c + 1) * kChunk, ne);
          for (int e = c * kChunk; e < e1; ++e) bulk(e);
        } else {
          const int i0 = (c - nbc) * kChunk, i1 = kmin(i0 + kChunk, ni);
          for (int q = i0; q < i1; ++q) interface(q);
        }
      });
  if (!contribute) return;  // the caller adds more (contact) and contributes
  auto f = m.f;
  Kokkos::Experimental::contribute(f, sf);
}

// Rigid platens acting on the boundary nodes: normal penalty (no tension) and incremental shear
// spring with Coulomb friction and cohesion. Adds to m.f (after the scatter, one writer per
// node), accumulates platen forces, work and friction dissipation. t: time of positions x.
template <int D>
void apply_platens(const Model<D>& m, double t, double dt) {
  if (m.platens.count == 0 || m.nb == 0) return;
  const auto ps = m.platens;
  auto acc = m.platen_acc;
  Kokkos::parallel_for(
      "fdem::platens::reset", Kokkos::RangePolicy<ExecSpace>(0, ps.count), KOKKOS_LAMBDA(const int p) {
        acc(p, 0) = 0; acc(p, 1) = 0; acc(p, 2) = 0; acc(p, 5) = 0;
      });
  auto x = m.x;
  auto v = m.v;
  auto f = m.f;
  auto bnode = m.bnode;
  auto barea = m.barea;
  auto fs = m.platen_fs;
  auto g0 = m.platen_g0;
  Kokkos::parallel_for(
      "fdem::platens", Kokkos::RangePolicy<ExecSpace>(0, m.nb), KOKKOS_LAMBDA(const int b) {
        const int i = bnode(b);
        const double A = barea(i);
        for (int p = 0; p < ps.count; ++p) {
          const PlatenDev& P = ps.p[p];
          double g = 0;
          for (int k = 0; k < D; ++k) g += (x(i, k) - (P.p0[k] + P.vel[k] * t)) * P.n[k];
          // relative displacement increment over the last step
          double du[D], dun = 0;
          for (int k = 0; k < D; ++k) {
            du[k] = (v(i, k) - P.vel[k]) * dt;
            dun += du[k] * P.n[k];
          }
          // Friction is booked as in contact_pair (kernels/contact.hpp): the shear spring's
          // energy before minus after, plus the work of du against the mean of the old and new
          // shear forces (zero while sticking, the leap-frog's work while slipping); a contact
          // that ends releases its spring's energy and the work of its last half step.
          // gap from the allowance g0 (<= 0, Simulation::sync_platen_nodes), which follows the
          // node out while it is shallower
          if (g >= g0(p, i)) g0(p, i) = g < 0.0 ? g : 0.0;
          g -= g0(p, i);
          if (g >= 0.0) {
            double f2 = 0, w = 0;
            for (int k = 0; k < D; ++k) {
              f2 += fs(p, i, k) * fs(p, i, k);
              w += fs(p, i, k) * du[k];
              fs(p, i, k) = 0.0;
            }
            if (f2 > 0.0) Kokkos::atomic_add(&acc(p, 4), 0.5 * f2 / (P.ks * A) - 0.5 * w);
            continue;
          }
          const double Fn = -P.kn * A * g;
          double fs0[D], Fs[D], fsn = 0, Fs2 = 0, f2old = 0;
          for (int k = 0; k < D; ++k) fsn += fs(p, i, k) * P.n[k];
          for (int k = 0; k < D; ++k) {
            fs0[k] = fs(p, i, k) - fsn * P.n[k];
            f2old += fs0[k] * fs0[k];
            Fs[k] = fs0[k] - P.ks * A * (du[k] - dun * P.n[k]);
            Fs2 += Fs[k] * Fs[k];
          }
          const double lim = P.mu * Fn + P.coh * A;
          const double Fsm = kmath::sqrt(Fs2);
          if (Fsm > lim) {
            const double r = Fsm > 0 ? lim / Fsm : 0.0;
            double w = 0;
            for (int k = 0; k < D; ++k) {
              Fs[k] *= r;
              w += (fs0[k] + Fs[k]) * du[k];
            }
            Kokkos::atomic_add(&acc(p, 4), 0.5 * (f2old - lim * lim) / (P.ks * A) - 0.5 * w);
          }
          double work = 0;
          for (int k = 0; k < D; ++k) {
            const double Fk = Fn * P.n[k] + Fs[k];
            fs(p, i, k) = Fs[k];
            f(i, k) += Fk;
            Kokkos::atomic_add(&acc(p, k), Fk);
            work += Fk * P.vel[k] * dt;
          }
          Kokkos::atomic_add(&acc(p, 3), work);
          Kokkos::atomic_add(&acc(p, 5), 1.0);
        }
      });
}

struct NodeUpdateParams {
  double gravity[3];
  double alpha;      // local non-viscous damping
  double cmass;      // mass-proportional damping (1/s)
  double t, dt;      // time of the current positions, step to the next positions
  // Velocity step: the time between v(n-1/2) and v(n+1/2), (dt_old + dt) / 2; = dt except on the
  // step where dt changes (Simulation: contact's stable step applies once surfaces can meet).
  double dtv;
  bool has_fext;
};

// Sums of one node update: energy dissipated by damping and work of the velocity BCs over this
// step (0, 1); on sampled steps also the kinetic energy 0.5 m v(n-1/2).v(n+1/2) (the leap-frog's
// conserved form) (2), the work of gravity (3) and of the point loads (4) at x(n), and the linear
// momentum sum m (v(n-1/2) + v(n+1/2)) / 2 at time n (5, 6, 7; components beyond D stay 0).
using NodeSums = SumN<8>;

// Central-difference update of one node with damping and velocity BCs; zeroes its force for the
// next step. The work of a force over the step is F . (v(n-1/2) + v(n+1/2)) dt / 2, which makes
// the kinetic-energy change of a node exactly the work of the forces on it.
// Damp = false: the scene has no damping (alpha = c = 0): no damping force, no damping work (the
// results are the same as with Damp = true at zero damping).
template <int D, bool Sample, bool Damp>
struct NodeUpdate {
  Kokkos::View<double* [D]> x, X, v, f, fext;
  Kokkos::View<double*> mass;
  Kokkos::View<int*> node_bc;
  Kokkos::View<BCDev*> bcs;
  NodeUpdateParams p;
  double th;  // velocities live at half steps

  KOKKOS_INLINE_FUNCTION void operator()(const int i, NodeSums& s) const {
    const double mi = mass(i);
    const int bc = node_bc(i);
    for (int k = 0; k < D; ++k) {
      double F = f(i, k) + mi * p.gravity[k];
      const double fe = p.has_fext ? fext(i, k) : 0.0;
      F += fe;
      const double vo = v(i, k);
      double vn;
      if (bc >= 0 && (bcs(bc).mask >> k & 1)) {
        const double r = bcs(bc).ramp > 0 ? kmin(1.0, th / bcs(bc).ramp) : 1.0;
        vn = bcs(bc).vel[k] * r;
        s.v[1] += (mi * (vn - vo) / p.dtv - F) * 0.5 * (vo + vn) * p.dtv;
      } else if (Damp) {
        double fd = -p.cmass * mi * vo;
        if (p.alpha > 0) {
          const double fu = F + fd;
          fd -= p.alpha * (fu < 0 ? -fu : fu) * (vo > 0 ? 1.0 : (vo < 0 ? -1.0 : 0.0));
        }
        vn = vo + p.dtv * (F + fd) / mi;
        s.v[0] -= fd * 0.5 * (vo + vn) * p.dtv;
      } else {
        vn = vo + p.dtv * F / mi;
      }
      if (Sample) {
        const double u = x(i, k) - X(i, k);
        s.v[2] += 0.5 * mi * vo * vn;
        s.v[3] += mi * p.gravity[k] * u;
        s.v[4] += fe * u;
        s.v[5 + k] += 0.5 * mi * (vo + vn);
      }
      v(i, k) = vn;
      x(i, k) += p.dt * vn;
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

// Update of all nodes. The sums are reduced only when there is something to sum: on sampled
// steps, or when the scene has damping or velocity BCs (their work is accumulated every step);
// otherwise the pass is a plain parallel_for.
template <int D, bool Sample, bool Damp>
NodeSums update_nodes(const Model<D>& m, const NodeUpdateParams& prm) {
  const NodeUpdate<D, Sample, Damp> fn{m.x, m.X, m.v, m.f, m.fext, m.mass, m.node_bc, m.bcs, prm,
                                       prm.t + 0.5 * prm.dt};
  NodeSums out;
  const bool reduce = Sample || Damp || m.bcs.extent(0) > 0;
  if (reduce) {
    Kokkos::parallel_reduce("fdem::nodes", Kokkos::RangePolicy<ExecSpace>(0, m.nn), fn, out);
  } else {
    Kokkos::parallel_for("fdem::nodes", Kokkos::RangePolicy<ExecSpace>(0, m.nn),
                         NodeUpdateNoSums<NodeUpdate<D, Sample, Damp>>{fn});
  }
  return out;
}

// ---- reductions for output and checks (not every step) ----

// Bulk strain energy.
template <int D>
double strain_energy(const Model<D>& m) {
  auto x = m.x;
  auto elem = m.elem;
  auto grad = m.grad;
  auto vol0 = m.vol0;
  auto emat = m.emat;
  auto mat = m.mat;
  double w = 0;
  Kokkos::parallel_reduce(
      "fdem::strain_energy", Kokkos::RangePolicy<ExecSpace>(0, m.ne),
      KOKKOS_LAMBDA(const int e, double& s) {
        double xe[D + 1][D], G[D][D], F[D][D], S[D][D];
        for (int a = 0; a < D + 1; ++a)
          for (int i = 0; i < D; ++i) xe[a][i] = x(elem(e, a), i);
        for (int b = 0; b < D; ++b)
          for (int j = 0; j < D; ++j) G[b][j] = grad(e, b, j);
        deformation_gradient<D>(xe, G, F);
        const int mt = emat(e);
        s += vol0(e) * svk_stress<D>(F, mat(mt, 0), mat(mt, 1), S);
      },
      w);
  return w;
}

// Interfaces: (stored elastic energy, dissipated fracture energy, damaged count, failed count).
template <int D>
SumN<4> interface_state(const Model<D>& m) {
  auto x = m.x;
  auto iface = m.iface;
  auto ihist = m.ihist;
  auto iarea = m.iarea;
  const auto coh = m.coh;
  auto icontact = m.icontact;
  SumN<4> out;
  Kokkos::parallel_reduce(
      "fdem::interface_state", Kokkos::RangePolicy<ExecSpace>(0, m.ni),
      KOKKOS_LAMBDA(const int q, SumN<4>& s) {
        double xa[D][D], xb[D][D], n[D], ap;
        for (int k = 0; k < D; ++k)
          for (int i = 0; i < D; ++i) {
            xa[k][i] = x(iface(q, k), i);
            xb[k][i] = x(iface(q, D + k), i);
          }
        interface_frame<D>(xa, xb, 1.0, n, ap);
        ap = iarea(q);
        const bool handed = icontact(q);  // carries nothing, stores nothing
        bool any = false, all = true;
        for (int k = 0; k < D; ++k) {
          const CohesivePoint h = load_point(ihist, q, k);
          double d[D], dn = 0, ds2 = 0;
          for (int i = 0; i < D; ++i) {
            d[i] = xb[k][i] - xa[k][i];
            dn += d[i] * n[i];
          }
          for (int i = 0; i < D; ++i) ds2 += (d[i] - dn * n[i]) * (d[i] - dn * n[i]);
          const double dmg = cohesive_damage(h);
          if (!handed) s.v[0] += ap * cohesive_stored(coh, dn, kmath::sqrt(ds2), dmg);
          s.v[1] += ap * cohesive_dissipation(h);
          any = any || dmg > 0.0;
          all = all && dmg >= 1.0;
        }
        s.v[2] += any ? 1.0 : 0.0;
        s.v[3] += all ? 1.0 : 0.0;
      },
      out);
  return out;
}

// Elastic energy stored in the platen springs (normal and shear).
template <int D>
double platen_energy(const Model<D>& m, double t) {
  if (m.platens.count == 0 || m.nb == 0) return 0.0;
  const auto ps = m.platens;
  auto x = m.x;
  auto bnode = m.bnode;
  auto barea = m.barea;
  auto fs = m.platen_fs;
  auto g0 = m.platen_g0;
  double e = 0;
  Kokkos::parallel_reduce(
      "fdem::platen_energy", Kokkos::RangePolicy<ExecSpace>(0, m.nb),
      KOKKOS_LAMBDA(const int b, double& s) {
        const int i = bnode(b);
        const double A = barea(i);
        for (int p = 0; p < ps.count; ++p) {
          const PlatenDev& P = ps.p[p];
          double g = 0, f2 = 0;
          for (int k = 0; k < D; ++k) {
            g += (x(i, k) - (P.p0[k] + P.vel[k] * t)) * P.n[k];
            f2 += fs(p, i, k) * fs(p, i, k);
          }
          g -= g0(p, i);
          if (g < 0) s += 0.5 * P.kn * A * g * g + 0.5 * f2 / (P.ks * A);
        }
      },
      e);
  return e;
}

// Sum of the internal force over a node list (reaction of a velocity BC = minus this sum).
template <int D>
void node_list_force(const Model<D>& m, const Kokkos::View<int*>& nodes, double (&out)[3]) {
  auto f = m.f;
  SumN<3> s;
  Kokkos::parallel_reduce(
      "fdem::node_list_force", Kokkos::RangePolicy<ExecSpace>(0, nodes.extent(0)),
      KOKKOS_LAMBDA(const int j, SumN<3>& a) {
        for (int k = 0; k < D; ++k) a.v[k] += f(nodes(j), k);
      },
      s);
  for (int k = 0; k < 3; ++k) out[k] = s.v[k];
}

// Mean displacement of a node list (monitors: crack mouth opening, deflections).
template <int D>
void node_list_displacement(const Model<D>& m, const Kokkos::View<int*>& nodes, double (&out)[3]) {
  auto x = m.x;
  auto X = m.X;
  SumN<3> s;
  Kokkos::parallel_reduce(
      "fdem::node_list_displacement", Kokkos::RangePolicy<ExecSpace>(0, nodes.extent(0)),
      KOKKOS_LAMBDA(const int j, SumN<3>& a) {
        for (int k = 0; k < D; ++k) a.v[k] += x(nodes(j), k) - X(nodes(j), k);
      },
      s);
  const double n = nodes.extent(0) > 0 ? static_cast<double>(nodes.extent(0)) : 1.0;
  for (int k = 0; k < 3; ++k) out[k] = s.v[k] / n;
}

// Per-element Cauchy stress (6 components) and per-interface mean damage, for snapshots.
template <int D>
void element_stress(const Model<D>& m, const Kokkos::View<double* [6]>& out) {
  auto x = m.x;
  auto elem = m.elem;
  auto grad = m.grad;
  auto emat = m.emat;
  auto mat = m.mat;
  const bool ps = m.plane_stress;
  Kokkos::parallel_for(
      "fdem::element_stress", Kokkos::RangePolicy<ExecSpace>(0, m.ne), KOKKOS_LAMBDA(const int e) {
        double xe[D + 1][D], G[D][D], F[D][D], s6[6];
        for (int a = 0; a < D + 1; ++a)
          for (int i = 0; i < D; ++i) xe[a][i] = x(elem(e, a), i);
        for (int b = 0; b < D; ++b)
          for (int j = 0; j < D; ++j) G[b][j] = grad(e, b, j);
        deformation_gradient<D>(xe, G, F);
        const int mt = emat(e);
        cauchy_stress<D>(F, mat(mt, 0), mat(mt, 1), ps, s6);
        for (int c = 0; c < 6; ++c) out(e, c) = s6[c];
      });
}

template <int D>
void interface_damage(const Model<D>& m, const Kokkos::View<double*>& out) {
  auto ihist = m.ihist;
  Kokkos::parallel_for(
      "fdem::interface_damage", Kokkos::RangePolicy<ExecSpace>(0, m.ni), KOKKOS_LAMBDA(const int q) {
        double s = 0;
        for (int k = 0; k < D; ++k)
          s += cohesive_damage(load_point(ihist, q, k));
        out(q) = s / D;
      });
}

}  // namespace fdem
