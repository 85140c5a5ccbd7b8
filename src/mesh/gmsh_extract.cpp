// Conversion of the current Gmsh model's mesh into a HostMesh (used by the Gmsh-based reader and
// the unstructured generators in gmsh_io.cpp, inside a Gmsh session).
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "common/error.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::mesh_detail {

namespace {

std::string group_name(int dim, int tag) {
  std::string name;
  gmsh::model::getPhysicalName(dim, tag, name);
  return name.empty() ? "group_" + std::to_string(tag) : name;
}

std::string element_type_name(int type) {
  std::string name;
  int d = 0, order = 0, nn = 0, np = 0;
  std::vector<double> loc;
  try {
    gmsh::model::mesh::getElementProperties(type, name, d, order, nn, loc, np);
  } catch (...) {
    return "type " + std::to_string(type);
  }
  return "'" + name + "'";
}

struct Elem {
  std::size_t tag;
  int region;
  std::array<std::size_t, 4> nodes;
};

// Nodes used by bulk elements, numbered 0..n-1 in increasing Gmsh tag.
struct NodeIndex {
  std::vector<std::size_t> used;               // new id -> Gmsh tag
  std::unordered_map<std::size_t, int> index;  // Gmsh tag -> new id
  int size() const { return static_cast<int>(used.size()); }
};

// Higher-dimensional elements mean the case dimension is wrong.
void check_no_higher_dim_elements(int dim, const std::string& source) {
  for (int d = dim + 1; d <= 3; ++d) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> et, nt;
    gmsh::model::mesh::getElements(types, et, nt, d, -1);
    std::size_t count = 0;
    for (const auto& v : et) count += v.size();
    if (count > 0)
      throw InputError(source + ": the mesh contains " + std::to_string(count) + " " + std::to_string(d) +
                       "D elements but the case is " + std::to_string(dim) + "D");
  }
}

// Regions: physical groups of dimension dim, by tag. Returns group tag -> region index.
std::map<int, int> read_regions(HostMesh& m, int dim) {
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, dim);
  std::sort(groups.begin(), groups.end());
  std::map<int, int> region_of_group;
  for (const auto& [d, tag] : groups) {
    const std::string name = group_name(d, tag);
    int r = m.region_index(name);
    if (r < 0) {
      r = static_cast<int>(m.region_names.size());
      m.region_names.push_back(name);
    }
    region_of_group[tag] = r;
  }
  return region_of_group;
}

// Region of entity (d, etag) whose elements are `et`: its lowest physical group, else "default"
// (added on first use). -1: an entity in no group and without elements (skipped).
int entity_region(HostMesh& m, int d, int etag, const std::map<int, int>& region_of_group,
                  const std::vector<std::vector<std::size_t>>& et, int& default_region) {
  std::vector<int> phys;
  gmsh::model::getPhysicalGroupsForEntity(d, etag, phys);
  std::sort(phys.begin(), phys.end());
  if (!phys.empty()) return region_of_group.at(phys.front());  // in several groups: lowest tag wins
  bool any = false;
  for (const auto& v : et) any = any || !v.empty();
  if (!any) return -1;
  if (default_region < 0) {
    default_region = m.region_index("default");
    if (default_region < 0) {
      default_region = static_cast<int>(m.region_names.size());
      m.region_names.push_back("default");
    }
  }
  return default_region;
}

// The linear simplices of all entities of dimension dim, sorted by Gmsh tag (stable).
std::vector<Elem> read_elements(HostMesh& m, int dim, const std::map<int, int>& region_of_group,
                                const std::string& source) {
  const int lin_type = dim == 2 ? 2 : 4;  // 3-node triangle, 4-node tetrahedron
  const int npe = dim + 1;
  int default_region = -1;
  std::vector<Elem> elems;
  gmsh::vectorpair ents;
  gmsh::model::getEntities(ents, dim);
  for (const auto& [d, etag] : ents) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> et, nt;
    gmsh::model::mesh::getElements(types, et, nt, d, etag);
    const int region = entity_region(m, d, etag, region_of_group, et, default_region);
    if (region < 0) continue;
    for (std::size_t t = 0; t < types.size(); ++t) {
      if (et[t].empty()) continue;
      if (types[t] != lin_type)
        throw InputError(source + ": " + std::to_string(et[t].size()) + " elements of " +
                         element_type_name(types[t]) + " in " + std::to_string(d) + "D entity " +
                         std::to_string(etag) + "; only linear " + (dim == 2 ? "triangles" : "tetrahedra") +
                         " are supported");
      for (std::size_t i = 0; i < et[t].size(); ++i) {
        Elem e{et[t][i], region, {0, 0, 0, 0}};
        for (int a = 0; a < npe; ++a) e.nodes[a] = nt[t][i * npe + a];
        elems.push_back(e);
      }
    }
  }
  if (elems.empty())
    throw InputError(source + ": the mesh contains no " +
                     std::string(dim == 2 ? "triangles (2D elements)" : "tetrahedra (3D elements)"));
  std::stable_sort(elems.begin(), elems.end(), [](const Elem& a, const Elem& b) { return a.tag < b.tag; });
  return elems;
}

NodeIndex number_used_nodes(const std::vector<Elem>& elems, int npe) {
  NodeIndex out;
  std::vector<std::size_t>& used = out.used;
  used.reserve(elems.size() * npe);
  for (const auto& e : elems) used.insert(used.end(), e.nodes.begin(), e.nodes.begin() + npe);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  out.index.reserve(used.size() * 2);
  for (std::size_t i = 0; i < used.size(); ++i) out.index[used[i]] = static_cast<int>(i);
  return out;
}

// Coordinates (3 per node) of the used nodes; every used node must be defined.
std::vector<double> read_node_coords(const NodeIndex& nodes, const std::string& source) {
  std::vector<std::size_t> ntags;
  std::vector<double> coord, param;
  gmsh::model::mesh::getNodes(ntags, coord, param, -1, -1, false, false);
  const int nn = nodes.size();
  std::vector<double> xyz(3 * static_cast<std::size_t>(nn), 0.0);
  std::vector<char> have(nn, 0);
  for (std::size_t i = 0; i < ntags.size(); ++i) {
    auto it = nodes.index.find(ntags[i]);
    if (it == nodes.index.end()) continue;
    for (int k = 0; k < 3; ++k) xyz[3 * static_cast<std::size_t>(it->second) + k] = coord[3 * i + k];
    have[it->second] = 1;
  }
  for (int n = 0; n < nn; ++n)
    if (!have[n])
      throw InputError(source + ": node " + std::to_string(nodes.used[n]) +
                       " is used by an element but not defined");
  return xyz;
}

void check_planar(const std::vector<double>& xyz, int nn, const std::string& source) {
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
  }
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], xyz[3 * static_cast<std::size_t>(n) + k]);
      hi[k] = std::max(hi[k], xyz[3 * static_cast<std::size_t>(n) + k]);
    }
  const double ext = std::max(hi[0] - lo[0], hi[1] - lo[1]);
  if (hi[2] - lo[2] > 1e-8 * ext)
    throw InputError(source + ": a 2D mesh must lie in a plane z = const (z ranges from " + fmt(lo[2]) +
                     " to " + fmt(hi[2]) + ")");
}

// Coordinates, connectivity, regions and element tags into `out`.
void fill_mesh(Extracted& out, const std::vector<double>& xyz, const std::vector<Elem>& elems,
               const NodeIndex& nodes) {
  HostMesh& m = out.mesh;
  const int dim = m.dim, npe = dim + 1, nn = nodes.size();
  m.X.resize(static_cast<std::size_t>(nn) * dim);
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < dim; ++k)
      m.X[static_cast<std::size_t>(n) * dim + k] = xyz[3 * static_cast<std::size_t>(n) + k];
  m.elems.resize(elems.size() * npe);
  m.elem_region.resize(elems.size());
  out.elem_tags.resize(elems.size());
  for (std::size_t e = 0; e < elems.size(); ++e) {
    for (int a = 0; a < npe; ++a) m.elems[e * npe + a] = nodes.index.at(elems[e].nodes[a]);
    m.elem_region[e] = elems[e].region;
    out.elem_tags[e] = elems[e].tag;
  }
}

// Node sets: physical groups of lower dimension (union over groups with the same name), "all" if
// absent; identity node_origin.
void read_node_sets(HostMesh& m, const NodeIndex& nodes) {
  const int nn = nodes.size();
  for (int d = 0; d < m.dim; ++d) {
    gmsh::vectorpair pg;
    gmsh::model::getPhysicalGroups(pg, d);
    std::sort(pg.begin(), pg.end());
    for (const auto& [gd, gtag] : pg) {
      std::vector<std::size_t> tags;
      std::vector<double> c;
      gmsh::model::mesh::getNodesForPhysicalGroup(gd, gtag, tags, c);
      auto& set = m.node_sets[group_name(gd, gtag)];
      for (std::size_t t : tags) {
        auto it = nodes.index.find(t);
        if (it != nodes.index.end()) set.push_back(it->second);
      }
    }
  }
  for (auto& [name, set] : m.node_sets) {
    std::sort(set.begin(), set.end());
    set.erase(std::unique(set.begin(), set.end()), set.end());
  }
  if (!m.node_sets.count("all")) {
    std::vector<int> all(nn);
    std::iota(all.begin(), all.end(), 0);
    m.node_sets["all"] = std::move(all);
  }
  m.node_origin.resize(nn);
  std::iota(m.node_origin.begin(), m.node_origin.end(), 0);
}

// Face sets: physical groups of dimension dim - 1 as their facets (2-node lines in 2D, 3-node
// triangles in 3D); facets with a node that no element uses are left out.
void read_face_sets(HostMesh& m, const NodeIndex& nodes) {
  const int d = m.dim - 1, type = m.dim == 2 ? 1 : 2;
  gmsh::vectorpair pg;
  gmsh::model::getPhysicalGroups(pg, d);
  std::sort(pg.begin(), pg.end());
  for (const auto& [gd, gtag] : pg) {
    std::vector<int> ents;
    gmsh::model::getEntitiesForPhysicalGroup(gd, gtag, ents);
    auto& set = m.face_sets[group_name(gd, gtag)];
    for (int ent : ents) {
      std::vector<std::size_t> etags, ntags;
      gmsh::model::mesh::getElementsByType(type, etags, ntags, ent);
      for (std::size_t i = 0; i + m.dim <= ntags.size(); i += m.dim) {
        int f[3] = {-1, -1, -1};
        bool ok = true;
        for (int a = 0; a < m.dim && ok; ++a) {
          const auto it = nodes.index.find(ntags[i + a]);
          ok = it != nodes.index.end();
          if (ok) f[a] = it->second;
        }
        if (ok) set.insert(set.end(), f, f + m.dim);
      }
    }
  }
}

}  // namespace

Extracted extract_model(int dim, const std::string& source) {
  Extracted out;
  HostMesh& m = out.mesh;
  m.dim = dim;
  check_no_higher_dim_elements(dim, source);
  const std::map<int, int> region_of_group = read_regions(m, dim);
  const std::vector<Elem> elems = read_elements(m, dim, region_of_group, source);
  const NodeIndex nodes = number_used_nodes(elems, dim + 1);
  const std::vector<double> xyz = read_node_coords(nodes, source);
  if (dim == 2) check_planar(xyz, nodes.size(), source);
  fill_mesh(out, xyz, elems, nodes);
  read_node_sets(m, nodes);
  read_face_sets(m, nodes);
  return out;
}

}  // namespace fdem::mesh_detail
