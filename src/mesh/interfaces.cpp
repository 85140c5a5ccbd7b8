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
// - Faces of the face sets named in `cut` get an interface even between two non-fracturable
//   elements; the nodes on them take one copy per side (cut_sides).
// - Interfaces are ordered by (element A, local face of A).
// - node_origin of every new node is the node_origin of its original node (identity if the mesh
//   had none), i.e. the node's id in the mesh as read or generated.
#include <algorithm>
#include <array>
#include <string>
#include <utility>
#include <vector>

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
  const int nn = mesh.num_nodes();
  // The faces by their sorted node ids: a counting sort by the first (smallest) id, then each
  // bucket (a few dozen faces around one node) by the other two ids, stably: equal keys stay in
  // element order. Linear in the faces, no sort of all of them.
  struct Entry {
    int k1, k2, ef;  // second and third node id (-1 in 2D), e * npe + f
  };
  const std::size_t nfaces = static_cast<std::size_t>(ne) * npe;
  auto key = [&](int e, int f) {  // the sorted node ids of local face f of element e
    std::array<int, 3> k{-1, -1, -1};
    for (int a = 0; a < dim; ++a) k[a] = mesh.elems[static_cast<std::size_t>(e) * npe + face_node(dim, f, a)];
    sort_face_key(k, dim);
    return k;
  };
  std::vector<int> start(static_cast<std::size_t>(nn) + 1, 0);
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      const int k0 = key(e, f)[0];
      if (k0 < 0 || k0 >= nn)
        throw InputError("insert_interfaces: element " + std::to_string(e) + " has a node out of range");
      ++start[static_cast<std::size_t>(k0) + 1];
    }
  for (int i = 0; i < nn; ++i) start[i + 1] += start[i];
  std::vector<Entry> faces(nfaces);
  {
    std::vector<int> at(start.begin(), start.end() - 1);
    for (int e = 0; e < ne; ++e)
      for (int f = 0; f < npe; ++f) {
        const std::array<int, 3> k = key(e, f);
        faces[at[k[0]]++] = {k[1], k[2], e * npe + f};
      }
  }
  auto before = [](const Entry& a, const Entry& b) { return a.k1 != b.k1 ? a.k1 < b.k1 : a.k2 < b.k2; };
  for (int i = 0; i < nn; ++i) {
    if (start[i + 1] - start[i] > 64) {
      std::stable_sort(faces.begin() + start[i], faces.begin() + start[i + 1], before);
      continue;
    }
    for (int j = start[i] + 1; j < start[i + 1]; ++j) {  // insertion sort (stable)
      const Entry x = faces[j];
      int q = j;
      for (; q > start[i] && before(x, faces[q - 1]); --q) faces[q] = faces[q - 1];
      faces[q] = x;
    }
  }
  std::vector<int> neighbour(nfaces, -1);
  for (int o = 0; o < nn; ++o)
    for (int i = start[o]; i < start[o + 1];) {
      int j = i + 1;
      while (j < start[o + 1] && faces[j].k1 == faces[i].k1 && faces[j].k2 == faces[i].k2) ++j;
      if (j - i > 2) {
        const int e = faces[i].ef / npe;
        const auto c = centroid(mesh, e);
        throw InputError("insert_interfaces: a face of element " + std::to_string(e) + " (centroid (" +
                         fmt(c[0]) + ", " + fmt(c[1]) + (dim == 3 ? ", " + fmt(c[2]) : std::string()) +
                         ")) is shared by " + std::to_string(j - i) + " elements (non-manifold mesh)");
      }
      if (j - i == 2) {
        neighbour[faces[i].ef] = faces[i + 1].ef / npe;
        neighbour[faces[i + 1].ef] = faces[i].ef / npe;
      }
      i = j;
    }
  return neighbour;
}

// Faces of the cut face sets: cut[e * (dim + 1) + f] is 1 for local face f of element e when
// it is a facet of one of the face sets named in `names` and shared by two elements.
std::vector<char> cut_faces(const HostMesh& mesh, const std::vector<std::string>& names,
                            const std::vector<int>& neighbour) {
  const int dim = mesh.dim, npe = dim + 1, ne = mesh.num_elems(), nn = mesh.num_nodes();
  std::vector<char> cut;
  if (names.empty()) return cut;
  cut.assign(static_cast<std::size_t>(ne) * npe, 0);
  std::vector<std::pair<std::array<int, 3>, int>> keys;  // facet, index of its set in names
  for (std::size_t ni = 0; ni < names.size(); ++ni) {
    const std::string& name = names[ni];
    const auto it = mesh.face_sets.find(name);
    if (it == mesh.face_sets.end()) {
      std::string known;
      for (const auto& kv : mesh.face_sets) known += (known.empty() ? "'" : ", '") + kv.first + "'";
      throw InputError("insert_interfaces: the mesh has no face set '" + name + "' (a physical " +
                       (dim == 2 ? "curve" : "surface") +
                       " of the Gmsh mesh; it has: " + (known.empty() ? "none" : known) + ")");
    }
    const std::vector<int>& f = it->second;
    for (std::size_t i = 0; i + dim <= f.size(); i += dim) {
      std::array<int, 3> k{-1, -1, -1};
      for (int a = 0; a < dim; ++a) {
        if (f[i + a] < 0 || f[i + a] >= nn)
          throw InputError("insert_interfaces: face set '" + name + "': node id out of range");
        k[a] = f[i + a];
      }
      sort_face_key(k, dim);
      keys.push_back({k, static_cast<int>(ni)});
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<char> used(names.size(), 0);
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      if (neighbour[static_cast<std::size_t>(e) * npe + f] < 0) continue;
      std::array<int, 3> k{-1, -1, -1};
      for (int a = 0; a < dim; ++a)
        k[a] = mesh.elems[static_cast<std::size_t>(e) * npe + face_node(dim, f, a)];
      sort_face_key(k, dim);
      for (auto it = std::lower_bound(keys.begin(), keys.end(), std::make_pair(k, -1));
           it != keys.end() && it->first == k; ++it) {
        cut[static_cast<std::size_t>(e) * npe + f] = 1;
        used[it->second] = 1;
      }
    }
  for (std::size_t ni = 0; ni < names.size(); ++ni)
    if (!used[ni])
      throw InputError("insert_interfaces: face set '" + names[ni] +
                       "' has no face inside the mesh (every facet of it is on the " +
                       "outer boundary or is not a face of an element): there is nothing to cut");
  return cut;
}

// Union-find over element node slots (e * (dim + 1) + a).
using Slots = UnionFind;

// For the nodes on a cut face of a non-fracturable element: the slots of the non-fracturable
// elements around each such node joined where two of them share a face that is not cut (the
// elements on one side of the cut; around the end of a cut surface, all of them).
Slots cut_sides(const HostMesh& mesh, const std::vector<bool>& fracturable, const std::vector<int>& neighbour,
                const std::vector<char>& cut, std::vector<char>& on_cut) {
  const int dim = mesh.dim, npe = dim + 1, ne = mesh.num_elems();
  Slots u(ne * npe);
  on_cut.assign(mesh.num_nodes(), 0);
  auto frac = [&](int e) { return static_cast<bool>(fracturable[mesh.elem_region[e]]); };
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f)
      if (cut[static_cast<std::size_t>(e) * npe + f] && !frac(e))
        for (int k = 0; k < dim; ++k)
          on_cut[mesh.elems[static_cast<std::size_t>(e) * npe + face_node(dim, f, k)]] = 1;
  for (int e = 0; e < ne; ++e) {
    if (frac(e)) continue;
    for (int f = 0; f < npe; ++f) {
      const int b = neighbour[static_cast<std::size_t>(e) * npe + f];
      if (b <= e || frac(b) || cut[static_cast<std::size_t>(e) * npe + f]) continue;
      for (int k = 0; k < dim; ++k) {
        const int la = face_node(dim, f, k);
        const int o = mesh.elems[static_cast<std::size_t>(e) * npe + la];
        if (!on_cut[o]) continue;
        for (int lb = 0; lb < npe; ++lb)
          if (mesh.elems[static_cast<std::size_t>(b) * npe + lb] == o) u.join(e * npe + la, b * npe + lb);
      }
    }
  }
  return u;
}

// New nodes, element by element: new_elems is the new connectivity, origin[new] the original
// (pre-insertion) id. A node of a non-fracturable element on a cut face takes the copy of its
// side (cut_sides), numbered when first met like the shared nodes.
void split_nodes(const HostMesh& mesh, const std::vector<bool>& fracturable, const std::vector<char>& on_cut,
                 Slots& sides, std::vector<int>& new_elems, std::vector<int>& origin) {
  const int npe = mesh.dim + 1;
  const int ne = mesh.num_elems();
  std::vector<int> shared(mesh.num_nodes(), -1);  // original -> new id for nodes of non-fracturable elements
  std::vector<int> side_copy(on_cut.empty() ? 0 : static_cast<std::size_t>(ne) * npe, -1);
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
        int& id = !on_cut.empty() && on_cut[o] ? side_copy[sides.find(static_cast<int>(s))] : shared[o];
        if (id < 0) {
          id = static_cast<int>(origin.size());
          origin.push_back(o);
        }
        new_elems[s] = id;
      }
    }
  }
}

// Interfaces: for each element in order, faces towards higher-index neighbours.
void build_interfaces(const HostMesh& mesh, const std::vector<bool>& fracturable,
                      const std::vector<int>& neighbour, const std::vector<char>& cut,
                      const std::vector<int>& new_elems, std::vector<int>& ifaces,
                      std::vector<int>& iface_elems, std::vector<std::array<int, 3>>& iface_keys) {
  const int dim = mesh.dim;
  const int npe = dim + 1;
  const int ne = mesh.num_elems();
  const bool keep_keys = !mesh.face_sets.empty();  // for fill_iface_sets
  auto frac = [&](int e) { return static_cast<bool>(fracturable[mesh.elem_region[e]]); };
  auto inserted = [&](int e, int f) {
    const int b = neighbour[static_cast<std::size_t>(e) * npe + f];
    if (b <= e) return false;  // boundary face, or already handled from the lower-index side
    return frac(e) || frac(b) || (!cut.empty() && cut[static_cast<std::size_t>(e) * npe + f]);
  };
  std::size_t count = 0;  // (counted first: the arrays are filled without growing)
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) count += inserted(e, f);
  ifaces.reserve(ifaces.size() + 2 * dim * count);
  iface_elems.reserve(iface_elems.size() + 2 * count);
  if (keep_keys) iface_keys.reserve(iface_keys.size() + count);
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      if (!inserted(e, f)) continue;
      const int b = neighbour[static_cast<std::size_t>(e) * npe + f];
      int a_nodes[3], b_nodes[3];
      std::array<int, 3> key{-1, -1, -1};
      for (int k = 0; k < dim; ++k) {
        const int la = face_node(dim, f, k);
        const int o = mesh.elems[static_cast<std::size_t>(e) * npe + la];
        a_nodes[k] = new_elems[static_cast<std::size_t>(e) * npe + la];
        key[k] = o;
        b_nodes[k] = -1;
        for (int lb = 0; lb < npe; ++lb)
          if (mesh.elems[static_cast<std::size_t>(b) * npe + lb] == o)
            b_nodes[k] = new_elems[static_cast<std::size_t>(b) * npe + lb];
      }
      ifaces.insert(ifaces.end(), a_nodes, a_nodes + dim);
      ifaces.insert(ifaces.end(), b_nodes, b_nodes + dim);
      iface_elems.push_back(e);
      iface_elems.push_back(b);
      if (keep_keys) {
        sort_face_key(key, dim);
        iface_keys.push_back(key);
      }
    }
}

// The interfaces on each face set (by the original node ids of their faces).
void fill_iface_sets(HostMesh& mesh, const std::vector<std::array<int, 3>>& iface_keys) {
  const int dim = mesh.dim;
  mesh.iface_sets.clear();
  for (const auto& [name, f] : mesh.face_sets) {
    std::vector<std::array<int, 3>> keys;
    for (std::size_t i = 0; i + dim <= f.size(); i += dim) {
      std::array<int, 3> k{-1, -1, -1};
      for (int a = 0; a < dim; ++a) k[a] = f[i + a];
      sort_face_key(k, dim);
      keys.push_back(k);
    }
    std::sort(keys.begin(), keys.end());
    std::vector<int>& out = mesh.iface_sets[name];
    for (std::size_t q = 0; q < iface_keys.size(); ++q)
      if (std::binary_search(keys.begin(), keys.end(), iface_keys[q])) out.push_back(static_cast<int>(q));
  }
  mesh.face_sets.clear();
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
  std::vector<char> in;  // (a large set: its copies marked, then read in order, without a sort)
  for (auto& [name, set] : mesh.node_sets) {
    std::vector<int> out;
    if (set.size() > static_cast<std::size_t>(nn) / 16) {
      in.assign(static_cast<std::size_t>(nn_new), 0);
      std::size_t marked = 0;
      for (int o : set)
        if (o >= 0 && o < nn)
          for (int j = start[o]; j < start[o + 1]; ++j) {
            marked += !in[copies[j]];
            in[copies[j]] = 1;
          }
      out.reserve(marked);
      for (int n = 0; n < nn_new; ++n)
        if (in[n]) out.push_back(n);
    } else {
      for (int o : set) {
        if (o < 0 || o >= nn) continue;
        out.insert(out.end(), copies.begin() + start[o], copies.begin() + start[o + 1]);
      }
      std::sort(out.begin(), out.end());
      out.erase(std::unique(out.begin(), out.end()), out.end());
    }
    set.swap(out);
  }
}

}  // namespace

void insert_interfaces(HostMesh& mesh, const std::vector<bool>& fracturable,
                       const std::vector<std::string>& cut) {
  check_insertion_args(mesh, fracturable);
  const int dim = mesh.dim;
  const int nn = mesh.num_nodes();
  const std::vector<int> neighbour = face_neighbours(mesh);
  const std::vector<char> cutf = cut_faces(mesh, cut, neighbour);
  std::vector<char> on_cut;
  Slots sides;
  if (!cut.empty()) sides = cut_sides(mesh, fracturable, neighbour, cutf, on_cut);
  std::vector<int> new_elems, origin;
  split_nodes(mesh, fracturable, on_cut, sides, new_elems, origin);
  const int nn_new = static_cast<int>(origin.size());
  std::vector<int> ifaces, iface_elems;
  std::vector<std::array<int, 3>> iface_keys;
  build_interfaces(mesh, fracturable, neighbour, cutf, new_elems, ifaces, iface_elems, iface_keys);
  fill_iface_sets(mesh, iface_keys);

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
