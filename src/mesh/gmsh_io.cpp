// Gmsh-based reader (.msh 2.2/4.1 ASCII or binary, .geo meshed on the fly) and the unstructured
// generators (disc, sphere) through the Gmsh C++ API. The model's mesh becomes a HostMesh in
// gmsh_extract.cpp.
#include <gmsh.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>

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
