// The Gmsh session (GmshSession, gmsh_internal.hpp: Gmsh initialized, its logger, always
// finalized; its errors turned into InputError) and what runs in it: the reader of .msh files
// (2.2/4.1 ASCII or binary) and .geo files meshed on the fly (read_gmsh), and the meshing of the
// unstructured generators (generate_with_gmsh; the disc and the sphere are in gmsh_generators.cpp).
// Each session runs in a child process (gmsh_child.cpp); the size checks and trial meshes are in
// gmsh_sizes.cpp; the model's mesh becomes a HostMesh in gmsh_extract.cpp.
#include <gmsh.h>

#include <cctype>
#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "mesh/gmsh_internal.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"
#include "mesh/msh_check.hpp"

namespace fdem {

namespace mesh_detail {

// The Gmsh API is one global state: one session at a time (run_gmsh_isolated, gmsh_child.cpp, holds
// a mutex), always finalized. Messages go to Gmsh's logger, whose "Error" lines we turn into
// InputError, and in a child process also to its terminal output, which the parent captures
// (gmsh_child.cpp). Gmsh 4.8 reports errors by throwing std::string (newer versions throw
// std::exception) when General.AbortOnError is 2 (the API default). While the .geo/.msh parser runs
// we set it to 0: an exception thrown from inside Gmsh's parser leaves the parser's global state
// broken for the rest of the process (every later .geo then fails with bogus syntax errors), so we
// let it finish and read the log instead.
GmshSession::GmshSession(bool terminal) {
  gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
  try {
    gmsh::option::setNumber("General.Terminal", terminal ? 1 : 0);
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::logger::start();
  } catch (...) {
    finish();
    throw;
  }
}

GmshSession::~GmshSession() { finish(); }

std::string GmshSession::first_error() {
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

void GmshSession::clear_log() {
  try {
    gmsh::logger::stop();
    gmsh::logger::start();
  } catch (...) {
  }
}

void GmshSession::finish() {
  try {
    gmsh::logger::stop();
  } catch (...) {
  }
  try {
    gmsh::finalize();
  } catch (...) {
  }
}

}  // namespace mesh_detail

namespace {

using namespace mesh_detail;

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

// Wall and CPU seconds of f() added to `into` (GmshTimes).
template <class F>
auto timed(double (&into)[2], F&& f) -> decltype(f()) {
  struct Add {
    double (&into)[2];
    std::chrono::steady_clock::time_point w0 = std::chrono::steady_clock::now();
    double c0 = setup_times::process_cpu_seconds();
    ~Add() {
      into[0] += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
      into[1] += setup_times::process_cpu_seconds() - c0;
    }
  } add{into};
  return f();
}

}  // namespace

HostMesh read_gmsh(const std::string& path, int dim, double element_size) {
  if (dim != 2 && dim != 3)
    throw InputError(path + ": mesh dimension must be 2 or 3 (got " + std::to_string(dim) + ")");
  {
    std::error_code ec;
    if (path.empty()) throw InputError("mesh file name is empty");
    if (!std::filesystem::exists(path, ec)) throw InputError(path + ": mesh file not found");
    if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a mesh file");
    if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": is not a regular file");
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
  Extracted ex = run_gmsh_isolated(path, geo ? "mesh the geometry" : "read the file", [&] {
    gmsh_call(path, "read the file", [&] {
      gmsh::option::setNumber("General.AbortOnError", 0);
      gmsh::open(path);
      gmsh::option::setNumber("General.AbortOnError", 2);
    });
    std::string err = GmshSession::first_error();
    if (!err.empty()) throw InputError(path + ": Gmsh could not read the file: " + err);
    GmshTimes t;
    if (geo) {
      timed(t.trial, [&] { refuse_oversized_geo(path, dim, element_size); });
      if (element_size > 0) {  // an upper bound on the element size, over the file's own sizes
        gmsh::option::setNumber("Mesh.CharacteristicLengthMin", 0.0);
        gmsh::option::setNumber("Mesh.CharacteristicLengthMax", element_size);
      }
      timed(t.mesh, [&] { gmsh_call(path, "mesh the geometry", [&] { gmsh::model::mesh::generate(dim); }); });
      err = GmshSession::first_error();
      if (!err.empty()) throw InputError(path + ": Gmsh could not mesh the geometry: " + err);
    }
    Extracted ex = timed(t.extract, [&] {
      return gmsh_call(path, "extract the mesh", [&] { return extract_model(dim, path); });
    });
    ex.times = t;
    return ex;
  });
  if (geo && element_size > 0) check_size_honoured(ex.mesh, path, element_size);
  check_elements_impl(ex.mesh, path, &ex.elem_tags);
  return std::move(ex.mesh);
}

namespace {

// The element size is h alone, whatever else the session holds. The generators set no size on
// their points, and Gmsh gives such a point a tenth of the session's bounding-box diagonal when
// sizes come from points: finer than h for a model under 10 h across (a particle meshed alone
// in its batch had elements 1.8 times finer than one meshed with others), so sizes from points
// are off. Curvature sizes are off as well; the size spreads from the boundary into the volume.
void set_mesh_size(double h, int algorithm3d) {
  gmsh::option::setNumber("Mesh.CharacteristicLengthMin", 0.0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthMax", h);
  gmsh::option::setNumber("Mesh.CharacteristicLengthFromPoints", 0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthFromCurvature", 0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthExtendFromBoundary", 1);
  // Delaunay: less regular than Frontal-Delaunay, whose rows of nearly aligned edges steer cracks
  // (Brazilian disc: the split followed the mesh rows, off the loaded diameter).
  gmsh::option::setNumber("Mesh.Algorithm", 5);
  gmsh::option::setNumber("Mesh.Algorithm3D", algorithm3d);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::option::setNumber("Mesh.Optimize", 1);
}

}  // namespace

namespace mesh_detail {

HostMesh generate_with_gmsh(const std::string& who, const std::string& doing, int dim, double h,
                            int algorithm3d, const std::function<void()>& build) {
  Extracted ex = run_gmsh_isolated(who, doing, [&] {
    return gmsh_call(who, doing, [&] {
      build();
      set_mesh_size(h, algorithm3d);
      GmshTimes t;
      timed(t.mesh, [&] { gmsh::model::mesh::generate(dim); });
      Extracted e = timed(t.extract, [&] { return extract_model(dim, who); });
      e.times = t;
      return e;
    });
  });
  check_size_honoured(ex.mesh, who, h);
  orient_positively(ex.mesh);
  check_elements_impl(ex.mesh, who, nullptr);
  return std::move(ex.mesh);
}

}  // namespace mesh_detail

}  // namespace fdem