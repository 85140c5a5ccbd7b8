#pragma once
// Host-side mesh: what the readers and generators produce, what interface insertion transforms,
// and what the solver uploads to the device once. Linear simplices only: triangles (dim 2) and
// tetrahedra (dim 3).
#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "mesh/particle_spec.hpp"

namespace fdem {

struct HostMesh {
  int dim = 2;
  std::vector<double> X;                 // num_nodes * dim reference coordinates
  std::vector<int> elems;                // num_elems * (dim+1) node ids, positively oriented
  std::vector<int> elem_region;          // per element: index into region_names
  std::vector<std::string> region_names;  // physical groups of dimension `dim`
  // Named node sets: physical groups of lower dimension (boundaries, points). After interface
  // insertion a set holds every copy of its original nodes.
  std::map<std::string, std::vector<int>> node_sets;
  // Named face sets: physical groups of dimension dim - 1 (curves in 2D, surfaces in 3D) as their
  // facets, `dim` node ids each (segments, triangles). Before insertion only: insert_interfaces
  // turns them into iface_sets.
  std::map<std::string, std::vector<int>> face_sets;
  // After insertion: per face set, the interfaces that lie on it (sorted indices).
  std::map<std::string, std::vector<int>> iface_sets;
  // Cohesive interfaces (filled by insert_interfaces). Interface i has `dim` node pairs; pair k is
  // (ifaces[2*dim*i + k] on side A, ifaces[2*dim*i + dim + k] on side B). The A-side nodes are
  // ordered so that the face normal from their ordering points from A towards B:
  //   2D: n = (t_y, -t_x) with t = x_A1 - x_A0;  3D: n = (x_A1 - x_A0) x (x_A2 - x_A0).
  std::vector<int> ifaces;
  std::vector<int> iface_elems;          // num_ifaces * 2: (element on side A, element on side B)
  std::vector<int> node_origin;          // per node: its id before insertion (identity before)
  // Warnings of the checks before the run (check_bodies), for the check report and summary.json.
  std::vector<std::string> warnings;
  // Bodies (elements joined through shared nodes) before interface insertion (check_bodies).
  int bodies = 0;
  // One part of a decomposed mesh (src/parallel/decompose.hpp): its first owned_nodes nodes,
  // owned_elems elements and owned_ifaces interfaces are its own, the rest ghosts. -1: a whole mesh.
  int owned_nodes = -1, owned_elems = -1, owned_ifaces = -1;
  // Its first bulk_elems elements have their bulk forces computed (the own ones and the ghosts at
  // an own node); the others only carry interfaces' sides and masses. -1: all.
  int bulk_elems = -1;
  // The whole mesh's size of each node set (node_sets hold a part's own nodes only): a point load
  // is shared by the whole set's nodes.
  std::map<std::string, long> whole_set_size;
  // A part with contact (decompose's contact reach > 0): the whole mesh's outer boundary faces
  // whose nodes the part holds, `dim` local node ids each (a part's own boundary_faces would also
  // list the faces where its ghost layer ends), and the whole mesh's connected pieces (elements
  // joined by shared nodes or interfaces; -1: not set).
  std::vector<int> outer_faces;
  int pieces = -1;
  double whole_min_size = 0;  // the whole mesh's smallest element size (contact's penetration depth)
  // A part: the whole mesh's index of each interface, from which a strength scatter without
  // correlation draws its factor (the same field on any number of processes). Empty: a whole mesh.
  std::vector<int> iface_ids;

  int nodes_per_elem() const { return dim + 1; }
  int num_nodes() const { return dim ? static_cast<int>(X.size()) / dim : 0; }
  int num_elems() const { return static_cast<int>(elems.size()) / (dim + 1); }
  int num_ifaces() const { return static_cast<int>(ifaces.size()) / (2 * dim); }
  int region_index(const std::string& name) const;  // -1 if absent
};

// What a case file's "mesh" object asks for (see docs/case-format.md).
struct MeshSpec {
  std::string kind;         // "file", "rectangle", "disc", "box", "sphere", "grains"
  std::string file;         // kind == "file": path, already resolved against the case file's folder
  double element_size = 0;  // generators (disc, sphere; rectangle/box derive nx,ny,nz if not given);
                            // .geo files: upper bound on the element size (0: the file's own)
  std::array<double, 3> origin{0, 0, 0};  // rectangle, box: lower corner; disc, sphere: centre
  std::array<double, 3> size{0, 0, 0};    // rectangle: width, height; box: lx, ly, lz
  double radius = 0;        // disc, sphere
  std::array<double, 3> diameter{0, 0, 0};  // disc: direction of a diameter meshed as element edges
                                            // (zero: none)
  bool symmetric = false;                   // disc: mesh mirror-symmetric about that diameter
  std::array<int, 3> cells{0, 0, 0};      // rectangle, box: cells per direction (0: from element_size)
  std::string region = "body";            // generators: name of the single region
  std::string mesher = "delaunay";        // sphere: Gmsh's 3D algorithm, "delaunay" or "hxt"
  ParticleSpec particles;                 // kind "particles" (src/mesh/particles.cpp)
  // grains (src/mesh/grains.hpp): the specimen's shape ("disc": origin, radius; "rectangle":
  // origin, size), the mean grain diameter, the seed of the tessellation, and the minerals (region
  // names) with their area fractions.
  std::string shape;
  double grain_size = 0;
  unsigned long seed = 1;
  std::vector<std::pair<std::string, double>> minerals;
  // Transforms of any mesh, applied once it is built (transform_mesh, src/mesh/mesh_transforms.cpp):
  // a rotation by rotation_deg about rotation_axis (3D; 2D: about z) through rotation_center (or,
  // without one, the centre of the mesh's bounding box), then a random move of each interior node
  // by up to `jitter` times its shortest edge (0: none), drawn from jitter_seed.
  double rotation_deg = 0;
  std::array<double, 3> rotation_axis{0, 0, 1};
  bool has_rotation_center = false;
  std::array<double, 3> rotation_center{0, 0, 0};
  double jitter = 0;
  unsigned long jitter_seed = 1;
  // Uniform refinement before the transforms (src/mesh/refine.hpp): each triangle into 4, each
  // tetrahedron into 8, `refine` times (0: none).
  int refine = 0;
};

// Readers and generators. All throw InputError with a message naming the file (or generator), the
// problem and, for bad elements, the element's index and location.
// .msh 2.2/4.1 ASCII or binary, or .geo (meshed on reading; element_size > 0 caps the element
// size there, so that one geometry file serves coarse and fine meshes).
HostMesh read_gmsh(const std::string& path, int dim, double element_size = 0);
// Crossed-diagonal rectangle: nx*ny cells, 4 triangles per cell around a centre node.
// Node sets: left/right/bottom/top (= xmin/xmax/ymin/ymax), and "all".
HostMesh generate_crossed_rectangle(double x0, double y0, double w, double h, int nx, int ny,
                                    const std::string& region = "body");
// Disc of radius R centred at (cx, cy), unstructured triangles of size h (Gmsh). Node sets:
// "boundary", "all". A non-zero (dx, dy) also meshes the diameter along that direction as element
// edges (nodes at both of its ends on the circle), so that a crack can run straight along it
// (node set and face set "diameter": a jitter keeps its nodes, a refinement its straightness);
// with `mirror`, the mesh is also symmetric about that diameter (one half meshed by Gmsh, the
// other its mirror image), so that a symmetric load sees a symmetric mesh.
HostMesh generate_disc(double cx, double cy, double R, double h, const std::string& region = "body",
                       double dx = 0, double dy = 0, bool mirror = false);
// Box of tetrahedra: nx*ny*nz hexahedral cells, each split into 6 tetrahedra (Kuhn). Node sets:
// xmin/xmax/ymin/ymax/zmin/zmax, "all".
HostMesh generate_box(const std::array<double, 3>& origin, const std::array<double, 3>& size,
                      int nx, int ny, int nz, const std::string& region = "body");
// Sphere of radius R, unstructured tetrahedra of size h (Gmsh). Node sets: "surface", "all".
// mesher "delaunay" (Gmsh's Algorithm3D 1) or "hxt" (10: about 8 times faster at 1e6
// tetrahedra, another mesh; one thread; not reproducible between invocations: docs/case-format.md).
HostMesh generate_sphere(const std::array<double, 3>& centre, double R, double h,
                         const std::string& region = "body", const std::string& mesher = "delaunay");
// Two meshes side by side as one (separate bodies): b's node ids, elements, regions and interfaces
// shifted after a's; node sets renamed "<prefix_a>.<name>" and "<prefix_b>.<name>".
HostMesh merge_meshes(const HostMesh& a, const HostMesh& b, const std::string& prefix_a,
                      const std::string& prefix_b);
// Dispatch on spec.kind.
HostMesh build_mesh(const MeshSpec& spec, int dim);

// The spec's rotation and jitter (MeshSpec above), before interface insertion. The jitter keeps
// the nodes of the outer boundary, of every face set and of every node set but "all" where they
// are, and moves the others one by one, in index order, each by a random vector in the ball of
// radius jitter x (its shortest edge); a move is kept only where every element at the node keeps
// at least 0.7 of its shortest altitude before the jitter (else it is halved, up to three times,
// then dropped), so that the stable time step falls by at most 30 %. Returns the nodes moved.
long transform_mesh(HostMesh& mesh, const MeshSpec& spec);

// Throws InputError naming the first element whose signed area/volume is <= a tiny fraction of
// the mean (zero or inverted), with its index, region and centroid. `source` names the file.
void check_elements(const HostMesh& mesh, const std::string& source);

// Bodies (elements joined through shared nodes) before interface insertion, src/mesh/mesh_bodies.cpp.
// Duplicate nodes: nodes used by elements that lie within `tolerance` (1e-6 of the mean edge) of
// each other. Within one body they split it at a point (a mesh error: InputError); between two
// bodies they are a warning (the bodies touch but are not joined). Overlap: nodes inside an element
// of another body deeper than the tolerance (depth: distance to that element's nearest face);
// deeper than 1e-3 of the mean edge an InputError, else a warning. `source` names the mesh.
struct BodyCheck {
  int bodies = 0;
  double tolerance = 0;  // m
  long duplicate_nodes = 0, split_pairs = 0, touching_pairs = 0;
  long overlapping_nodes = 0;
  double overlap_depth = 0;  // m, the deepest (a lower bound: distance to the nearest face of the element)
  std::vector<std::string> warnings;
};
BodyCheck check_bodies(const HostMesh& mesh, const std::string& source);

// Renumber elements along a space-filling curve and nodes in order of first use, so that
// neighbours sit near each other in memory. Call before insert_interfaces. elements false: the
// elements keep their order (a refined mesh's, src/mesh/refine.hpp), only the nodes follow it.
void reorder_for_locality(HostMesh& mesh, bool elements = true);

// Interface insertion: every element of a fracturable region gets its own copies of its nodes,
// and every face shared by two elements of which at least one is fracturable gets an interface.
// Faces between two non-fracturable elements stay continuous, except those of the face sets
// named in `cut` (joints, pre-existing cracks): they get an interface too, and their nodes a copy
// for each side (a node where a cut surface ends inside the body, at a crack tip, keeps one copy
// on both sides). `fracturable[r]` is true for region r. Fills iface_sets for every face set.
void insert_interfaces(HostMesh& mesh, const std::vector<bool>& fracturable,
                       const std::vector<std::string>& cut = {});

// Node sets "region.<name>" for the listed regions: the nodes of that region's elements. After
// interface insertion these are that region's copies only (one side of an interface between two
// regions), unlike a Gmsh node set, which holds every copy of its nodes.
void add_region_node_sets(HostMesh& mesh, const std::vector<std::string>& regions);
inline const char* kRegionSetPrefix = "region.";

// Faces on the outer boundary (belong to exactly one element and to no interface), `dim` node
// ids each, ordered so that the normal by the convention above points out of the body.
std::vector<int> boundary_faces(const HostMesh& mesh);

struct MeshQuality {
  double min_angle_deg = 0;    // smallest interior angle (2D) or dihedral angle (3D)
  double max_aspect = 0;       // longest edge / shortest altitude
  double min_size = 0;         // shortest altitude (the length that sets the time step)
  double mean_size = 0;        // mean edge length
  double min_measure = 0;      // smallest area/volume
  double edge_sum = 0;         // the edges' lengths summed (each element's), and their count:
  long edge_count = 0;         // mean_size = edge_sum / edge_count
};
MeshQuality mesh_quality(const HostMesh& mesh);
// The same over the mesh's first `elems` elements (a part's own elements: src/parallel).
MeshQuality mesh_quality(const HostMesh& mesh, int elems);
// min_size and mean_size alone, the same bits as mesh_quality's, without its angles (the set-up's
// sizes: at 1e7 tetrahedra the angles' arc cosines were most of mesh_quality's time).
struct ElementSizes {
  double min_size = 0, mean_size = 0;
};
ElementSizes mesh_sizes(const HostMesh& mesh);

}  // namespace fdem
