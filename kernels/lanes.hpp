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
// sqrtpd where SSE2 is there (a loop over the lanes elsewhere). Lanes<W, float> holds quadruples
// of floats instead: the case key precision = "mixed" (FusedForceKernel::mixed,
// kernels/forces.hpp). Host backends only: a device compiler (CUDA, HIP) never sees the batched
// path (FDEM_HOST_LANES is 0 there).
#include "kernels/fdem_kokkos.hpp"

#if !defined(__CUDACC__) && !defined(__HIPCC__) && (defined(__GNUC__) || defined(__clang__))
#define FDEM_HOST_LANES 1
#else
#define FDEM_HOST_LANES 0
#endif

#if FDEM_HOST_LANES
#include <cmath>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fdem {

template <int W, class S = double>
struct Lanes {
  // one 16-byte vector holds kPer lanes: pairs of doubles, or quadruples of floats (the mixed
  // precision's lanes, FusedForceKernel::mixed)
  static constexpr int kPer = 16 / static_cast<int>(sizeof(S));
  static_assert(W % kPer == 0 && W > 0, "Lanes<W, S>: W is a positive multiple of the lanes of one 16-byte vector");
  typedef S Vec __attribute__((vector_size(16)));
  static constexpr int kVecs = W / kPer;
  static constexpr int kWidth = W;
  using Scalar = S;
  Vec p[kVecs];

  Lanes() = default;
  Lanes(S a) {  // NOLINT: implicit, so that scalar constants mix with lanes as with doubles
    for (int k = 0; k < kVecs; ++k) p[k] = Vec{} + a;
  }
  S operator[](int w) const { return p[w / kPer][w % kPer]; }
  // The lanes f(0) .. f(W - 1) (f: the item's value from its place in the batch, converted to S).
  template <class F>
  static Lanes gather(const F& f) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k)
      for (int j = 0; j < kPer; ++j) r.p[k][j] = static_cast<S>(f(kPer * k + j));
    return r;
  }

  friend Lanes operator+(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k) r.p[k] = a.p[k] + b.p[k];
    return r;
  }
  friend Lanes operator-(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k) r.p[k] = a.p[k] - b.p[k];
    return r;
  }
  friend Lanes operator*(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k) r.p[k] = a.p[k] * b.p[k];
    return r;
  }
  friend Lanes operator/(const Lanes& a, const Lanes& b) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k) r.p[k] = a.p[k] / b.p[k];
    return r;
  }
  friend Lanes operator-(const Lanes& a) {
    Lanes r;
    for (int k = 0; k < kVecs; ++k) r.p[k] = -a.p[k];
    return r;
  }
  Lanes& operator+=(const Lanes& b) { return *this = *this + b; }
  friend Lanes sqrt(const Lanes& a) {
    Lanes r;
#if defined(__SSE2__)
    if constexpr (sizeof(S) == 8)
      for (int k = 0; k < kVecs; ++k) r.p[k] = _mm_sqrt_pd(a.p[k]);
    else
      for (int k = 0; k < kVecs; ++k) r.p[k] = _mm_sqrt_ps(a.p[k]);
#else
    for (int k = 0; k < kVecs; ++k)
      for (int j = 0; j < kPer; ++j) r.p[k][j] = std::sqrt(a.p[k][j]);
#endif
    return r;
  }
};

// Lanes of doubles rounded to floats, lane by lane (the mixed precision's way in).
template <int W>
inline Lanes<W, float> to_float(const Lanes<W, double>& a) {
  Lanes<W, float> r;
#if defined(__SSE2__)
  for (int k = 0; k < Lanes<W, float>::kVecs; ++k)  // two pairs of doubles into one vector of floats
    r.p[k] = _mm_movelh_ps(_mm_cvtpd_ps(a.p[2 * k]), _mm_cvtpd_ps(a.p[2 * k + 1]));
#else
  for (int w = 0; w < W; ++w) r.p[w / 4][w % 4] = static_cast<float>(a[w]);
#endif
  return r;
}

// Lanes of doubles as the lanes M a batch computes in: the same lanes (M of doubles), or rounded to
// floats lane by lane (M of floats: to_float).
template <class M, int W>
inline M lanes_as(const Lanes<W, double>& a) {
  if constexpr (std::is_same_v<M, Lanes<W, double>>)
    return a;
  else
    return to_float(a);
}

// The host force pass takes kLanes items at once: two pairs of doubles, so that two independent
// packed chains hide the latency of the divisions and square roots (8 lanes were no faster: the 3D
// force pass took 246 ns per element with 8 against 229 and 236 with 4, at 3e5 tetrahedra, one
// thread).
constexpr int kLanes = 4;
using HostLanes = Lanes<kLanes>;
// The mixed precision's batches (FusedForceKernel::mixed) take kMixedLanes items in floats: two
// vectors of four, so that, as with the doubles, two independent packed chains hide the latency of
// the divisions and square roots.
constexpr int kMixedLanes = 8;
using MixedLanes = Lanes<kMixedLanes, float>;

// The square root of a scalar or of lanes, for code written once for both (kmath::sqrt takes
// doubles only).
KOKKOS_FORCEINLINE_FUNCTION double lane_sqrt(double a) { return kmath::sqrt(a); }
KOKKOS_FORCEINLINE_FUNCTION float lane_sqrt(float a) { return kmath::sqrt(a); }
template <int W, class S>
inline Lanes<W, S> lane_sqrt(const Lanes<W, S>& a) {
  return sqrt(a);
}

}  // namespace fdem

#else

namespace fdem {
KOKKOS_FORCEINLINE_FUNCTION double lane_sqrt(double a) { return kmath::sqrt(a); }
}  // namespace fdem

#endif
