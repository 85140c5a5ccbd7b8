#pragma once
// SIMD lanes for the host force pass (kernels/forces.hpp, FusedForceKernel): Lanes<W> holds one
// quantity of W bulk elements or interfaces side by side, and its arithmetic works lane by lane,
// so that the force pass's device functions (kernels/elastic.hpp, kernels/interface.hpp), written
// once for a scalar type T, run on W items at once when T is Lanes<W>. Each lane sees the same
// IEEE operations in the same order as the scalar code (no contraction into fused multiply-adds
// unless the whole build allows it), so a batch gives the scalar results to the bit.
//
// The lanes are pairs of doubles in GCC/Clang vector types (SSE2's 128-bit registers on x86-64,
// NEON's on ARM): +, -, *, / map to one packed instruction per pair, the square root to
// sqrtpd where SSE2 is there (a loop over the lanes elsewhere). Host backends only: a device
// compiler (CUDA, HIP) never sees the batched path (FDEM_HOST_LANES is 0 there).
#include "kernels/fdem_kokkos.hpp"

#if !defined(__CUDACC__) && !defined(__HIPCC__) && (defined(__GNUC__) || defined(__clang__))
#define FDEM_HOST_LANES 1
#else
#define FDEM_HOST_LANES 0
#endif

#if FDEM_HOST_LANES
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fdem {

template <int W>
struct Lanes {
  static_assert(W % 2 == 0 && W > 0, "Lanes<W>: W is a positive even number (pairs of doubles)");
  typedef double Pair __attribute__((vector_size(16)));
  static constexpr int kPairs = W / 2;
  Pair p[kPairs];

  Lanes() = default;
  Lanes(double a) {  // NOLINT: implicit, so that scalar constants mix with lanes as with doubles
    for (int k = 0; k < kPairs; ++k) p[k] = Pair{a, a};
  }
  double operator[](int w) const { return p[w / 2][w % 2]; }
  // The lanes f(0) .. f(W - 1) (f: the item's value from its place in the batch).
  template <class F>
  static Lanes gather(const F& f) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = Pair{f(2 * k), f(2 * k + 1)};
    return r;
  }

  friend Lanes operator+(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = a.p[k] + b.p[k];
    return r;
  }
  friend Lanes operator-(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = a.p[k] - b.p[k];
    return r;
  }
  friend Lanes operator*(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = a.p[k] * b.p[k];
    return r;
  }
  friend Lanes operator/(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = a.p[k] / b.p[k];
    return r;
  }
  friend Lanes operator-(const Lanes& a) {
    Lanes r;
    for (int k = 0; k < kPairs; ++k) r.p[k] = -a.p[k];
    return r;
  }
  Lanes& operator+=(const Lanes& b) { return *this = *this + b; }
  friend Lanes sqrt(const Lanes& a) {
    Lanes r;
#if defined(__SSE2__)
    for (int k = 0; k < kPairs; ++k) r.p[k] = _mm_sqrt_pd(a.p[k]);
#else
    for (int k = 0; k < kPairs; ++k) r.p[k] = Pair{std::sqrt(a.p[k][0]), std::sqrt(a.p[k][1])};
#endif
    return r;
  }
};

// The host force pass takes kLanes items at once: two pairs of doubles, so that two independent
// packed chains hide the latency of the divisions and square roots (8 lanes were no faster: the 3D
// force pass took 246 ns per element with 8 against 229 and 236 with 4, at 3e5 tetrahedra, one
// thread).
constexpr int kLanes = 4;
using HostLanes = Lanes<kLanes>;

// The square root of a scalar or of lanes, for code written once for both (kmath::sqrt takes
// doubles only).
KOKKOS_FORCEINLINE_FUNCTION double lane_sqrt(double a) { return kmath::sqrt(a); }
template <int W>
inline Lanes<W> lane_sqrt(const Lanes<W>& a) {
  return sqrt(a);
}

}  // namespace fdem

#else

namespace fdem {
KOKKOS_FORCEINLINE_FUNCTION double lane_sqrt(double a) { return kmath::sqrt(a); }
}  // namespace fdem

#endif
