#pragma once
// Boundary conditions and loads, the host side in one place (docs/developing.md, "The module
// shape"): the velocity BCs (their table, each one's node list and reaction), gravity, point
// loads (constant and ramped) and initial velocities. Their device side is fused into the node
// update (kernels/nodes.hpp: the BC mask, the loads and their works), so this module builds the
// update's data and parameters and reports what the run writes: the reactions and their history
// columns. Their works are terms of the energy ledger (Simulation::book_energies, solver/ledger.hpp).
#include <array>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "kernels/nodes.hpp"
#include "mesh/mesh.hpp"
#include "parallel/parts.hpp"

namespace fdem {

template <int D>
class Loads {
 public:
  // The BC table and its node lists, the point loads, gravity, and the initial velocities (regions,
  // then the BCs' values at the start) into m; gravity and the loads' groups into prm.
  void build(const Case& c, const HostMesh& mesh, Model<D>& m, NodeUpdateParams& prm);

  // Reaction of each velocity BC (sum over its node set of minus the internal force, over the
  // processes), from the forces of the present step (before the node update clears them).
  void sample_reactions(const Model<D>& m, const Parts<D>& parts);
  const std::vector<std::array<double, 3>>& reactions() const { return reactions_; }
  const std::vector<std::string>& names() const { return names_; }

  // history.csv: per velocity BC its reaction's components; and a row's values.
  void add_columns(std::vector<std::string>& cols) const;
  void append_row(std::vector<double>& row) const;

 private:
  std::vector<std::string> names_;
  std::vector<Kokkos::View<int*>> nodes_;
  std::vector<std::array<double, 3>> reactions_;
};

extern template class Loads<2>;
extern template class Loads<3>;

}  // namespace fdem
