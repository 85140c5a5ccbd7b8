// The host's force scatter (kernels/fdem_kokkos.hpp, HostForceScatter): a copy per thread but the
// first, which adds into the forces themselves. It must give the same sums to the bit as Kokkos'
// duplicated ScatterView (a copy per thread, all added into the forces at the contribute) wherever
// the forces start at zero, also with forces put in between the pass and the contribute (the
// platens'), and hold one copy fewer than the threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#include "kernels/fdem_kokkos.hpp"

// The scatters' items (a named namespace: a device build, which compiles no host scatter, uses
// only some of them, and would warn of unused functions in an unnamed one).
namespace scatter_test {

constexpr int kNodes = 5000, kItems = 40000;

// Item j's node and value: a fixed pseudo-random sequence (values of mixed signs and magnitudes,
// so that the order of the sums shows in the last bits).
KOKKOS_INLINE_FUNCTION std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
KOKKOS_INLINE_FUNCTION int node_of(int j, int salt) { return static_cast<int>(mix(2 * j + salt) % kNodes); }
KOKKOS_INLINE_FUNCTION double value_of(int j, int k) {
  const std::uint64_t r = mix(7 * j + k + 1);
  return (static_cast<double>(r % 2000001) - 1e6) * (r % 3 == 0 ? 1e-9 : 1.3);
}

}  // namespace scatter_test

namespace {

using namespace fdem;
using scatter_test::kItems;
using scatter_test::kNodes;
using scatter_test::node_of;
using scatter_test::value_of;

// A pass as the force kernels make it: one access per chunk of 256 items, each item adding to two
// nodes (salt: which pass).
template <class Scatter>
void scatter_pass(const Scatter& sf, int salt) {
  Kokkos::parallel_for(
      "test::scatter_pass", Kokkos::RangePolicy<ExecSpace>(0, (kItems + 255) / 256), KOKKOS_LAMBDA(const int c) {
        auto acc = sf.access();
        for (int j = c * 256; j < (c + 1) * 256 && j < kItems; ++j)
          for (int k = 0; k < 3; ++k) {
            acc(node_of(j, salt), k) += value_of(j, k);
            acc(node_of(j, salt + 1), k) += -0.5 * value_of(j + 1, k);
          }
      });
}

// Platen-like forces on every tenth node, added into f directly.
void add_direct(const Kokkos::View<double* [3]>& f) {
  Kokkos::parallel_for(
      "test::direct", Kokkos::RangePolicy<ExecSpace>(0, kNodes / 10), KOKKOS_LAMBDA(const int b) {
        for (int k = 0; k < 3; ++k) f(10 * b, k) += value_of(kItems + b, k);
      });
}

bool same_bits(const Kokkos::View<double* [3]>& a, const Kokkos::View<double* [3]>& b, int& differing) {
  auto ha = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a);
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b);
  differing = 0;
  for (int i = 0; i < kNodes; ++i)
    for (int k = 0; k < 3; ++k) differing += std::memcmp(&ha(i, k), &hb(i, k), sizeof(double)) != 0;
  return differing == 0;
}

using KokkosDuplicated = Kokkos::Experimental::ScatterView<double* [3], Kokkos::LayoutRight, ExecSpace,
                                                           Kokkos::Experimental::ScatterSum,
                                                           Kokkos::Experimental::ScatterDuplicated,
                                                           Kokkos::Experimental::ScatterNonAtomic>;

// (templates on the backend's kind, so that a device build compiles no host scatter in a kernel)
template <bool Host>
void same_bits_as_kokkos() {
  if constexpr (Host) {
  // Kokkos: two passes into the copies, the direct forces into f between them and the contribute
  // (as Simulation::step on one process before: platens, then contact's pass, then the contribute)
  Kokkos::View<double* [3]> fa("fa", kNodes), fb("fb", kNodes);
  KokkosDuplicated ka(fa);
  ka.reset();
  scatter_pass(ka, 0);
  add_direct(fa);
  scatter_pass(ka, 2);
  Kokkos::Experimental::contribute(fa, ka);
  // the host scatter: both passes, then the direct forces, then the contribute (Simulation::step)
  HostForceScatter<3> hb(fb);
  hb.reset();
  scatter_pass(hb, 0);
  scatter_pass(hb, 2);
  add_direct(fb);
  contribute_forces<3>(fb, hb);
  int differing = -1;
  EXPECT_TRUE(same_bits(fa, fb, differing)) << differing << " of " << 3 * kNodes << " sums differ";

  // again from the same scatter after a reset (the next step): f zeroed by the node update
  Kokkos::deep_copy(fa, 0.0);
  Kokkos::deep_copy(fb, 0.0);
  ka.reset();
  hb.reset();
  scatter_pass(ka, 4);
  Kokkos::Experimental::contribute(fa, ka);
  scatter_pass(hb, 4);
  contribute_forces<3>(fb, hb);
  EXPECT_TRUE(same_bits(fa, fb, differing)) << differing << " sums differ after a reset";

  // the order matters (the check can fail): the direct forces put in before the passes, where
  // Kokkos' copies start from zero but f does not, change the last bits of some sums
  Kokkos::deep_copy(fb, 0.0);
  hb.reset();
  add_direct(fb);
  scatter_pass(hb, 0);
  scatter_pass(hb, 2);
  contribute_forces<3>(fb, hb);
  Kokkos::deep_copy(fa, 0.0);
  ka.reset();
  scatter_pass(ka, 0);
  add_direct(fa);
  scatter_pass(ka, 2);
  Kokkos::Experimental::contribute(fa, ka);
  EXPECT_FALSE(same_bits(fa, fb, differing));
  }
}

template <bool Host>
void one_copy_fewer() {
  if constexpr (Host) {
  Kokkos::View<double* [3]> f("f", kNodes);
  HostForceScatter<3> sf(f);
  const int threads = HostForceScatter<3>::Token().size();
  EXPECT_EQ(sf.copies(), threads - 1);
  // what the copies hold goes into f once, and a reset empties them (f left as it is)
  scatter_pass(sf, 0);
  contribute_forces<3>(f, sf);
  auto once = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), f);
  sf.reset();
  contribute_forces<3>(f, sf);
  int differing = -1;
  Kokkos::View<double* [3]> g("g", kNodes);
  Kokkos::deep_copy(g, once);
  EXPECT_TRUE(same_bits(f, g, differing)) << "a second contribute after a reset changed " << differing << " sums";
  double total = 0;
  for (int i = 0; i < kNodes; ++i) total += std::fabs(once(i, 0));
  EXPECT_GT(total, 0.0);
  }
}

TEST(HostForceScatter, SameBitsAsKokkosDuplicatedScatterView) {
  if (!kHostScatter) GTEST_SKIP() << "a device backend: Kokkos' atomic ScatterView";
  same_bits_as_kokkos<kHostScatter>();
}

TEST(HostForceScatter, OneCopyFewerThanThreads) {
  if (!kHostScatter) GTEST_SKIP() << "a device backend: no copies";
  one_copy_fewer<kHostScatter>();
}

}  // namespace
