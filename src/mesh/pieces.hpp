#pragma once
// The connected pieces of a mesh (host only): the contact's body count (solver/contact_topology.hpp,
// ContactSystem) and the whole mesh's piece count that decompose gives each part
// (parallel/decompose.hpp, HostMesh::pieces).
#include "mesh/mesh.hpp"

namespace fdem {

// Connected pieces of the mesh: elements joined by shared nodes or by interfaces.
int count_bodies(const HostMesh& mesh);

}  // namespace fdem
