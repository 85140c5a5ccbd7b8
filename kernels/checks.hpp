#pragma once
// Checks of the state (docs/theory.md section 8), run on check steps only: the first node whose
// position or velocity is not finite, and the elements turned inside out.
#include "kernels/model.hpp"

namespace fdem {

// The smallest index of a node whose position or velocity is not finite; m.nn if there is none.
template <int D>
int first_nonfinite_node(const Model<D>& m) {
  auto x = m.x;
  auto v = m.v;
  int bad = m.nn;
  Kokkos::parallel_reduce(
      "fdem::check_finite", Kokkos::RangePolicy<ExecSpace>(0, m.nn),
      KOKKOS_LAMBDA(const int i, int& first) {
        bool ok = true;
        for (int k = 0; k < D; ++k) {  // x - x is 0 for finite x, NaN for NaN and inf
          const double dx = x(i, k) - x(i, k), dv = v(i, k) - v(i, k);
          ok = ok && dx == 0.0 && dv == 0.0;
        }
        if (!ok && i < first) first = i;
      },
      Kokkos::Min<int>(bad));
  return bad;
}

// Signed measure (2D: twice the area, 3D: six times the volume) of the simplex with edge vectors a.
template <int D>
KOKKOS_INLINE_FUNCTION double simplex_orientation(const double (&a)[D][D]) {
  if constexpr (D == 2) {
    return a[0][0] * a[1][1] - a[0][1] * a[1][0];
  } else {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  }
}

// True when element e's orientation now differs from its reference one (or either is degenerate).
template <int D>
struct ElementInverted {
  Kokkos::View<double* [D]> x, X;
  Kokkos::View<int* [D + 1]> elem;
  KOKKOS_INLINE_FUNCTION bool operator()(const int e) const {
    double a[D][D], b[D][D];
    for (int q = 0; q < D; ++q)
      for (int k = 0; k < D; ++k) {
        a[q][k] = x(elem(e, q + 1), k) - x(elem(e, 0), k);
        b[q][k] = X(elem(e, q + 1), k) - X(elem(e, 0), k);
      }
    return !(simplex_orientation<D>(a) * simplex_orientation<D>(b) > 0.0);
  }
};

struct InvertedElements {
  int count = 0;  // elements turned inside out
  int first = 0;  // the smallest index among them (m.ne when there is none)
};

template <int D>
InvertedElements inverted_elements(const Model<D>& m) {
  const ElementInverted<D> inverted{m.x, m.X, m.elem};
  const int ne = m.owned_elems();
  int count = 0, first = ne;
  Kokkos::parallel_reduce(
      "fdem::check_inverted", Kokkos::RangePolicy<ExecSpace>(0, ne),
      KOKKOS_LAMBDA(const int e, int& n) { n += inverted(e) ? 1 : 0; }, count);
  if (count > 0)
    Kokkos::parallel_reduce(
        "fdem::check_inverted_first", Kokkos::RangePolicy<ExecSpace>(0, ne),
        KOKKOS_LAMBDA(const int e, int& f) {
          if (inverted(e) && e < f) f = e;
        },
        Kokkos::Min<int>(first));
  return InvertedElements{count, first};
}

}  // namespace fdem
