#pragma once
// Rigid platens (docs/theory.md section 6): their forces on the boundary nodes, the elastic energy
// of their springs, and the growth of a node's platen area when faces around it become contact
// surfaces. The accumulator columns of Model::platen_acc are named in kernels/model.hpp.
#include "kernels/friction.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Platen contact of one boundary node with every platen (apply_platens).
template <int D>
struct PlatenKernel {
  PlatenSet ps;
  Kokkos::View<double* [D]> x, v, f;
  Kokkos::View<int*> bnode;
  Kokkos::View<double*> barea;
  Kokkos::View<double** [D]> fs;
  Kokkos::View<double**> g0;
  Kokkos::View<double* [kPlatenAcc]> acc;
  Kokkos::View<double* [kPlatenMotion]> motion;
  double t, dt;

  // Node i, the b-th of bnode (platen area A), against platen p.
  KOKKOS_INLINE_FUNCTION void contact(const int p, const int i, const int b, const double A) const {
    const PlatenDev& P = ps.p[p];
    double g = 0;
    for (int k = 0; k < D; ++k) g += (x(i, k) - (P.p0[k] + platen_shift(P, motion, p, k, t))) * P.n[k];
    // in front of the platen with no allowance and no shear spring (most nodes at most steps): the
    // path below would write the same zeros and add nothing, so the node is done without its reads
    // and writes
    if (g >= 0.0 && plus_zero(g0(p, b))) {
      bool spring = false;
      for (int k = 0; k < D; ++k) spring = spring || !plus_zero(fs(p, b, k));
      if (!spring) return;
    }
    // relative displacement increment over the last step
    double du[D], dun = 0;
    for (int k = 0; k < D; ++k) {
      du[k] = (v(i, k) - platen_velocity(P, motion, p, k, t - dt, dt)) * dt;
      dun += du[k] * P.n[k];
    }
    // The shear spring follows the Coulomb law shared with contact (kernels/friction.hpp); a
    // contact that ends releases its spring's energy and the work of its last half step.
    // gap from the allowance g0 (<= 0, grow_platen_areas), which follows the
    // node out while it is shallower
    if (g >= g0(p, b)) g0(p, b) = g < 0.0 ? g : 0.0;
    g -= g0(p, b);
    if (g >= 0.0) {
      double f2 = 0, w = 0;
      for (int k = 0; k < D; ++k) {
        f2 += fs(p, b, k) * fs(p, b, k);
        w += fs(p, b, k) * du[k];
        fs(p, b, k) = 0.0;
      }
      if (f2 > 0.0) Kokkos::atomic_add(&acc(p, kPlatenFriction), 0.5 * f2 / (P.ks * A) - 0.5 * w);
      return;
    }
    const double Fn = -P.kn * A * g;
    double fsp[D], fsn = 0;
    for (int k = 0; k < D; ++k) {
      fsp[k] = fs(p, b, k);
      fsn += fsp[k] * P.n[k];
    }
    const ShearStep<D> sh = coulomb_shear<D>(P, P.n, A, Fn, fsp, fsn, du, dun);
    if (sh.slipped) Kokkos::atomic_add(&acc(p, kPlatenFriction), sh.slip);
    const double(&Fs)[D] = sh.Fs;
    double work = 0;
    for (int k = 0; k < D; ++k) {
      const double Fk = Fn * P.n[k] + Fs[k];
      fs(p, b, k) = Fs[k];
      f(i, k) += Fk;
      Kokkos::atomic_add(&acc(p, kPlatenForce + k), Fk);
      work += Fk * P.mean_velocity(k, t - 0.5 * dt, dt) * dt;  // centred on x(t)
    }
    // (a driven platen's work needs its velocity after t: advance_platens books it)
    if (P.inv_mass == 0.0) Kokkos::atomic_add(&acc(p, kPlatenWork), work);
    Kokkos::atomic_add(&acc(p, kPlatenContacts), 1.0);
  }

  KOKKOS_INLINE_FUNCTION void operator()(const int b) const {
    const int i = bnode(b);
    const double A = barea(b);
    for (int p = 0; p < ps.count; ++p) contact(p, i, b, A);
  }
};

// Rigid platens acting on the boundary nodes: normal penalty (no tension) and incremental shear
// spring with Coulomb friction and cohesion. Adds to m.f (after the scatter, one writer per
// node), accumulates platen forces, work and friction dissipation. t: time of positions x.
template <int D>
void apply_platens(const Model<D>& m, double t, double dt) {
  if (m.platens.count == 0 || m.nb == 0) return;
  auto acc = m.platen_acc;
  Kokkos::parallel_for(
      "fdem::platens::reset", Kokkos::RangePolicy<ExecSpace>(0, m.platens.count), KOKKOS_LAMBDA(const int p) {
        acc(p, kPlatenForce + 0) = 0; acc(p, kPlatenForce + 1) = 0; acc(p, kPlatenForce + 2) = 0;
        acc(p, kPlatenContacts) = 0;
      });
  const PlatenKernel<D> kernel{m.platens,    m.x,         m.v,           m.f, m.bnode, m.barea, m.platen_fs,
                               m.platen_g0, m.platen_acc, m.platen_motion, t,   dt};
  Kokkos::parallel_for("fdem::platens", Kokkos::RangePolicy<ExecSpace>(0, m.nb), kernel);
}

// The platens' total force on the body this step (summed over the processes of a decomposed run;
// `given` 0: one process, the accumulators hold it).
struct PlatenTotals {
  int given = 0;
  double F[kMaxPlatens][3] = {};
};

// The driven platens' step, after the node update (the leap-frog of the nodes, kernels/nodes.hpp):
// the speed along n over [t, t + dt] from the speed over [t - dt, t], the reaction to the total
// force on the body and gravity; the travel to t + dt; and the work of the own nodes' forces of this
// step at the mean of the two speeds (centred on x(t), as a prescribed platen's work), so that the
// work done on the body is the platen's loss of kinetic energy 0.5 M v(n - 1/2) v(n + 1/2).
// dtv: the step of the velocities (the nodes' own: the mean of the two steps at a change of dt).
template <int D>
void advance_platens(const Model<D>& m, const PlatenTotals& totals, double dt, double dtv) {
  if (m.platens.count == 0) return;
  const auto ps = m.platens;
  auto acc = m.platen_acc;
  auto motion = m.platen_motion;
  Kokkos::parallel_for(
      "fdem::platens::advance", Kokkos::RangePolicy<ExecSpace>(0, ps.count), KOKKOS_LAMBDA(const int p) {
        const PlatenDev& P = ps.p[p];
        if (!(P.inv_mass > 0)) return;
        double Fn = 0;  // the total force on the body along n
        for (int k = 0; k < D; ++k) Fn += (totals.given ? totals.F[p][k] : acc(p, kPlatenForce + k)) * P.n[k];
        const double v0 = motion(p, kPlatenSpeed);
        const double v1 = v0 + dtv * (P.gn - Fn * P.inv_mass);
        double work = 0;
        for (int k = 0; k < D; ++k) work += acc(p, kPlatenForce + k) * (P.vt[k] + 0.5 * (v0 + v1) * P.n[k]);
        acc(p, kPlatenWork) += work * dtv;
        motion(p, kPlatenTravelAtForces) = motion(p, kPlatenTravel);
        motion(p, kPlatenSpeedAtForces) = 0.5 * (v0 + v1);
        motion(p, kPlatenSpeed) = v1;
        motion(p, kPlatenTravel) += v1 * dt;
      });
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
  auto motion = m.platen_motion;
  double e = 0;
  Kokkos::parallel_reduce(
      "fdem::platen_energy", Kokkos::RangePolicy<ExecSpace>(0, m.nb),
      KOKKOS_LAMBDA(const int b, double& s) {
        const int i = bnode(b);
        const double A = barea(b);
        for (int p = 0; p < ps.count; ++p) {
          const PlatenDev& P = ps.p[p];
          double g = 0, f2 = 0;
          for (int k = 0; k < D; ++k) {
            g += (x(i, k) - (P.p0[k] + platen_shift(P, motion, p, k, t))) * P.n[k];
            f2 += fs(p, b, k) * fs(p, b, k);
          }
          g -= g0(p, b);
          if (g < 0) s += 0.5 * P.kn * A * g * g + 0.5 * f2 / (P.ks * A);
        }
      },
      e);
  return e;
}

// The platens act on the first ns nodes of m.bnode (the contact surface nodes, in the order of
// their list) with their contact areas narea (by the same places): a node's platen area grows when faces around it become surfaces (from 0
// for a node of a crack face just handed over). Its stored energy may not grow with it: a node in
// a platen's penalty zone keeps its normal energy (the allowance g0 takes the rest: a crack face
// node can be well below the plate when it becomes a surface, having slid there along failed
// interfaces, 0.2 mm in the 2D impact at 15 m/s, h = 8 mm), and its shear spring keeps its force
// (the energy that loses is dissipated), as contact_pair does for contacts. t: time of x.
template <int D>
void grow_platen_areas(const Model<D>& m, const Kokkos::View<double*>& narea, int ns, double t) {
  auto bnode = m.bnode;
  auto barea = m.barea;
  auto na = narea;
  auto x = m.x;
  auto fs = m.platen_fs;
  auto g0 = m.platen_g0;
  auto acc = m.platen_acc;
  auto motion = m.platen_motion;
  const auto ps = m.platens;
  const double tn = t;
  Kokkos::parallel_for(
      "fdem::platen_nodes", Kokkos::RangePolicy<ExecSpace>(0, ns), KOKKOS_LAMBDA(const int b) {
        const int i = bnode(b);
        const double A0 = barea(b), A1 = 2.0 * na(b);  // contact area: half the node's share
        if (!(A1 > A0)) return;
        for (int p = 0; p < ps.count; ++p) {
          const PlatenDev& P = ps.p[p];
          double g = 0, f2 = 0;
          for (int k = 0; k < D; ++k) {
            g += (x(i, k) - (P.p0[k] + platen_shift(P, motion, p, k, tn))) * P.n[k];
            f2 += fs(p, b, k) * fs(p, b, k);
          }
          const double ge = g - g0(p, b);
          if (ge < 0.0) g0(p, b) = g - ge * kmath::sqrt(A0 / A1);
          if (f2 > 0.0) Kokkos::atomic_add(&acc(p, kPlatenFriction), 0.5 * f2 * (1.0 / A0 - 1.0 / A1) / P.ks);
        }
        barea(b) = A1;
      });
}

// The platens' rows of the nodes of an old list (`from`: its bnode, barea, platen_fs, platen_g0;
// n rows) into the rows of a new one (`to`, zero where a node is new), at place(i) - 1 for node i
// (0: not in the new list). Returns the old rows that found no place (0 when the new list holds
// every node of the old one).
template <int D>
int carry_platen_rows(const PlatenData<D>& from, int n, const PlatenData<D>& to, const Kokkos::View<int*>& place_in) {
  auto bnode = from.bnode;
  auto place = place_in;
  auto a0 = from.barea, a1 = to.barea;
  auto fs0 = from.platen_fs, fs1 = to.platen_fs;
  auto g00 = from.platen_g0, g01 = to.platen_g0;
  const int np = from.platens.count, cap = static_cast<int>(to.barea.extent(0));
  int lost = 0;
  Kokkos::parallel_reduce(
      "fdem::platens::carry_rows", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int b, int& l) {
        const int c = place(bnode(b)) - 1;
        if (c < 0 || c >= cap) {
          ++l;
          return;
        }
        a1(c) = a0(b);
        for (int p = 0; p < np; ++p) {
          g01(p, c) = g00(p, b);
          for (int k = 0; k < D; ++k) fs1(p, c, k) = fs0(p, b, k);
        }
      },
      lost);
  return lost;
}

}  // namespace fdem
