// Insertion of zero-thickness cohesive interface elements (docs/theory.md section 1).
//
// Rules (see also mesh.hpp):
// - Elements keep their indices and order. Nodes are renumbered element by element in order of
//   first use: an element of a fracturable region gets fresh copies of all its nodes; an element of
//   a non-fracturable region uses the (shared) node of its original node, numbered when first met.
//   Nodes that no element uses are dropped.
// - Every face shared by two elements of which at least one is fracturable gets one interface.
//   Side A is the element with the LOWER index, side B the higher one. The A-side nodes follow the
//   outward ordering of the face in element A, so the normal by the convention of mesh.hpp points
//   from A towards B. Pair k = (A's copy, B's copy) of the same original node.
// - Interfaces are ordered by (element A, local face of A).
// - node_origin of every new node is the node_origin of its original node (identity if the mesh
//   had none), i.e. the node's id in the mesh as read or generated.
#include <algorithm>
#include <array>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

using namespace mesh_detail;

namespace {

void check_insertion_args(const HostMesh& mesh, const std::vector<bool>& fracturable) {
  const int dim = mesh.dim;
  if (dim != 2 && dim != 3) throw InputError("insert_interfaces: mesh dimension must be 2 or 3");
  if (!mesh.ifaces.empty() || !mesh.iface_elems.empty())
    throw InputError("insert_interfaces: the mesh already has interfaces");
  if (fracturable.size() != mesh.region_names.size())
    throw InputError("insert_interfaces: " + std::to_string(fracturable.size()) +
                     " fracturable flags for " + std::to_string(mesh.region_names.size()) +
                     " regions");
  for (int r : mesh.elem_region)
    if (r < 0 || r >= static_cast<int>(fracturable.size()))
      throw InputError("insert_interfaces: element region index out of range");
}

// Neighbours across faces (by original node ids): neighbour[e * (dim + 1) + f] is the element on
// the other side of local face f of element e, -1 on the boundary.
std::vector<int> face_neighbours(const HostMesh& mesh) {
  const int dim = mesh.dim;
  const int npe = dim + 1;
  const int ne = mesh.num_elems();
  struct Entry {
    std::array<int, 3> key;
    int elem, face;
  };
  std::vector<Entry> faces;
  faces.reserve(static_cast<std::size_t>(ne) * npe);
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      std::array<int, 3> k{-1, -1, -1};
      for (int a = 0; a < dim; ++a)
        k[a] = mesh.elems[static_cast<std::size_t>(e) * npe + face_node(dim, f, a)];
      sort_face_key(k, dim);
      faces.push_back({k, e, f});
    }
  std::sort(faces.begin(), faces.end(), [](const Entry& a, const Entry& b) {
    return a.key != b.key ? a.key < b.key : a.elem < b.elem;
  });
  std::vector<int> neighbour(static_cast<std::size_t>(ne) * npe, -1);
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2) {
      const auto c = centroid(mesh, faces[i].elem);
      throw InputError("insert_interfaces: a face of element " + std::to_string(faces[i].elem) +
                       " (centroid (" + fmt(c[0]) + ", " + fmt(c[1]) +
                       (dim == 3 ? ", " + fmt(c[2]) : std::string()) + ")) is shared by " +
                       std::to_string(j - i) + " elements (non-manifold mesh)");
    }
    if (j - i == 2) {
      neighbour[static_cast<std::size_t>(faces[i].elem) * npe + faces[i].face] = faces[i + 1].elem;
      neighbour[static_cast<std::size_t>(faces[i + 1].elem) * npe + faces[i + 1].face] = faces[i].elem;
    }
    i = j;
  }
  return neighbour;
}

// New nodes, element by element: new_elems is the new connectivity, origin[new] the original
// (pre-insertion) id.
void split_nodes(const HostMesh& mesh, const std::vector<bool>& fracturable, std::vector<int>& new_elems,
                 std::vector<int>& origin) {
  const int npe = mesh.dim + 1;
  const int ne = mesh.num_elems();
  std::vector<int> shared(mesh.num_nodes(), -1);  // original -> new id for nodes of non-fracturable elements
  new_elems.resize(mesh.elems.size());
  origin.reserve(static_cast<std::size_t>(ne) * npe);
  for (int e = 0; e < ne; ++e) {
    const bool fe = fracturable[mesh.elem_region[e]];
    for (int a = 0; a < npe; ++a) {
      const std::size_t s = static_cast<std::size_t>(e) * npe + a;
      const int o = mesh.elems[s];
      if (fe) {
        new_elems[s] = static_cast<int>(origin.size());
        origin.push_back(o);
      } else {
        if (shared[o] < 0) {
          shared[o] = static_cast<int>(origin.size());
          origin.push_back(o);
        }
        new_elems[s] = shared[o];
      }
    }
  }
}

// Interfaces: for each element in order, faces towards higher-index neighbours.
void build_interfaces(const HostMesh& mesh, const std::vector<bool>& fracturable,
                      const std::vector<int>& neighbour, const std::vector<int>& new_elems,
                      std::vector<int>& ifaces, std::vector<int>& iface_elems) {
  const int dim = mesh.dim;
  const int npe = dim + 1;
  const int ne = mesh.num_elems();
  auto frac = [&](int e) { return static_cast<bool>(fracturable[mesh.elem_region[e]]); };
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      const int b = neighbour[static_cast<std::size_t>(e) * npe + f];
      if (b <= e) continue;  // boundary face, or already handled from the lower-index side
      if (!frac(e) && !frac(b)) continue;
      int a_nodes[3], b_nodes[3];
      for (int k = 0; k < dim; ++k) {
        const int la = face_node(dim, f, k);
        const int o = mesh.elems[static_cast<std::size_t>(e) * npe + la];
        a_nodes[k] = new_elems[static_cast<std::size_t>(e) * npe + la];
        b_nodes[k] = -1;
        for (int lb = 0; lb < npe; ++lb)
          if (mesh.elems[static_cast<std::size_t>(b) * npe + lb] == o)
            b_nodes[k] = new_elems[static_cast<std::size_t>(b) * npe + lb];
      }
      ifaces.insert(ifaces.end(), a_nodes, a_nodes + dim);
      ifaces.insert(ifaces.end(), b_nodes, b_nodes + dim);
      iface_elems.push_back(e);
      iface_elems.push_back(b);
    }
}

// Every node set holds all copies of its original nodes (sorted, unique).
void remap_node_sets(HostMesh& mesh, const std::vector<int>& origin) {
  const int nn = mesh.num_nodes();
  const int nn_new = static_cast<int>(origin.size());
  // copies of each original node (CSR)
  std::vector<int> start(nn + 1, 0);
  for (int n = 0; n < nn_new; ++n) ++start[origin[n] + 1];
  for (int o = 0; o < nn; ++o) start[o + 1] += start[o];
  std::vector<int> copies(nn_new), fill(start.begin(), start.end() - 1);
  for (int n = 0; n < nn_new; ++n) copies[fill[origin[n]]++] = n;
  for (auto& [name, set] : mesh.node_sets) {
    std::vector<int> out;
    for (int o : set) {
      if (o < 0 || o >= nn) continue;
      out.insert(out.end(), copies.begin() + start[o], copies.begin() + start[o + 1]);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    set.swap(out);
  }
}

}  // namespace

void insert_interfaces(HostMesh& mesh, const std::vector<bool>& fracturable) {
  check_insertion_args(mesh, fracturable);
  const int dim = mesh.dim;
  const int nn = mesh.num_nodes();
  const std::vector<int> neighbour = face_neighbours(mesh);
  std::vector<int> new_elems, origin;
  split_nodes(mesh, fracturable, new_elems, origin);
  const int nn_new = static_cast<int>(origin.size());
  std::vector<int> ifaces, iface_elems;
  build_interfaces(mesh, fracturable, neighbour, new_elems, ifaces, iface_elems);

  // Coordinates, node sets, origins.
  std::vector<double> X(static_cast<std::size_t>(nn_new) * dim);
  for (int n = 0; n < nn_new; ++n)
    for (int k = 0; k < dim; ++k)
      X[static_cast<std::size_t>(n) * dim + k] = mesh.X[static_cast<std::size_t>(origin[n]) * dim + k];
  remap_node_sets(mesh, origin);
  const bool had_origin = mesh.node_origin.size() == static_cast<std::size_t>(nn);
  std::vector<int> node_origin(nn_new);
  for (int n = 0; n < nn_new; ++n) node_origin[n] = had_origin ? mesh.node_origin[origin[n]] : origin[n];

  mesh.X.swap(X);
  mesh.elems.swap(new_elems);
  mesh.ifaces.swap(ifaces);
  mesh.iface_elems.swap(iface_elems);
  mesh.node_origin.swap(node_origin);
}

}  // namespace fdem
