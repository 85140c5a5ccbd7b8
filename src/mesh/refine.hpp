#pragma once
// Uniform refinement of a simplex mesh (case key mesh.refine, docs/case-format.md): each triangle
// into 4 and each tetrahedron into 8 (red refinement: the corners and, in 3D, the inner octahedron
// cut along its shortest diagonal), k times. The new nodes are the lattice points i/m (m = 2^k) of
// the coarse elements' barycentric coordinates, so each has a global id from the coarse entity it
// lies on (vertex, edge, face, interior) and its place there, and a global element id is the coarse
// element's id times 8^k (4^k) plus its place in the recursion: a process can refine its own coarse
// elements and get the same ids, coordinates and elements as the whole refinement restricted to
// them (RefinedPart), without ever holding the whole fine mesh.
//
// The new nodes on a curved outer boundary (a disc's circle, a sphere: CurvedSurface) are moved
// onto it radially; elsewhere they stay where the coarse element puts them (linear: exact for
// planes, a faceted approximation of a curved surface the case does not describe).
#include <array>
#include <cstdint>
#include <vector>

#include "mesh/mesh.hpp"

namespace fdem {

// A circle (2D) or sphere (3D) the coarse mesh's outer boundary approximates.
struct CurvedSurface {
  std::array<double, 3> centre{0, 0, 0};
  double radius = 0;
};

// The curved surfaces of a generated mesh (disc, sphere, grains in a disc); none for the others.
std::vector<CurvedSurface> curved_surfaces(const MeshSpec& spec, int dim);

// Fine elements per coarse element after `levels` refinements: 4^levels (2D), 8^levels (3D).
double refine_factor(int dim, int levels);

// The numbering of the coarse mesh's edges and faces, which every process computes alike from the
// coarse mesh (small: the fine mesh is 8^k times larger).
struct CoarseTopology {
  int dim = 0, levels = 0, m = 1;  // m = 2^levels
  int num_vertices = 0;
  std::vector<std::array<int, 2>> edges;  // sorted pairs of coarse node ids, in sorted order
  std::vector<std::array<int, 3>> faces;  // 3D: sorted triples, in sorted order
  std::vector<int> elem_edges;            // per element 3 (2D) or 6 (3D) edge indices
  std::vector<int> elem_faces;            // 3D: per element 4 face indices (face f opposite vertex f)
  // Per element dim + 1: the coarse element across each of its facets (elem_edges' order in 2D,
  // elem_faces' in 3D), -1 on the boundary.
  std::vector<int> elem_neighbours;
  std::vector<CurvedSurface> surfaces;
  // Per edge / face: the curved surface its new nodes are moved onto (-1: none).
  std::vector<int> edge_surface, face_surface;
  // Per node set (in HostMesh::node_sets order, "all" excluded): the edges and faces whose new
  // nodes join it (sorted indices).
  std::vector<std::vector<int>> set_edges, set_faces;
  std::int64_t num_fine_nodes = 0;  // of the whole refinement
  // Global id of the first new node on edges, faces and element interiors.
  std::int64_t edge_base = 0, face_base = 0, interior_base = 0;
};

// Throws InputError when levels is out of [0, 10] or the mesh has no element.
CoarseTopology coarse_topology(const HostMesh& coarse, int levels,
                               const std::vector<CurvedSurface>& surfaces);

// The refinement of some coarse elements: a HostMesh of their fine elements (in the order of
// `coarse_elems`, each one's children together) and the nodes they use, with every node's and
// element's global id, node sets (the coarse sets' nodes and the new nodes on their edges and
// faces, see coarse_topology) and face sets (the facets of the coarse face sets that lie on a
// refined element, each cut into 2^k (2D) or 4^k (3D) facets of the same orientation).
struct RefinedPart {
  HostMesh mesh;
  std::vector<std::int64_t> node_gid, elem_gid;
};
RefinedPart refine_elements(const HostMesh& coarse, const CoarseTopology& topo,
                            const std::vector<int>& coarse_elems);

// Where the interfaces of each coarse element's children start in the numbering insert_interfaces
// gives the whole refined mesh when every region is fracturable and the fine elements are in the
// order of their global ids (interfaces ordered by their side-A element, the lower one): a prefix
// sum over the coarse elements of the faces inside each one's refinement and the fine faces of its
// coarse faces towards a higher coarse element, computed from the coarse mesh alone, so that a
// process that inserts only its own part's interfaces numbers them as the whole mesh would.
// Size: coarse elements + 1 (the last: the whole mesh's interface count).
std::vector<std::int64_t> refined_interface_offsets(const HostMesh& coarse, const CoarseTopology& topo);

// A refined mesh's element edges summed per coarse element: `fine` holds groups of `children`
// consecutive elements (each coarse element's children, in order), and each group's sum runs over
// its elements' edges in mesh_quality's order. Summed over the coarse elements in their order and
// divided by the edge count, they give the refined mesh's mean element size (refined_mean_size),
// which a process holding only its own coarse elements' children computes to the same bits
// (docs/parallel.md, "The local set-up"): unlike mesh_quality's one running sum over the whole mesh.
std::vector<double> coarse_edge_sums(const HostMesh& fine, int children);
double refined_mean_size(const HostMesh& fine, int children);
// The same from the sums (coarse element order) and the fine element count.
double mean_size_from_sums(const std::vector<double>& sums, long fine_elems, int dim);

// The whole mesh refined `levels` times; nodes in the order of their global ids (so node i is
// the coarse mesh's node i for every coarse node), elements in the order of theirs. levels 0:
// the mesh as it is.
HostMesh refine_mesh(const HostMesh& coarse, int levels, const std::vector<CurvedSurface>& surfaces);

}  // namespace fdem
