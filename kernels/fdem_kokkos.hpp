#pragma once
// One source for Kokkos 3.4.1 (Debian) and current Kokkos (4.x/5.x), OpenMP and CUDA.
// What differs between the versions and what each bridge below does: docs/cuda.md, "Porting rules".
#include <Kokkos_Core.hpp>
#include <Kokkos_ScatterView.hpp>

#include <type_traits>

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

// Scatter of nodal forces; `access()` is taken once per chunk of kScatterChunk items, and
// `contribute_forces(f, sf)` adds what the pass left apart into f.
// - GPUs: Kokkos' ScatterView, atomics into f (no copy, nothing to contribute).
// - Host backends: a copy of f per thread, as Kokkos' duplicated ScatterView, except that the
//   first thread (token 0) adds into f itself: one copy fewer (none on one thread: 24 B per node
//   in 3D, and no reset or contribute pass). The sums are the same to the bit as the ScatterView's
//   wherever f holds zeros when the pass starts (the node update leaves them): ScatterView's
//   ((f + c0) + c1) + ... is then (c0 + c1) + ..., which is what f = c0 becomes here; what is put
//   into f between a pass and its contribute (the platens' forces) commutes with c0 alone, so it
//   goes in after the last pass into the scatter (Simulation::step). reset() zeroes the copies, not f.
constexpr int kScatterChunk = 256;

template <int D>
class HostForceScatter {
 public:
  using Token = Kokkos::Experimental::UniqueToken<ExecSpace, Kokkos::Experimental::UniqueTokenScope::Global>;

  // One thread's view of its sums: f itself (token 0) or its copy; a ScatterAccess's interface
  // (acc(node, k) += value).
  class Access {
   public:
    Access(const Token& token, double* f, double* copies, size_t stride) : token_(token), id_(token.acquire()) {
      base_ = id_ == 0 ? f : copies + (static_cast<size_t>(id_) - 1) * stride;
    }
    ~Access() {
      if (id_ >= 0) token_.release(id_);
    }
    Access(Access&& o) noexcept : token_(o.token_), id_(o.id_), base_(o.base_) { o.id_ = -1; }
    Access(const Access&) = delete;
    Access& operator=(const Access&) = delete;
    Access& operator=(Access&&) = delete;
    double& operator()(int i, int k) const { return base_[static_cast<size_t>(i) * D + k]; }

   private:
    const Token& token_;
    int id_;
    double* base_;
  };

  HostForceScatter() = default;
  explicit HostForceScatter(const Kokkos::View<double* [D]>& f) : f_(f), stride_(f.extent(0) * D) {
    const int extra = token_.size() - 1;
    if (extra > 0)
      copies_ = Kokkos::View<double*>(Kokkos::ViewAllocateWithoutInitializing("duplicated_" + f.label()),
                                      static_cast<size_t>(extra) * stride_);
    reset();
  }
  Access access() const { return Access(token_, f_.data(), copies_.data(), stride_); }
  // the copies held (threads - 1)
  int copies() const { return stride_ > 0 ? static_cast<int>(copies_.extent(0) / stride_) : 0; }
  // the copies to zero (f is left as it is); a kernel, not a deep_copy (which the profiling hooks
  // count as a copy: tests/test_gpu_ready.cpp)
  void reset() const {
    if (copies_.extent(0) == 0) return;
    const auto c = copies_;
    Kokkos::parallel_for(
        "fdem::scatter::reset", Kokkos::RangePolicy<ExecSpace>(0, c.extent(0)), KOKKOS_LAMBDA(const size_t i) { c(i) = 0.0; });
  }
  // f += the copies, in the threads' order (node by node: ((f + c1) + c2) + ...). f: the View the
  // scatter was made for.
  void contribute_into(const Kokkos::View<double* [D]>& f) const {
    const size_t n = copies_.extent(0);
    if (n == 0) return;
    if (f.data() != f_.data()) Kokkos::abort("HostForceScatter: contributed into another View");
    const double* c = copies_.data();
    const size_t stride = stride_;
    const int copies = static_cast<int>(n / stride);
    double* out = f.data();
    Kokkos::parallel_for(
        "fdem::scatter::contribute", Kokkos::RangePolicy<ExecSpace>(0, stride), KOKKOS_LAMBDA(const size_t i) {
          double v = out[i];
          for (int t = 0; t < copies; ++t) v += c[t * stride + i];
          out[i] = v;
        });
  }

 private:
  Kokkos::View<double* [D]> f_;
  Kokkos::View<double*> copies_;  // threads 1 ... T-1, stride_ values each
  size_t stride_ = 0;
  Token token_;
};

template <int D>
using DeviceForceScatter = Kokkos::Experimental::ScatterView<double* [D]>;
constexpr bool kHostScatter = std::is_same<ExecSpace, Kokkos::DefaultHostExecutionSpace>::value;
template <int D>
using ForceScatter = std::conditional_t<kHostScatter, HostForceScatter<D>, DeviceForceScatter<D>>;

template <int D>
void contribute_forces(const Kokkos::View<double* [D]>& f, const HostForceScatter<D>& sf) {
  sf.contribute_into(f);
}
template <int D>
void contribute_forces(const Kokkos::View<double* [D]>& f, DeviceForceScatter<D>& sf) {
  auto dst = f;
  Kokkos::Experimental::contribute(dst, sf);
}

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
