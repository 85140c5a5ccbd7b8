#pragma once
// Host topology of the contact surfaces, from the mesh (docs/theory.md section 6b), computed once
// by the ContactSystem constructor (solver/contact_system.cpp): the faces that can become
// surfaces, with their nodes, owner elements and interfaces; each face's share of its nodes'
// areas; the vertex groups of the copies of one mesh vertex (the number of bodies: mesh/pieces.hpp).
#include <vector>

#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "mesh/pieces.hpp"  // count_bodies

namespace fdem {

// Faces: the outer boundary (nb of them), then both faces of each interface: nodes (D per face;
// the interface's side A in its stored order, side B reversed: both normals point out of their
// element), owner element (the interface of face f: face_interface(f, nb), kernels/contact/geometry.hpp).
struct ContactFaces {
  int nb = 0, nf = 0;
  std::vector<int> fnode, fowner;
};

// The faces around each node (CSR: nface(nfoff(i)) .. nface(nfoff(i + 1) - 1)), and each node's
// share of every face it can ever be part of (a face's share of its nodes' areas: face_share_of,
// kernels/contact/geometry.hpp, as the run's surface areas take it).
struct FaceShares {
  std::vector<int> nfoff, nface;
  std::vector<double> area;
};

// Vertex groups (copies of one mesh vertex joined through interface node pairs): each node's
// group id (vgrp), and the groups that have interface pairs (CSR, see VertexGroups in
// kernels/contact/surfaces.hpp).
struct HostVertexGroups {
  std::vector<int> vgrp, off, ent, copy_off, copy;
  int n = 0;
};

// The 'enabled' rule of the case's contact object: on/off as given; "auto" (default): on when the
// mesh has interfaces or more than one body (connected piece of elements).
bool contact_wanted(const Case& c, const HostMesh& mesh);

// The faces (InputError, naming c.file, when a face has no element).
template <int D>
ContactFaces contact_faces(const Case& c, const HostMesh& mesh);

template <int D>
FaceShares face_shares(const HostMesh& mesh, const ContactFaces& F, double thick);

template <int D>
HostVertexGroups vertex_groups(const HostMesh& mesh);

}  // namespace fdem
