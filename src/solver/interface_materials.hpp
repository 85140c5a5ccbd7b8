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
// Whether the map has per-interface values (materials by place or a strength scatter) for a mesh
// with interfaces: what the snapshots' /mesh/interface_material shows.
bool interface_fields_wanted(const Case& c);

// The rules of fracture.region_materials and fracture.pair_materials that apply to no interface
// of the (whole) mesh: one warning each, naming the case file, the key and the regions. A warning,
// not an error: a generated mesh (grains) may leave a region out, and the run is still what the
// rest of the case says.
std::vector<std::string> unused_material_rules(const Case& c, const HostMesh& mesh);
// The same from the interfaces' counts per (region of side A, region of side B), row-major over
// `region_names` (a run whose mesh no process holds sums its parts' counts).
std::vector<std::string> unused_material_rules(const Case& c, const std::vector<std::string>& region_names,
                                               const std::vector<long>& between);
// Those counts over the mesh's first `ifaces` interfaces (a part's own); zeros for a mesh without its
// interfaces' elements.
std::vector<long> region_pair_counts(const HostMesh& mesh, long ifaces);

// The strength factor of interface q for a scatter (mean 1), a pure function of (seed, q) (q: the
// whole mesh's index of the interface, HostMesh::iface_ids on a part).
double strength_factor(const StrengthScatter& s, long q);

// A spatially correlated scatter (StrengthScatter::correlation_length l > 0): a standard normal
// random field g(x) with correlation exp(-r^2 / l^2), the sum of kModes cosines with random
// wave vectors (normal, variance 2 / l^2 per component) and phases, all from the seed; the factor
// at x is the scatter's distribution at the probability Phi(g(x)) (factor_from_gaussian), so the
// factors have the same distribution as the independent ones and the field's correlation.
class CorrelatedField {
 public:
  static constexpr int kModes = 256;
  CorrelatedField(const StrengthScatter& s, int dim);
  double gaussian(const double* x) const;  // g at the point x (dim coordinates)
 private:
  int dim_;
  std::vector<double> k_, phase_;
};
double factor_from_gaussian(const StrengthScatter& s, double g);

// For `fdem check` and summary.json: {"<material>": interfaces, ...} of the materials in use and,
// with a scatter, "strength_scatter": distribution, mean, min and max of the factors.
nlohmann::json interface_material_report(const Case& c, const InterfaceMaterialMap& map);

}  // namespace fdem
