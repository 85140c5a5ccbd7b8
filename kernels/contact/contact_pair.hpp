#pragma once
// The contact law of one (node, face) pair (docs/theory.md section 6b): normal and shear penalty
// springs (K_n A_c, K_s A_c), no tension, incremental shear force with Coulomb friction and
// cohesion (kernels/friction.hpp), the rules that keep contacts from gaining energy, and the sums
// of a narrow-phase pass. Called by the narrow phase (kernels/contact/narrow_phase.hpp).
#include "kernels/contact/geometry.hpp"
#include "kernels/contact/surfaces.hpp"
#include "kernels/friction.hpp"

namespace fdem {

// Penalty and friction parameters of the contact law, and the geometric tolerances.
struct ContactLaw {
  double kn, ks;     // Pa/m, times the contact area
  double mu, coh;    // friction coefficient, cohesion (Pa)
  double dpen;       // deepest penetration recognised (m); deeper nodes are not in contact
  double tol;        // a contact fades out as its projection leaves the face by this much (barycentric)
  double cos_same;   // coplanar test: faces of one piece with normals closer than this share a contact
  double srf = 1.0;  // strength reduction factor now (divides a frictional joint's friction too)
};

// Results of one narrow-phase pass (a reduction type): energy dissipated by the slip of the shear
// springs and released when a contact opens, number of active contacts (sums); largest squared
// displacement of a surface node since the last build and largest squared speed (maxima), for the
// rebuild test of the next step.
struct ContactSums {
  double dissipated, active, d2max, v2max;
  KOKKOS_INLINE_FUNCTION ContactSums() : dissipated(0), active(0), d2max(0), v2max(0) {}
  KOKKOS_INLINE_FUNCTION ContactSums& operator+=(const ContactSums& o) {
    dissipated += o.dissipated;
    active += o.active;
    d2max = o.d2max > d2max ? o.d2max : d2max;
    v2max = o.v2max > v2max ? o.v2max : v2max;
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile ContactSums& o) volatile {
    dissipated += o.dissipated;
    active += o.active;
    d2max = o.d2max > d2max ? o.d2max : d2max;
    v2max = o.v2max > v2max ? o.v2max : v2max;
  }
#endif
};
// Pair j not (any more) in contact at gap g: the allowance g0 follows the node out; a contact
// that ended (was) dissipates its shear spring's energy and the work of its last half step du.
template <int D, bool Fric>
KOKKOS_INLINE_FUNCTION void contact_open(const ContactLaw& L, const Kokkos::View<double*>& pfn,
                                         const Kokkos::View<double*>& pac, const Kokkos::View<double*>& pg0,
                                         const Kokkos::View<double* [D]>& pfs, int j, double g, double g0,
                                         bool was, const double (&du)[D], ContactSums& sums) {
  pg0(j) = g >= g0 ? (g < 0.0 ? g : 0.0) : g0;
  if (was) {
    if constexpr (Fric) {
      double f2 = 0, w = 0;
      for (int k = 0; k < D; ++k) {
        f2 += pfs(j, k) * pfs(j, k);
        w += pfs(j, k) * du[k];
        pfs(j, k) = 0.0;
      }
      sums.dissipated += 0.5 * f2 / (L.ks * pac(j)) - 0.5 * w;
    }
    pfn(j) = 0.0;
    pac(j) = 0.0;
  }
}

// One (node, face) pair with effective contact area A (0: not in contact): normal penalty (no
// tension), incremental shear spring with Coulomb friction and cohesion (coulomb_shear); forces
// added to the node and, through the contact point's barycentric weights, to the face's nodes;
// history updated. Rule: no energy from nowhere: a starting contact gets only the depth its
// approach explains beyond `limit` (allowance g0), a growing one only the energy in `budget`,
// and what the shear spring loses is dissipated (why and how: docs/theory.md section 6b).
// Fric = false: frictionless contact (mu = 0 and no cohesion): the shear force is zero, so the
// shear spring is neither computed nor stored (its history stays zero; see ContactSystem::update
// for the switch from friction to none).
// seed: a shear force added to the spring's before the step (where seed.on(); seed[k] its
// components), the pair's share of an interface handed over at this poll (HandoverSeed,
// kernels/contact/narrow_phase.hpp); the energy the spring then stores beyond its own is booked
// against the seed's (the caller releases the seed's energy).
template <int D, bool Fric = true, class Force, class SeedForce>
KOKKOS_INLINE_FUNCTION void contact_pair(const ContactSurface<D>& S, const ContactLaw& L,
                                         const Kokkos::View<double* [D]>& v,
                                         const Force& f, const Kokkos::View<double*>& pfn,
                                         const Kokkos::View<double*>& pac, const Kokkos::View<double*>& pg0,
                                         const Kokkos::View<double* [D]>& pfs, int j, int s, int fc,
                                         const double (&xs)[D], const double (&vs)[D], double A, double limit,
                                         double budget, double dt, const SeedForce& seed, ContactSums& sums) {
  const bool was = pfn(j) > 0.0;
  double g0 = pg0(j);
  if (!(A > 0.0) && !(was || g0 < 0.0)) return;  // not in contact, nothing to update
  double n[D], N[D];
  const double g = face_project_geo<D>(S.fgeo, S.fslot(fc), xs, n, N);
  double Nc[D], nsum = 0;
  for (int q = 0; q < D; ++q) {
    Nc[q] = kclamp(N[q], 0.0, 1.0);
    nsum += Nc[q];
  }
  // relative displacement of the node against the contact point over the last step
  double du[D], du2 = 0;
  int fv[D];  // the face's nodes
  S.fnode.get(fc, fv);
  for (int k = 0; k < D; ++k) {
    double vf = 0;
    for (int q = 0; q < D; ++q) vf += Nc[q] / nsum * v(fv[q], k);
    du[k] = (vs[k] - vf) * dt;
    du2 += du[k] * du[k];
  }
  for (int q = 0; q < D; ++q) Nc[q] /= nsum;
  if (A > 0.0 && !was) {  // a contact starts: depth beyond what the approach explains is allowed
    const double allowed = limit + 2.0 * kmath::sqrt(du2);
    if (g - g0 < -allowed) g0 = g + allowed;
  }
  if (A > pac(j) && was && g - g0 < 0.0) {  // the area grew: energy only from the budget
    const double ge = g - g0;
    const double Aok = pac(j) + 2.0 * budget / (L.kn * ge * ge);
    if (A > Aok) g0 = g - ge * kmath::sqrt(Aok / A);
  }
  if (!(A > 0.0) || !(g - g0 < 0.0)) {  // no contact (any more)
    contact_open<D, Fric>(L, pfn, pac, pg0, pfs, j, g, g0, was, du, sums);
    return;
  }
  pg0(j) = g0;
  const double Fn = -L.kn * A * (g - g0);
  double Fs[D];
  for (int k = 0; k < D; ++k) Fs[k] = 0.0;
  if constexpr (Fric) {
    // the last step's shear spring in this step's tangent plane, scaled to this step's area
    const double scale = was && A < pac(j) ? A / pac(j) : 1.0;
    double fs[D], dun = 0, fsn = 0, f2old = 0;
    for (int k = 0; k < D; ++k) {
      dun += du[k] * n[k];
      fs[k] = (was ? pfs(j, k) * scale : 0.0) + (seed.on() ? seed[k] : 0.0);
      f2old += was ? pfs(j, k) * pfs(j, k) : 0.0;
      fsn += fs[k] * n[k];
    }
    // the face of a frictional joint has the joint's friction (ContactSurface::fmu)
    const bool joint = S.fmu.extent(0) > 0 && S.fmu(fc) >= 0.0;
    const FrictionLaw fl{L.ks, joint ? S.fmu(fc) / L.srf : L.mu, L.coh};
    const ShearStep<D> sh = coulomb_shear<D>(fl, n, A, Fn, fs, fsn, du, dun);
    if (was || seed.on()) sums.dissipated += 0.5 * ((was ? f2old / pac(j) : 0.0) - sh.f2 / A) / L.ks;
    if (sh.slipped) sums.dissipated += sh.slip;
    for (int k = 0; k < D; ++k) Fs[k] = sh.Fs[k];
  }
  for (int k = 0; k < D; ++k) {
    const double Fk = Fn * n[k] + Fs[k];
    f(s, k) += Fk;
    for (int q = 0; q < D; ++q) f(fv[q], k) += -Nc[q] * Fk;
    if constexpr (Fric) pfs(j, k) = Fs[k];
  }
  pfn(j) = Fn;
  pac(j) = A;
  sums.active += 1.0;
}

}  // namespace fdem

namespace Kokkos {
template <>
struct reduction_identity<fdem::ContactSums> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::ContactSums sum() { return fdem::ContactSums(); }
};
}  // namespace Kokkos
