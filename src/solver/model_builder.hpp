#pragma once
// Building the device model of a run (kernels/model.hpp) from a case and its mesh, one step per
// module: materials, nodes, element geometry and masses, interfaces and their chunk index, the
// velocity-BC table, point loads and initial velocities (the platens build themselves:
// solver/platens.hpp). The Simulation constructor (model_builder.cpp) calls them in this order,
// then creates the contact system and decides the time step (solver/stable_step.hpp);
// solver/loads.cpp holds the steps from the velocity BCs on. Each step that finds a
// contribution to the stable step returns it.
#include <cmath>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "kernels/model.hpp"
#include "mesh/mesh.hpp"

namespace fdem {

// Per material (index into Case::materials) its density and P-wave speed; per mesh region its
// material index. build_materials also fills m.mat (Lame constants, plane-stress corrected).
struct MaterialTable {
  std::vector<double> rho, cp;
  std::vector<int> region_mat;
};
template <int D>
MaterialTable build_materials(const Case& c, const HostMesh& mesh, Model<D>& m);

// Reference and current positions (the mesh's), zero velocities and forces.
template <int D>
void build_nodes(const HostMesh& mesh, Model<D>& m);

// Element connectivity, reference gradients, volumes and materials; lumped nodal masses (`mass`:
// as summed, 0 for orphan nodes; m.mass: 1 for orphan nodes, which stay inert); the total volume
// and the bulk stable step (shortest altitude over P-wave speed) with its element.
struct ElementSetup {
  std::vector<double> mass;
  double volume = 0;
  double bulk_step = 0;
  int bulk_element = -1;
};
template <int D>
ElementSetup build_elements(const Case& c, const HostMesh& mesh, const MaterialTable& mats, Model<D>& m);

// Area of the triangle with edge vectors a and b.
inline double triangle_area(const double (&a)[3], const double (&b)[3]) {
  return 0.5 * std::sqrt(std::pow(a[1] * b[2] - a[2] * b[1], 2) + std::pow(a[2] * b[0] - a[0] * b[2], 2) +
                         std::pow(a[0] * b[1] - a[1] * b[0], 2));
}

// The cohesive parameters of an interface material.
CohesiveParams cohesive_params(const InterfaceMaterial& im);

// Interfaces: node pairs, reference tributary areas and cohesive parameters (the case's fracture
// material). Returns the interface springs' stable step (infinite without interfaces).
template <int D>
double build_interfaces(const Case& c, const HostMesh& mesh, const std::vector<double>& mass, Model<D>& m);

// Host backends: the chunk index of the fused force pass (Model::ichunk) when the interfaces are
// in order of their side-A element; else left empty.
template <int D>
void build_interface_chunks(const HostMesh& mesh, Model<D>& m);

// Velocity BCs: the BC table (one entry per BC, plus merged entries where sets overlap), per node
// its entry (-1: free), per BC its name and its node list (reactions).
struct VelocityBCTable {
  std::vector<BCDev> table;
  std::vector<int> node_bc;
  std::vector<std::string> names;
  std::vector<Kokkos::View<int*>> nodes;
};
template <int D>
VelocityBCTable build_velocity_bcs(const Case& c, const HostMesh& mesh, Model<D>& m);

// Point loads: the total force of each load shared by its set's nodes; the constant loads in
// m.fext (extent 0 without), the ramped ones in m.fext_ramp, one group per distinct ramp time
// (extent 0 without). Returns the groups' ramp times (empty without ramped loads).
template <int D>
std::vector<double> build_point_loads(const Case& c, const HostMesh& mesh, Model<D>& m);

// Initial velocities of regions, then the velocity BCs' values at the start (0 for a ramp).
template <int D>
void set_initial_velocities(const Case& c, const HostMesh& mesh, const VelocityBCTable& bcs, Model<D>& m);

}  // namespace fdem
