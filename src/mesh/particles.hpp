#pragma once
// Assemblies of many particles (mesh generator "particles", src/mesh/particles.cpp): spheres,
// ellipsoids or random convex polyhedra of random size and orientation, placed without overlap
// in a box by random sequential addition, each its own body, meshed in one Gmsh session.
#include <array>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"
#include "mesh/particle_spec.hpp"

namespace fdem {

// One placed particle. Its points are x = centre + rot * (axes * p) for p on the unit sphere
// (sphere, ellipsoid) or x = centre + rot * v for the hull vertices v (polyhedron).
struct Particle {
  std::array<double, 3> centre{0, 0, 0};
  double radius = 0;                                     // equivalent-sphere radius
  double bound = 0;                                      // bounding-sphere radius about the centre
  std::array<double, 9> rot{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major rotation matrix
  std::array<double, 3> axes{0, 0, 0};                   // sphere, ellipsoid: semi-axes
  std::vector<double> verts;                             // polyhedron: 3 per vertex, unrotated
  std::vector<int> tris;  // polyhedron: hull triangles, outward by the right-hand rule
};

struct Placement {
  std::vector<Particle> particles;  // in order of placement (largest first)
  double solid_fraction = 0;        // particle volume / box volume
  double bound_fraction = 0;        // bounding-sphere volume / box volume
};

// Draws sizes, shapes and orientations from the seed and places them (reproducible: the same
// spec gives the same placement on every platform). Throws InputError naming `who` when a key is
// out of range or when not all particles fit (with the packing fraction reached).
Placement place_particles(const ParticleSpec& s, const std::string& who);

// Convex hull of points on the unit sphere (3 coordinates each): triangles (3 vertex ids each)
// outward by the right-hand rule. Returns false when four points are nearly coplanar on the hull.
bool sphere_hull(const std::vector<double>& p, std::vector<int>& tris);

// Volume enclosed by a closed, outward triangulated surface.
double hull_volume(const std::vector<double>& p, const std::vector<int>& tris);

// The mesh of the placement: one Gmsh volume per particle (no shared nodes: each particle is its
// own body), all in region `region`; node sets "surface" (every particle surface) and "all".
HostMesh generate_particles(const ParticleSpec& s, double h, const std::string& region);

}  // namespace fdem
