#pragma once
// What mesh generator "particles" asks for (MeshSpec::particles; the generator: particles.hpp).
#include <array>
#include <string>

namespace fdem {

struct ParticleSpec {
  int count = 0;
  std::string shape = "sphere";           // "sphere", "ellipsoid", "polyhedron"
  double rmin = 0, rmax = 0;              // equivalent-sphere radius (same volume), uniform in [rmin, rmax]
  double ratio_min = 0.5, ratio_max = 1;  // ellipsoid: b/a and c/a, each uniform in this range
  int vertices = 12;                      // polyhedron: points on a sphere whose convex hull it is
  std::array<double, 3> box_origin{0, 0, 0}, box_size{0, 0, 0};  // every particle lies inside
  double gap = 0;                                                // least clearance between two
  unsigned long seed = 1;
  int batch = 50;                   // particles per Gmsh session (particles.cpp: cost linear in N)
  std::string mesher = "delaunay";  // Gmsh's 3D algorithm: "delaunay" (1) or "hxt" (10)
  int threads = 1;  // Gmsh's threads (General.NumThreads; the mesh depends on it: see particles.cpp)
};

}  // namespace fdem
