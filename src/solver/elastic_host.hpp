#pragma once
// Host helpers of the linear elastic simplex shared by the model build (model_builder.cpp) and
// the homogenisation (homogenise.cpp): determinant and inverse of the edge matrix, Lame constants.

namespace fdem {

template <int D>
double det(const double (&A)[D][D]) {
  if constexpr (D == 2) {
    return A[0][0] * A[1][1] - A[0][1] * A[1][0];
  } else {
    return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
           A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
           A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  }
}

template <int D>
void inverse(const double (&A)[D][D], double (&B)[D][D]) {
  const double d = det<D>(A);
  if constexpr (D == 2) {
    B[0][0] = A[1][1] / d;
    B[0][1] = -A[0][1] / d;
    B[1][0] = -A[1][0] / d;
    B[1][1] = A[0][0] / d;
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
        B[i][j] = (A[i1][j1] * A[i2][j2] - A[i1][j2] * A[i2][j1]) / d;
      }
  }
}

// Lame constants of E, nu; plane stress through the reduced lambda 2 lambda mu / (lambda + 2 mu).
struct Lame {
  double lambda, mu;
};
inline Lame lame(double E, double nu, bool plane_stress) {
  double lam = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = E / (2 * (1 + nu));
  if (plane_stress) lam = 2 * lam * mu / (lam + 2 * mu);
  return {lam, mu};
}

}  // namespace fdem
