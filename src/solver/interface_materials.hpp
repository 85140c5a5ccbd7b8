#pragma once
// Interface materials by place and random strength (docs/case-format.md, "fracture"): which
// interface material each interface takes, and its strength factor.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "mesh/mesh.hpp"

namespace fdem {

struct InterfaceMaterialMap {
  // Per interface: index into Case::interface_materials. Empty when every interface takes
  // Case::fracture_material and there is no scatter (the one-material run).
  std::vector<int> material;
  // Per interface: strength factor (mean 1) with a scatter, else empty.
  std::vector<float> scale;
  // Interfaces per material (Case::interface_materials order), also for the one-material run.
  std::vector<long> count;
};

// The map for the mesh's interfaces (side A and side B elements, their regions). Deterministic:
// the factors depend on the seed and the interface's index only (same on every backend and
// thread count).
InterfaceMaterialMap interface_material_map(const Case& c, const HostMesh& mesh);

// The strength factor of interface q for a scatter (mean 1), a pure function of (seed, q).
double strength_factor(const StrengthScatter& s, long q);

// For `fdem check` and summary.json: {"<material>": interfaces, ...} of the materials in use and,
// with a scatter, "strength_scatter": distribution, mean, min and max of the factors.
nlohmann::json interface_material_report(const Case& c, const InterfaceMaterialMap& map);

}  // namespace fdem
