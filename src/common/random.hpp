#pragma once
// SplitMix64 (host only): the same numbers on every platform and standard library. The strength
// scatter hashes (seed, interface, draw) with it (src/solver/interface_materials.cpp); the grain
// generators draw from its stream (src/mesh/grains_common.cpp).
#include <cstdint>

namespace fdem {

inline std::uint64_t splitmix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A stream of uniform numbers in [0, 1) from a seed: splitmix64 of a counter.
class SplitMixStream {
 public:
  explicit SplitMixStream(std::uint64_t seed) : s_(seed * 0x2545f4914f6cdd1dULL + 0x632be59bd9b4e019ULL) {}
  double uniform() {
    const std::uint64_t z = splitmix64(s_);
    s_ += 0x9e3779b97f4a7c15ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t s_;
};

}  // namespace fdem
