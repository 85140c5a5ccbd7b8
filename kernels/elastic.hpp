#pragma once
// Bulk elements: constant-strain simplices (3-node triangles, 4-node tetrahedra), objective
// finite-rotation elasticity by the total-Lagrangian St Venant-Kirchhoff law (docs/theory.md
// section 3, where the choice is documented): F = dx/dX, E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E,
// nodal forces f_a = -V0 F S grad0(N_a). A rigid rotation gives E = 0 exactly, so no stress.
#include "kernels/fdem_kokkos.hpp"

namespace fdem {

// Deformation gradient of a simplex. x[a][i]: current coordinates of its D+1 nodes; G[b][j] =
// dN_{b+1}/dX_j (reference gradients of nodes 1..D; node 0's gradient is minus their sum).
template <int D, class T = double>
KOKKOS_INLINE_FUNCTION void deformation_gradient(const T (&x)[D + 1][D], const T (&G)[D][D], T (&F)[D][D]) {
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      T s = 0.0;
      for (int b = 0; b < D; ++b) s += (x[b + 1][i] - x[0][i]) * G[b][j];
      F[i][j] = s;
    }
}

// Second Piola-Kirchhoff stress S and strain energy density from F (SVK).
template <int D, class T = double>
KOKKOS_INLINE_FUNCTION T svk_stress(const T (&F)[D][D], const T& lambda, const T& mu, T (&S)[D][D]) {
  T E[D][D];
  T tr = 0.0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      T s = 0.0;
      for (int k = 0; k < D; ++k) s += F[k][i] * F[k][j];
      E[i][j] = 0.5 * (s - (i == j ? 1.0 : 0.0));
    }
  for (int i = 0; i < D; ++i) tr += E[i][i];
  T ee = 0.0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      S[i][j] = 2.0 * mu * E[i][j] + (i == j ? lambda * tr : T(0.0));
      ee += E[i][j] * E[i][j];
    }
  return 0.5 * lambda * tr * tr + mu * ee;
}

// Internal nodal forces (force acting on each node, i.e. minus the internal force vector) of one
// element; returns its strain energy V0 * W. T: double, or Lanes<W> (kernels/lanes.hpp) for W
// elements at once.
template <int D, class T = double>
KOKKOS_INLINE_FUNCTION T element_forces(const T (&x)[D + 1][D], const T (&G)[D][D], const T& vol0,
                                        const T& lambda, const T& mu, T (&f)[D + 1][D]) {
  T F[D][D], S[D][D], P[D][D];
  deformation_gradient<D, T>(x, G, F);
  const T w = svk_stress<D, T>(F, lambda, mu, S);
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      T s = 0.0;
      for (int k = 0; k < D; ++k) s += F[i][k] * S[k][j];
      P[i][j] = s;
    }
  for (int i = 0; i < D; ++i) f[0][i] = 0.0;
  for (int b = 0; b < D; ++b)
    for (int i = 0; i < D; ++i) {
      T s = 0.0;
      for (int j = 0; j < D; ++j) s += P[i][j] * G[b][j];
      f[b + 1][i] = -vol0 * s;
      f[0][i] += vol0 * s;
    }
  return vol0 * w;
}

// The same forces from the displacement gradient H = F - I (the mixed precision's bulk element,
// FusedForceKernel::mixed): E = (H + H^T + H^T H) / 2 and P = S + H S, so that a strain far below
// the rounding of F's unit diagonal keeps its relative precision in floats. T: float or
// Lanes<W, float>; H is formed in double by the caller.
template <int D, class T>
KOKKOS_INLINE_FUNCTION T element_forces_h(const T (&H)[D][D], const T (&G)[D][D], const T& vol0, const T& lambda,
                                          const T& mu, T (&f)[D + 1][D]) {
  T E[D][D], S[D][D];
  T tr = 0.0, ee = 0.0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      T s = H[i][j] + H[j][i];
      for (int k = 0; k < D; ++k) s += H[k][i] * H[k][j];
      E[i][j] = 0.5 * s;
    }
  for (int i = 0; i < D; ++i) tr += E[i][i];
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      S[i][j] = 2.0 * mu * E[i][j];
      ee += E[i][j] * E[i][j];
    }
  for (int i = 0; i < D; ++i) S[i][i] += lambda * tr;
  for (int i = 0; i < D; ++i) f[0][i] = 0.0;
  for (int i = 0; i < D; ++i) {
    T P[D];
    for (int j = 0; j < D; ++j) {
      T s = S[i][j];
      for (int k = 0; k < D; ++k) s += H[i][k] * S[k][j];
      P[j] = s;
    }
    for (int b = 0; b < D; ++b) {
      T s = 0.0;
      for (int j = 0; j < D; ++j) s += P[j] * G[b][j];
      f[b + 1][i] = -vol0 * s;
      f[0][i] += vol0 * s;
    }
  }
  return vol0 * (0.5 * lambda * tr * tr + mu * ee);
}

// Cauchy stress sigma = F S F^T / J as 6 components (xx, yy, zz, xy, yz, xz). In 2D, zz is the
// plane-strain out-of-plane stress lambda tr(E) (pushed forward), or 0 in plane stress.
template <int D>
KOKKOS_INLINE_FUNCTION void cauchy_stress(const double (&F)[D][D], double lambda, double mu,
                                          bool plane_stress, double (&s6)[6]) {
  double S[D][D];
  svk_stress<D>(F, lambda, mu, S);
  double J;
  if constexpr (D == 2) {
    J = F[0][0] * F[1][1] - F[0][1] * F[1][0];
  } else {
    J = F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) -
        F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
        F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
  }
  double sig[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      double s = 0;
      for (int k = 0; k < D; ++k)
        for (int l = 0; l < D; ++l) s += F[i][k] * S[k][l] * F[j][l];
      sig[i][j] = s / J;
    }
  if (D == 2 && !plane_stress) {
    double tr = 0;
    for (int i = 0; i < D; ++i) {
      double c = 0;
      for (int k = 0; k < D; ++k) c += F[k][i] * F[k][i];
      tr += 0.5 * (c - 1.0);
    }
    sig[2][2] = lambda * tr / J;
  }
  s6[0] = sig[0][0]; s6[1] = sig[1][1]; s6[2] = sig[2][2];
  s6[3] = sig[0][1]; s6[4] = sig[1][2]; s6[5] = sig[0][2];
}

}  // namespace fdem
