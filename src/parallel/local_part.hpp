#pragma once
// A part built from the coarse mesh alone (issue 49, docs/parallel.md "Scale"): the process of
// part p refines its own coarse elements and a halo of coarse elements around them, inserts the
// interfaces of that neighbourhood, and cuts its part out of it with the same Decomposer that cuts
// the whole mesh (decompose.hpp). Every fine node, element and interface has a global id that
// follows from the coarse mesh (mesh/refine.hpp: refine_elements, refined_interface_offsets), so
// the part is the one decompose() cuts from the whole refined mesh, item for item and bit for bit,
// without any process holding the whole fine mesh. What the part cannot see (the whole mesh's
// counts, its pieces, its smallest element, its node sets' sizes) comes in as WholeFacts, which a
// run over processes computes from the coarse mesh or sums over the processes.
//
// Scope: the neighbourhood gets interfaces with every region fracturable and no face set cut (the
// whole mesh's nodes are then the copies e (dim + 1) + a of its elements' corners), so it is the
// part of a case whose fracturable regions are all of them and which cuts no face set.
//
// The halo: the coarse elements whose bounding box (widened by how far the refinement may move a
// new node out onto a curved boundary) comes within the contact reach of an own coarse element's,
// and rings of coarse elements sharing a vertex with those, until every item the part holds lies
// where the neighbourhood is complete (its coarse element has all its coarse neighbours there, so
// its faces, interfaces and outer faces are those of the whole mesh). The send lists of the
// exchange come from the other parts' requests (ghost_requests, lists_from_requests), one exchange
// of global node ids.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"
#include "mesh/refine.hpp"
#include "parallel/decompose.hpp"

namespace fdem {

// What a part takes from the whole refined mesh (after insertion) that its neighbourhood cannot
// tell: the counts, the connected pieces and the smallest element size (contact), the node sets'
// sizes and the mesh checks' warnings and body count.
struct WholeFacts {
  long nodes = 0, elems = 0, ifaces = 0;
  int pieces = -1;
  double min_size = 0;
  std::map<std::string, long> set_sizes;
  std::vector<std::string> warnings;
  int bodies = 0;
};

// The coarse elements part p's process refines (ascending): its own, those within `reach` (boxes
// widened as above) of an own one, and `rings` rings of vertex neighbours around those.
std::vector<int> halo_coarse_elements(const HostMesh& coarse, const CoarseTopology& topo,
                                      const std::vector<int>& coarse_part, int p, double reach, int rings);

// What a run does to a neighbourhood, as prepare_mesh (src/solver/run.hpp) does to the whole mesh:
// after the refinement (the rotation of mesh.rotation about the whole mesh's centre) and after the
// insertion (the node sets of regions). Each must give every node it touches the bits the whole
// mesh's would get.
// widen: how much farther than the contact reach the halo must look (a rotation: the contact
// zones are taken at the rotated elements' boxes, the halo at the coarse elements' unrotated ones).
struct LocalHooks {
  std::function<void(HostMesh&)> refined, inserted;
  double widen = 0;
};

// The refinement of some coarse elements (ascending) with its interfaces inserted, in the whole
// refined mesh's order (elements by global id; interfaces by side A, then face), and the global id
// of each node, element and interface: -1 for an interface whose number the neighbourhood cannot
// give (at its edge: the whole mesh numbers it among interfaces this one does not hold).
struct LocalRefinement {
  HostMesh mesh;
  std::vector<std::int64_t> node_gid, elem_gid, iface_gid;
  std::vector<char> closed;  // per coarse element of the whole coarse mesh: it and every facet neighbour held
};
LocalRefinement refine_and_insert(const HostMesh& coarse, const CoarseTopology& topo,
                                  const std::vector<std::int64_t>& iface_offsets, const std::vector<int>& coarse_elems,
                                  const LocalHooks& hooks = {});

// Part p of the whole refined mesh (refine_mesh then insert_interfaces) for the coarse elements'
// part ids `coarse_part`, as decompose() would cut it with each fine element in its coarse
// element's part (the receive lists only: add the send lists with lists_from_requests and
// complete_lists). iface_offsets: refined_interface_offsets(coarse, topo).
// stats (optional): the size of the neighbourhood it refined and the rings that took.
struct LocalPartStats {
  long coarse_elems = 0, fine_elems = 0;
  int rings = 0;
  // wall seconds of the phases (over every ring tried): the halo, the refinement with its
  // interfaces, the cut of the part
  double halo_seconds = 0, refine_seconds = 0, cut_seconds = 0;
};
SubMesh local_part(const HostMesh& coarse, const CoarseTopology& topo, const std::vector<std::int64_t>& iface_offsets,
                   const std::vector<int>& coarse_part, int parts, int p, double contact_reach, const WholeFacts& facts,
                   LocalPartStats* stats = nullptr, const LocalHooks& hooks = {});

// The global ids of the ghost nodes part s receives from each of its neighbours (s.neighbours
// order): what it asks of each owner.
std::vector<std::vector<std::int64_t>> ghost_requests(const SubMesh& s);
// Part s's exchange lists from the requests of the parts that receive from it (`from`, ascending,
// each with the global ids it asks for, in its receive order): the send lists decompose() gives.
// InputError when a request names a node that is not one of s's own.
PartLists lists_from_requests(const SubMesh& s, const std::vector<int>& from,
                              const std::vector<std::vector<std::int64_t>>& requested);

}  // namespace fdem
