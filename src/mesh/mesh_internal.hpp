#pragma once
// Helpers shared by the files of the mesh module (not part of its public interface).
#include <array>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/union_find.hpp"
#include "mesh/mesh.hpp"

namespace fdem::mesh_detail {

// Local faces of a positively oriented simplex, each ordered so that the normal by the convention
// of mesh.hpp (2D: n = (t_y, -t_x), t = x1 - x0; 3D: n = (x1 - x0) x (x2 - x0)) points OUT of
// the element. 2D: 3 edges of 2 nodes; 3D: 4 triangles of 3 nodes (face f is opposite vertex f
// in 3D, opposite vertex (f + 2) % 3 in 2D).
inline constexpr int kFaces2[3][2] = {{0, 1}, {1, 2}, {2, 0}};
inline constexpr int kFaces3[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Lists per key in CSR form: off[k]..off[k+1] in `item` (counting sort by key, items in order).
struct Csr {
  std::vector<int> off, item;
  template <class KeyOf>
  Csr(int nkeys, int nitems, KeyOf key_of) : off(static_cast<std::size_t>(nkeys) + 1, 0), item(nitems) {
    for (int i = 0; i < nitems; ++i) ++off[key_of(i) + 1];
    for (int k = 0; k < nkeys; ++k) off[k + 1] += off[k];
    std::vector<int> fill(off.begin(), off.end() - 1);
    for (int i = 0; i < nitems; ++i) item[fill[key_of(i)]++] = i;
  }
};

inline int faces_per_elem(int dim) { return dim + 1; }
// Local node `k` (0..dim-1) of local face `f`.
inline int face_node(int dim, int f, int k) { return dim == 2 ? kFaces2[f][k] : kFaces3[f][k]; }

// Sort the first `dim` (2 or 3) entries of a face key in place (third entry -1 in 2D).
inline void sort_face_key(std::array<int, 3>& k, int dim) {
  auto order = [&](int i, int j) {
    if (k[j] < k[i]) std::swap(k[i], k[j]);
  };
  order(0, 1);
  if (dim == 3) {
    order(1, 2);
    order(0, 1);
  }
}

// Signed area (2D) or volume (3D) of element e; positive when the element is positively oriented.
double signed_measure(const HostMesh& m, int e);
// Centroid of element e (3 components, z = 0 in 2D).
std::array<double, 3> centroid(const HostMesh& m, int e);

// Swap two nodes of every element with negative signed measure (generator output only).
void orient_positively(HostMesh& m);

// Element check with optional original element tags for the message (read_gmsh passes Gmsh's).
void check_elements_impl(const HostMesh& mesh, const std::string& source,
                         const std::vector<std::size_t>* elem_tags);

// Wall and CPU seconds of the Gmsh session's parts, measured in its process (setup_times).
struct GmshTimes {
  double trial[2] = {0, 0};    // trial meshes of the memory check (.geo files)
  double mesh[2] = {0, 0};     // gmsh::model::mesh::generate
  double extract[2] = {0, 0};  // extract_model
};

// A mesh taken from the current Gmsh model (gmsh_extract.cpp), with Gmsh's tag of each element.
struct Extracted {
  HostMesh mesh;
  std::vector<std::size_t> elem_tags;
  GmshTimes times;
};
// Turn the current Gmsh model's mesh into a HostMesh (call inside a Gmsh session). Does not check
// element orientation. Throws InputError naming `source`.
Extracted extract_model(int dim, const std::string& source);

// A generated mesh through Gmsh (gmsh_io.cpp): build() adds the model (geometry and physical
// groups) in a Gmsh session in a child process (gmsh_child.cpp); then the size h (Delaunay in 2D,
// algorithm3d in 3D), meshing in `dim`, extraction, the check that Gmsh honoured h (gmsh_sizes.cpp),
// positive orientation and the element checks. Gmsh's errors become InputError naming `who` ("could
// not <doing>").
HostMesh generate_with_gmsh(const std::string& who, const std::string& doing, int dim, double h,
                            int algorithm3d, const std::function<void()>& build);

// Format a double compactly (like %g with 6 significant digits).
std::string fmt(double v);

using fdem::UnionFind;  // src/common/union_find.hpp

}  // namespace fdem::mesh_detail
