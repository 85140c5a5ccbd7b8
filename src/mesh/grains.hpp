#pragma once
// Grain-based specimens (src/mesh/grains.cpp): a Voronoi tessellation of a disc or a rectangle
// into grains of a given mean size, each grain assigned a mineral by area fraction. The
// tessellation is plain geometry (tested on its own); generate_grains meshes it through Gmsh.
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "mesh/mesh.hpp"

namespace fdem {

// The grains as closed loops of vertices (counter-clockwise). Segment k of grain g runs from
// loops[g][k] to loops[g][(k + 1) % n]: a straight line, or with arc[g][k] an arc of the disc's
// circle (counter-clockwise, less than half a turn). Vertices are shared between the grains that
// meet there, so a grain boundary is the same pair of vertices in both grains.
struct GrainTessellation {
  std::vector<std::array<double, 2>> vertices;
  std::vector<std::vector<int>> loops;
  std::vector<std::vector<char>> arc;
  std::vector<int> mineral;                  // per grain: index into minerals
  std::vector<double> area;                  // per grain, m^2
  std::vector<std::array<double, 2>> seeds;  // per grain: its Voronoi seed
  std::vector<std::string> minerals;         // names (the regions)
  std::vector<double> mineral_area;          // per mineral: the area its grains cover
};

// Seeds: a random set with a minimum spacing of half the grain size (dart throwing), as many as
// the domain's area over the area of a circle of diameter spec.grain_size; the stream of random
// numbers is splitmix64 from spec.seed, so the same seed gives the same grains everywhere. Cells:
// the seed's Voronoi cell clipped to the rectangle, or to the disc's bounding square and then to
// its circle (the outer segments become arcs). Vertices closer than a third of the element size
// (at most 0.15 grain sizes) are merged, so that no grain boundary is much shorter than an element,
// and vertices that close to the circle are moved onto it. Minerals: grains in a random order, each
// to the mineral furthest below its area fraction. Throws InputError for a domain that holds fewer
// than 2 or more than 20000 grains.
GrainTessellation tessellate_grains(const MeshSpec& spec);

// The 3D tessellation of a box (spec.shape "box": origin, size): convex polyhedral grains. Each face
// is stored once (faces[f], a loop of vertex ids; face_side[f] = -1 between two grains, 0..5 on the
// box's side xmin, xmax, ymin, ymax, zmin, zmax); cells[g] lists grain g's faces. Seeds, merging
// (vertices closer than a third of the element size, at most 0.15 grain sizes) and minerals (by
// volume fraction) as in 2D; a face whose vertices no longer lie in one plane after merging is
// meshed as a fan of triangles around its centre.
struct GrainTessellation3 {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::vector<int>> faces;
  std::vector<int> face_side;
  std::vector<std::vector<int>> cells;
  std::vector<double> volume;                // per grain, m^3
  std::vector<std::array<double, 3>> seeds;  // per grain
  std::vector<int> mineral;                  // per grain: index into minerals
  std::vector<std::string> minerals;
  std::vector<double> mineral_volume;
};
GrainTessellation3 tessellate_grains_3d(const MeshSpec& spec);

// The tessellation meshed with triangles of size spec.element_size (Gmsh). Regions: the minerals;
// face (and node) sets "grain_boundaries" (curves between two grains) and "boundary" (the outer
// curves), for a rectangle also "left", "right", "bottom", "top"; node set "all".
HostMesh generate_grains(const MeshSpec& spec);
// The same in 3D (tetrahedra; face sets "grain_boundaries", "boundary", "xmin" ... "zmax").
HostMesh generate_grains_3d(const MeshSpec& spec);

}  // namespace fdem
