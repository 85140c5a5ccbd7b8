#pragma once
// One source for Kokkos 3.4.1 (Debian) and current Kokkos (4.x/5.x), OpenMP and CUDA.
// What differs between the versions and what each bridge below does: docs/cuda.md, "Porting rules".
#include <Kokkos_Core.hpp>
#include <Kokkos_ScatterView.hpp>

namespace fdem {

#if KOKKOS_VERSION >= 30700
namespace kmath = Kokkos;
#else
namespace kmath = Kokkos::Experimental;
#endif

using ExecSpace = Kokkos::DefaultExecutionSpace;
using MemSpace = ExecSpace::memory_space;

template <class T>
KOKKOS_INLINE_FUNCTION T kmin(T a, T b) { return a < b ? a : b; }
template <class T>
KOKKOS_INLINE_FUNCTION T kmax(T a, T b) { return a > b ? a : b; }
template <class T>
KOKKOS_INLINE_FUNCTION T kclamp(T x, T lo, T hi) { return x < lo ? lo : (x > hi ? hi : x); }

// Whether v is +0.0 to the bit (not -0.0, not anything else): a test that some state is exactly
// what a write of 0.0 would leave, so that a pass may skip the write and keep the same bits.
KOKKOS_INLINE_FUNCTION bool plus_zero(double v) {
#if defined(__CUDA_ARCH__) || defined(__HIP_DEVICE_COMPILE__)
  return __double_as_longlong(v) == 0;
#else
  unsigned long long u;
  __builtin_memcpy(&u, &v, sizeof v);
  return u == 0ull;
#endif
}

// c ? a : b, to the bit, without a branch on host CPUs: where c follows a sign that changes at
// random from one item to the next (the openings of intact interfaces), the compiler's branch is
// mispredicted half the time, and a miss costs more than the arithmetic. GPUs select anyway.
KOKKOS_INLINE_FUNCTION double kselect(bool c, double a, double b) {
#if defined(__CUDA_ARCH__) || defined(__HIP_DEVICE_COMPILE__)
  return c ? a : b;
#else
  unsigned long long ua, ub;
  __builtin_memcpy(&ua, &a, sizeof a);
  __builtin_memcpy(&ub, &b, sizeof b);
  const unsigned long long m = 0ull - static_cast<unsigned long long>(c);
  const unsigned long long r = (ua & m) | (ub & ~m);
  double out;
  __builtin_memcpy(&out, &r, sizeof out);
  return out;
#endif
}

// A fixed number of sums reduced together (energies, counts). Works as a parallel_reduce result
// type in Kokkos 3.4.1 (volatile join) and 4.x (plain join).
template <int N>
struct SumN {
  double v[N];
  KOKKOS_INLINE_FUNCTION SumN() {
    for (int i = 0; i < N; ++i) v[i] = 0.0;
  }
  KOKKOS_INLINE_FUNCTION SumN& operator+=(const SumN& o) {
    for (int i = 0; i < N; ++i) v[i] += o.v[i];
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile SumN& o) volatile {
    for (int i = 0; i < N; ++i) v[i] += o.v[i];
  }
#endif
};

// The labels of reductions and scans whose result stays in device memory (a View) end in this
// mark; a reduction into a host value makes the host wait for the device (tests/test_gpu_ready.cpp
// tells the two apart by it).
inline constexpr char kDeviceResult[] = " [device]";

// Every fence the code asks for (host code in src/) goes through here: counted, because Kokkos
// 3.4.1 reports no fence of a host backend to its profiling hooks (tests/test_gpu_ready.cpp counts
// them per step, and checks that src/ and kernels/ call Kokkos::fence nowhere else), and named
// where Kokkos takes a name.
inline long& fence_count() {
  static long n = 0;
  return n;
}
inline void fence(const char* why) {
  ++fence_count();
#if KOKKOS_VERSION >= 30600
  Kokkos::fence(why);
#else
  (void)why;
  Kokkos::fence();
#endif
}

// Scatter of nodal forces: ScatterView duplicates per thread on host backends and uses atomics
// on GPUs (Kokkos' per-backend defaults); `access()` is taken once per chunk of kScatterChunk items.
constexpr int kScatterChunk = 256;
template <int D>
using ForceScatter = Kokkos::Experimental::ScatterView<double* [D]>;

// Launch bounds of the heaviest kernels on CUDA (the interface forces, the narrow phase): at most
// 128 threads per block and at least 4 (FDEM_CUDA_OCCUPANCY 25, the build's default) or 8 (50)
// resident blocks per multiprocessor, so that the compiler keeps each thread within 128 or 64 of
// the multiprocessor's 65536 registers (25 or 50 % theoretical occupancy; docs/cuda.md, "Kernel
// resources"). Host backends ignore them.
#ifndef FDEM_CUDA_OCCUPANCY
#define FDEM_CUDA_OCCUPANCY 25
#endif
using HeavyLaunchBounds = Kokkos::LaunchBounds<128, (FDEM_CUDA_OCCUPANCY >= 50 ? 8 : 4)>;
using ForceLaunchBounds = HeavyLaunchBounds;

// A device function kept out of line: a rare branch of a heavy kernel, so that on CUDA the
// registers it needs do not add to those of the common path (docs/cuda.md, "Kernel resources").
#if defined(__CUDACC__) || defined(__HIPCC__)
#define FDEM_NOINLINE __noinline__
#else
#define FDEM_NOINLINE __attribute__((noinline))
#endif

}  // namespace fdem

namespace Kokkos {
template <int N>
struct reduction_identity<fdem::SumN<N>> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::SumN<N> sum() { return fdem::SumN<N>(); }
};
}  // namespace Kokkos
