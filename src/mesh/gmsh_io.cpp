// Gmsh-based reader (.msh 2.2/4.1 ASCII or binary, .geo meshed on the fly) and the unstructured
// generators (disc, sphere) through the Gmsh C++ API.
#include <gmsh.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <unordered_map>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"
#include "mesh/msh_check.hpp"

namespace fdem {

namespace {

using namespace mesh_detail;

// The Gmsh API is one global state: one session at a time, always finalized. Terminal output is
// off; messages go to Gmsh's logger, whose "Error" lines we turn into InputError. Gmsh 4.8 reports
// errors by throwing std::string (newer versions throw std::exception) when General.AbortOnError
// is 2 (the API default). While the .geo/.msh parser runs we set it to 0: an exception thrown from
// inside Gmsh's parser leaves the parser's global state broken for the rest of the process (every
// later .geo then fails with bogus syntax errors), so we let it finish and read the log instead.
std::mutex& gmsh_mutex() {
  static std::mutex m;
  return m;
}

class GmshSession {
 public:
  GmshSession() : lock_(gmsh_mutex()) {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    try {
      gmsh::option::setNumber("General.Terminal", 0);
      gmsh::option::setNumber("General.NumThreads", 1);
      gmsh::logger::start();
    } catch (...) {
      finish();
      throw;
    }
  }
  ~GmshSession() { finish(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  // First error Gmsh logged so far in this session ("" if none), without the "Error: " prefix.
  static std::string first_error() {
    std::vector<std::string> log;
    try {
      gmsh::logger::get(log);
    } catch (...) {
      return "";
    }
    for (const auto& line : log)
      if (line.rfind("Error", 0) == 0) {
        std::string msg = line.substr(5);
        while (!msg.empty() && (msg.front() == ':' || msg.front() == ' ')) msg.erase(0, 1);
        return msg.empty() ? line : msg;
      }
    return "";
  }

 private:
  static void finish() {
    try {
      gmsh::logger::stop();
    } catch (...) {
    }
    try {
      gmsh::finalize();
    } catch (...) {
    }
  }
  std::lock_guard<std::mutex> lock_;
};

// Run a function that calls Gmsh; turn Gmsh's errors into InputError naming `source`.
template <class F>
auto gmsh_call(const std::string& source, const std::string& doing, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError&) {
    throw;
  } catch (const std::string& s) {
    throw InputError(source + ": Gmsh could not " + doing + ": " + (s.empty() ? "unknown error" : s));
  } catch (const char* s) {
    throw InputError(source + ": Gmsh could not " + doing + ": " + (s ? s : "unknown error"));
  } catch (const std::exception& e) {
    throw InputError(source + ": Gmsh could not " + doing + ": " + e.what());
  } catch (...) {
    std::string last;
    try {
      gmsh::logger::getLastError(last);
    } catch (...) {
    }
    throw InputError(source + ": Gmsh could not " + doing + ": " +
                     (last.empty() ? std::string("unknown error") : last));
  }
}

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

struct Extracted {
  HostMesh mesh;
  std::vector<std::size_t> elem_tags;  // Gmsh tag of each element
};

// Turn the current Gmsh model's mesh into a HostMesh. Does not check element orientation.
Extracted extract_model(int dim, const std::string& source) {
  const int lin_type = dim == 2 ? 2 : 4;  // 3-node triangle, 4-node tetrahedron
  const int npe = dim + 1;
  Extracted out;
  HostMesh& m = out.mesh;
  m.dim = dim;

  // Higher-dimensional elements mean the case dimension is wrong.
  for (int d = dim + 1; d <= 3; ++d) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> et, nt;
    gmsh::model::mesh::getElements(types, et, nt, d, -1);
    std::size_t count = 0;
    for (const auto& v : et) count += v.size();
    if (count > 0)
      throw InputError(source + ": the mesh contains " + std::to_string(count) + " " +
                       std::to_string(d) + "D elements but the case is " + std::to_string(dim) +
                       "D");
  }

  // Regions: physical groups of dimension dim, by tag; "default" for the rest.
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
  int default_region = -1;

  struct Elem {
    std::size_t tag;
    int region;
    std::array<std::size_t, 4> nodes;
  };
  std::vector<Elem> elems;
  gmsh::vectorpair ents;
  gmsh::model::getEntities(ents, dim);
  for (const auto& [d, etag] : ents) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> et, nt;
    gmsh::model::mesh::getElements(types, et, nt, d, etag);
    std::vector<int> phys;
    gmsh::model::getPhysicalGroupsForEntity(d, etag, phys);
    std::sort(phys.begin(), phys.end());
    int region;
    if (!phys.empty()) {
      region = region_of_group.at(phys.front());  // an entity in several groups: lowest tag wins
    } else {
      bool any = false;
      for (const auto& v : et) any = any || !v.empty();
      if (!any) continue;
      if (default_region < 0) {
        default_region = m.region_index("default");
        if (default_region < 0) {
          default_region = static_cast<int>(m.region_names.size());
          m.region_names.push_back("default");
        }
      }
      region = default_region;
    }
    for (std::size_t t = 0; t < types.size(); ++t) {
      if (et[t].empty()) continue;
      if (types[t] != lin_type)
        throw InputError(source + ": " + std::to_string(et[t].size()) + " elements of " +
                         element_type_name(types[t]) + " in " + std::to_string(d) +
                         "D entity " + std::to_string(etag) + "; only linear " +
                         (dim == 2 ? "triangles" : "tetrahedra") + " are supported");
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
  std::stable_sort(elems.begin(), elems.end(),
                   [](const Elem& a, const Elem& b) { return a.tag < b.tag; });

  // Nodes used by bulk elements, numbered 0..n-1 in increasing Gmsh tag.
  std::vector<std::size_t> used;
  used.reserve(elems.size() * npe);
  for (const auto& e : elems) used.insert(used.end(), e.nodes.begin(), e.nodes.begin() + npe);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::unordered_map<std::size_t, int> index;
  index.reserve(used.size() * 2);
  for (std::size_t i = 0; i < used.size(); ++i) index[used[i]] = static_cast<int>(i);

  std::vector<std::size_t> ntags;
  std::vector<double> coord, param;
  gmsh::model::mesh::getNodes(ntags, coord, param, -1, -1, false, false);
  const int nn = static_cast<int>(used.size());
  std::vector<double> xyz(3 * static_cast<std::size_t>(nn), 0.0);
  std::vector<char> have(nn, 0);
  for (std::size_t i = 0; i < ntags.size(); ++i) {
    auto it = index.find(ntags[i]);
    if (it == index.end()) continue;
    for (int k = 0; k < 3; ++k) xyz[3 * static_cast<std::size_t>(it->second) + k] = coord[3 * i + k];
    have[it->second] = 1;
  }
  for (int n = 0; n < nn; ++n)
    if (!have[n])
      throw InputError(source + ": node " + std::to_string(used[n]) +
                       " is used by an element but not defined");

  if (dim == 2) {
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
      throw InputError(source + ": a 2D mesh must lie in a plane z = const (z ranges from " +
                       fmt(lo[2]) + " to " + fmt(hi[2]) + ")");
  }
  m.X.resize(static_cast<std::size_t>(nn) * dim);
  for (int n = 0; n < nn; ++n)
    for (int k = 0; k < dim; ++k)
      m.X[static_cast<std::size_t>(n) * dim + k] = xyz[3 * static_cast<std::size_t>(n) + k];

  m.elems.resize(elems.size() * npe);
  m.elem_region.resize(elems.size());
  out.elem_tags.resize(elems.size());
  for (std::size_t e = 0; e < elems.size(); ++e) {
    for (int a = 0; a < npe; ++a) m.elems[e * npe + a] = index.at(elems[e].nodes[a]);
    m.elem_region[e] = elems[e].region;
    out.elem_tags[e] = elems[e].tag;
  }

  // Node sets: physical groups of lower dimension (union over groups with the same name).
  for (int d = 0; d < dim; ++d) {
    gmsh::vectorpair pg;
    gmsh::model::getPhysicalGroups(pg, d);
    std::sort(pg.begin(), pg.end());
    for (const auto& [gd, gtag] : pg) {
      std::vector<std::size_t> tags;
      std::vector<double> c;
      gmsh::model::mesh::getNodesForPhysicalGroup(gd, gtag, tags, c);
      auto& set = m.node_sets[group_name(gd, gtag)];
      for (std::size_t t : tags) {
        auto it = index.find(t);
        if (it != index.end()) set.push_back(it->second);
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
  return out;
}

std::string lower_ext(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

HostMesh read_gmsh(const std::string& path, int dim, double element_size) {
  if (dim != 2 && dim != 3)
    throw InputError(path + ": mesh dimension must be 2 or 3 (got " + std::to_string(dim) + ")");
  {
    std::error_code ec;
    if (path.empty()) throw InputError("mesh file name is empty");
    if (!std::filesystem::exists(path, ec))
      throw InputError(path + ": mesh file not found");
    if (std::filesystem::is_directory(path, ec))
      throw InputError(path + ": is a directory, not a mesh file");
    if (!std::filesystem::is_regular_file(path, ec))
      throw InputError(path + ": is not a regular file");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputError(path + ": mesh file cannot be opened for reading");
  }
  const std::string ext = lower_ext(path);
  const bool geo = ext == ".geo";
  // Gmsh picks a reader by extension and, for unknown ones, by the first line: anything that
  // does not start like a .msh file is run as a .geo script. Only .msh and .geo are accepted, and
  // a .msh file is checked first (Gmsh 4.8 crashes on malformed .msh files; see msh_check.hpp).
  // A .geo file is a script (it can include files and run commands): trust it like code.
  if (!geo && ext != ".msh")
    throw InputError(path + ": unsupported mesh file type " +
                     (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
                     " (fdem reads Gmsh .msh files, format 2.2 or 4.1, and .geo files)");
  if (!geo) check_msh_structure(path);
  Extracted ex;
  {
    GmshSession session;
    gmsh_call(path, "read the file", [&] {
      gmsh::option::setNumber("General.AbortOnError", 0);
      gmsh::open(path);
      gmsh::option::setNumber("General.AbortOnError", 2);
    });
    std::string err = GmshSession::first_error();
    if (!err.empty()) throw InputError(path + ": Gmsh could not read the file: " + err);
    if (geo) {
      if (element_size > 0) {  // an upper bound on the element size, over the file's own sizes
        gmsh::option::setNumber("Mesh.CharacteristicLengthMin", 0.0);
        gmsh::option::setNumber("Mesh.CharacteristicLengthMax", element_size);
      }
      gmsh_call(path, "mesh the geometry", [&] { gmsh::model::mesh::generate(dim); });
      err = GmshSession::first_error();
      if (!err.empty()) throw InputError(path + ": Gmsh could not mesh the geometry: " + err);
    }
    ex = gmsh_call(path, "extract the mesh", [&] { return extract_model(dim, path); });
  }
  check_elements_impl(ex.mesh, path, &ex.elem_tags);
  return std::move(ex.mesh);
}

namespace {

void check_generator_args(const std::string& who, double R, double h) {
  if (!(R > 0) || !std::isfinite(R))
    throw InputError(who + ": radius must be positive (got " + fmt(R) + ")");
  if (!(h > 0) || !std::isfinite(h))
    throw InputError(who + ": element_size must be positive (got " + fmt(h) + ")");
  if (h > R) throw InputError(who + ": element_size " + fmt(h) + " is larger than the radius " + fmt(R));
}

void set_mesh_size(double h) {
  gmsh::option::setNumber("Mesh.CharacteristicLengthMin", 0.0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthMax", h);
  gmsh::option::setNumber("Mesh.CharacteristicLengthFromCurvature", 0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthExtendFromBoundary", 1);
  // Delaunay: less regular than Frontal-Delaunay, whose rows of nearly aligned edges steer cracks
  // (Brazilian disc: the split followed the mesh rows, off the loaded diameter).
  gmsh::option::setNumber("Mesh.Algorithm", 5);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);  // Delaunay
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::option::setNumber("Mesh.Optimize", 1);
}

HostMesh finish_generated(Extracted&& ex, const std::string& who) {
  orient_positively(ex.mesh);
  check_elements_impl(ex.mesh, who, nullptr);
  return std::move(ex.mesh);
}

}  // namespace

HostMesh generate_disc(double cx, double cy, double R, double h, const std::string& region) {
  const std::string who = "disc generator";
  check_generator_args(who, R, h);
  if (R / h > 5000) throw InputError(who + ": radius / element_size is too large");
  const std::string rname = region.empty() ? std::string("body") : region;
  Extracted ex;
  {
    GmshSession session;
    ex = gmsh_call(who, "mesh the disc", [&] {
      gmsh::model::add("disc");
      const int s = gmsh::model::occ::addDisk(cx, cy, 0.0, R, R);
      gmsh::model::occ::synchronize();
      gmsh::vectorpair bnd;
      gmsh::model::getBoundary({{2, s}}, bnd, false, false, false);
      std::vector<int> curves;
      for (const auto& [d, t] : bnd) curves.push_back(std::abs(t));
      const int ps = gmsh::model::addPhysicalGroup(2, {s});
      gmsh::model::setPhysicalName(2, ps, rname);
      const int pc = gmsh::model::addPhysicalGroup(1, curves);
      gmsh::model::setPhysicalName(1, pc, "boundary");
      set_mesh_size(h);
      gmsh::model::mesh::generate(2);
      return extract_model(2, who);
    });
  }
  return finish_generated(std::move(ex), who);
}

HostMesh generate_sphere(const std::array<double, 3>& centre, double R, double h,
                         const std::string& region) {
  const std::string who = "sphere generator";
  check_generator_args(who, R, h);
  if (R / h > 200) throw InputError(who + ": radius / element_size is too large");
  const std::string rname = region.empty() ? std::string("body") : region;
  Extracted ex;
  {
    GmshSession session;
    ex = gmsh_call(who, "mesh the sphere", [&] {
      gmsh::model::add("sphere");
      const int v = gmsh::model::occ::addSphere(centre[0], centre[1], centre[2], R);
      gmsh::model::occ::synchronize();
      gmsh::vectorpair bnd;
      gmsh::model::getBoundary({{3, v}}, bnd, false, false, false);
      std::vector<int> surfs;
      for (const auto& [d, t] : bnd) surfs.push_back(std::abs(t));
      const int pv = gmsh::model::addPhysicalGroup(3, {v});
      gmsh::model::setPhysicalName(3, pv, rname);
      const int ps = gmsh::model::addPhysicalGroup(2, surfs);
      gmsh::model::setPhysicalName(2, ps, "surface");
      set_mesh_size(h);
      gmsh::model::mesh::generate(3);
      return extract_model(3, who);
    });
  }
  return finish_generated(std::move(ex), who);
}

}  // namespace fdem
