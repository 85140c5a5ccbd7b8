// GoogleTest entry point: Kokkos lives for the whole test binary.
#include <sched.h>

#include <Kokkos_Core.hpp>
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  Kokkos::ScopeGuard guard(argc, argv);
  // With OMP_PROC_BIND set (the test preset: spread) OpenMP pins this main thread to one core when
  // the program loads, and every fdem process a test starts (std::system from this thread)
  // inherits that one core: its two threads then share it. Unpin the main thread (every core the
  // system allows: the kernel keeps the allowed ones of the full set) so that they may use them all.
  cpu_set_t all;
  CPU_ZERO(&all);
  for (int c = 0; c < CPU_SETSIZE; ++c) CPU_SET(c, &all);
  sched_setaffinity(0, sizeof(all), &all);  // on failure the tests run as before, only slower
  return RUN_ALL_TESTS();
}
