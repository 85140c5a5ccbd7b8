#pragma once
// Pieces shared by the 2D and 3D grain generators (src/mesh/grains.cpp, grains3d.cpp).
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/random.hpp"
#include "mesh/mesh.hpp"

namespace fdem::grain_detail {

using Stream = SplitMixStream;  // src/common/random.hpp

// Seeds in the box [lo, hi] (dim components drawn per try) for which inside() holds, at least half
// a grain size d apart, as many as `measure` (area or volume) over a circle's (sphere's) of
// diameter d. Throws InputError naming `who` for a measure that is zero or not finite, for fewer
// than 2 or more than 20000 grains (giving the grain size that fits), or when dart throwing cannot
// place them.
std::vector<std::array<double, 3>> draw_seeds(
    int dim, const double lo[3], const double hi[3], double measure, double d, std::uint64_t seed,
    const std::string& who, const std::function<bool(const std::array<double, 3>&)>& inside);

// Minerals by area (volume) fraction: grains in a random order (from spec.seed), each to the
// mineral furthest below its share. No minerals in spec: one, named spec.region. Throws
// InputError naming `who` and the mineral's key when a mineral gets no grain.
void assign_minerals(const std::vector<double>& measure, const MeshSpec& spec, const std::string& who,
                     std::vector<int>& mineral, std::vector<std::string>& names,
                     std::vector<double>& mineral_measure);

}  // namespace fdem::grain_detail
