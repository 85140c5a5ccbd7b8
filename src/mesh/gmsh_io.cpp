// Gmsh-based reader (.msh 2.2/4.1 ASCII or binary, .geo meshed on the fly) and the Gmsh session
// of the unstructured generators (generate_with_gmsh; the disc and the sphere are in
// gmsh_generators.cpp). The model's mesh becomes a HostMesh in gmsh_extract.cpp.
#include <gmsh.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <mutex>
#include <new>
#include <unordered_map>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"
#include "mesh/msh_check.hpp"

namespace fdem {

namespace {

using namespace mesh_detail;

// The Gmsh API is one global state: one session at a time (run_gmsh_isolated holds the mutex),
// always finalized. Messages go to Gmsh's logger, whose "Error" lines we turn into InputError, and
// in a child process also to its terminal output, which the parent captures (see below). Gmsh 4.8 reports
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
  explicit GmshSession(bool terminal) {
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

  // Forget the messages logged so far (after a trial meshing whose errors do not count).
  static void clear_log() {
    try {
      gmsh::logger::stop();
      gmsh::logger::start();
    } catch (...) {
    }
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

// The Gmsh session's times into the set-up phases: its meshing, extraction and the rest (the
// child process, the copy of the mesh through the pipe) of `total` wall / cpu seconds.
void record_gmsh_times(const GmshTimes& t, double total_wall, double total_cpu) {
  if (t.trial[0] > 0) setup_times::add("gmsh_trial_meshes", t.trial[0], t.trial[1]);
  setup_times::add("gmsh_meshing", t.mesh[0], t.mesh[1]);
  setup_times::add("gmsh_extraction", t.extract[0], t.extract[1]);
  setup_times::add("gmsh_process", std::max(0.0, total_wall - t.trial[0] - t.mesh[0] - t.extract[0]),
                   std::max(0.0, total_cpu - t.trial[1] - t.mesh[1] - t.extract[1]));
}

// ---- Gmsh in a child process ----
// Gmsh can abort the whole process: an error thrown inside its OpenMP regions ends in
// std::terminate (a .geo surface of zero area), and an assertion or an allocation failure in a
// mesher does the same. So every Gmsh session runs in a forked child: it meshes, turns the model
// into an Extracted, and sends that (or an error message) back through a pipe; its terminal output
// (Gmsh's Info/Warning/Error lines, and what the C++ runtime prints when it aborts) goes to an
// unlinked temporary file. The parent reads the pipe, reaps the child and, if the child died,
// reports the signal with Gmsh's last messages as an InputError. The child's address space is
// capped at the memory available (memory_budget.hpp), so that a mesh too large for the machine
// stops Gmsh instead of the machine. Cost: one fork and a copy of the mesh through the pipe
// (docs/developing.md, "Refusals").

// Runs work() -> Extracted in a Gmsh session in a child process (in this process if no
// child can be made); Gmsh errors, crashes and aborts become InputError naming `source`.
template <class F>
Extracted run_gmsh_isolated(const std::string& source, const std::string& doing, F&& work) {
  std::lock_guard<std::mutex> lock(gmsh_mutex());
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = setup_times::process_cpu_seconds();
  std::fflush(nullptr);
  std::FILE* log = std::tmpfile();
  int fds[2];
  pid_t pid = -1;
  if (::pipe(fds) == 0) {
    pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
    }
  }
  if (pid < 0) {  // no child: Gmsh in this process
    if (log) std::fclose(log);
    GmshSession session(false);
    Extracted ex = work();
    record_gmsh_times(ex.times,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count(),
                      setup_times::process_cpu_seconds() - cpu0);
    return ex;
  }
  if (pid == 0) {  // the child: never returns, never runs the parent's exit handlers
    ::close(fds[0]);
    if (log) {
      ::dup2(::fileno(log), 1);
      ::dup2(::fileno(log), 2);
      std::setvbuf(stdout, nullptr, _IONBF, 0);
      std::setvbuf(stderr, nullptr, _IONBF, 0);
    }
    cap_address_space();
    std::string out;
    try {
      Extracted ex;
      {
        GmshSession session(log != nullptr);
        ex = work();
      }
      out = "M";
      pack(out, ex);
    } catch (const InputError& e) {
      out = std::string("E") + e.what();
    } catch (const std::bad_alloc&) {
      out = "E" + source + ": Gmsh ran out of memory while trying to " + doing + " (" +
            std::to_string(available_memory().bytes / 1073741824.0) + " GiB available)";
    } catch (const std::exception& e) {
      out = std::string("X") + e.what();
    } catch (...) {
      out = "Xunknown error";
    }
    write_all(fds[1], out);
    ::close(fds[1]);
    ::_exit(0);
  }
  ::close(fds[1]);
  const std::string data = read_all(fds[0]);
  ::close(fds[0]);
  int status = 0;
  rusage ru{};
  while (::wait4(pid, &status, 0, &ru) < 0 && errno == EINTR) {
  }
  const std::string excerpt = log_excerpt(log);
  if (log) std::fclose(log);
  setup_times::note_gmsh_peak(static_cast<double>(ru.ru_maxrss) * 1024.0);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && !data.empty()) {
    if (data[0] == 'E') throw InputError(data.substr(1));
    if (data[0] == 'X') throw InputError(source + ": Gmsh could not " + doing + ": " + data.substr(1));
    if (data[0] == 'M') {
      Extracted ex = unpack(data);
      record_gmsh_times(ex.times,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count(),
                        setup_times::process_cpu_seconds() - cpu0);  // the child's CPU time included
      return ex;
    }
  }
  std::string how = WIFSIGNALED(status) ? "was killed by " + signal_name(WTERMSIG(status))
                                        : "exited with status " + std::to_string(WEXITSTATUS(status));
  char mem[96];
  std::snprintf(mem, sizeof mem, " after using %.3g GiB (%.3g GiB available)",
                static_cast<double>(ru.ru_maxrss) / 1048576.0, available_memory().bytes / 1073741824.0);
  throw InputError(source + ": Gmsh failed while trying to " + doing + ": the meshing process " + how + mem +
                   (excerpt.empty() ? std::string() : "; Gmsh's last messages: " + excerpt));
}

// ---- Sizes: refuse before meshing what cannot fit, and check that Gmsh honoured the size ----

// Area (2D) or volume (3D) of the current mesh's elements of dimension dim (triangles,
// tetrahedra), or total length and count of its line elements (dim 1).
struct MeshMeasure {
  double measure = 0;
  std::size_t count = 0;
};

MeshMeasure measure_current_mesh(int dim) {
  std::vector<std::size_t> ntags;
  std::vector<double> xyz, uvw;
  gmsh::model::mesh::getNodes(ntags, xyz, uvw, -1, -1, false, false);
  std::unordered_map<std::size_t, std::size_t> at;
  for (std::size_t i = 0; i < ntags.size(); ++i) at[ntags[i]] = 3 * i;
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> etags, enodes;
  gmsh::model::mesh::getElements(types, etags, enodes, dim, -1);
  MeshMeasure mm;
  auto p = [&](std::size_t tag) { return &xyz.at(at.at(tag)); };
  for (std::size_t t = 0; t < types.size(); ++t) {
    const int npe = types[t] == 1 ? 2 : types[t] == 2 ? 3 : types[t] == 4 ? 4 : 0;
    if (npe == 0) continue;  // other element types: not counted
    const auto& nd = enodes[t];
    for (std::size_t e = 0; e + npe <= nd.size(); e += npe) {
      const double* a = p(nd[e]);
      double u[3][3] = {};
      for (int k = 1; k < npe; ++k) {
        const double* b = p(nd[e + k]);
        for (int c = 0; c < 3; ++c) u[k - 1][c] = b[c] - a[c];
      }
      const double cx = u[0][1] * u[1][2] - u[0][2] * u[1][1], cy = u[0][2] * u[1][0] - u[0][0] * u[1][2],
                   cz = u[0][0] * u[1][1] - u[0][1] * u[1][0];
      if (npe == 2) mm.measure += std::sqrt(u[0][0] * u[0][0] + u[0][1] * u[0][1] + u[0][2] * u[0][2]);
      if (npe == 3) mm.measure += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
      if (npe == 4) mm.measure += std::abs(cx * u[2][0] + cy * u[2][1] + cz * u[2][2]) / 6.0;
      ++mm.count;
    }
  }
  return mm;
}

// A trial meshing of dimension d with sizes clamped to [lmin, lmax]; errors do not count, the mesh
// and the log are cleared after it and the options restored. Returns count 0 if it failed.
MeshMeasure trial_mesh(int d, double lmin, double lmax) {
  const char* kMin = "Mesh.CharacteristicLengthMin";
  const char* kMax = "Mesh.CharacteristicLengthMax";
  double min0 = 0, max0 = 1e22, abort0 = 2;
  gmsh::option::getNumber(kMin, min0);
  gmsh::option::getNumber(kMax, max0);
  gmsh::option::getNumber("General.AbortOnError", abort0);
  MeshMeasure mm;
  try {
    gmsh::option::setNumber("General.AbortOnError", 0);  // an error is logged, not thrown
    gmsh::option::setNumber(kMin, lmin);
    gmsh::option::setNumber(kMax, lmax);
    gmsh::model::mesh::generate(d);
    if (GmshSession::first_error().empty()) mm = measure_current_mesh(d);
  } catch (...) {
    mm = MeshMeasure{};
  }
  try {
    gmsh::model::mesh::clear();
    gmsh::option::setNumber(kMin, min0);
    gmsh::option::setNumber(kMax, max0);
    gmsh::option::setNumber("General.AbortOnError", abort0);
  } catch (...) {
  }
  GmshSession::clear_log();
  return mm;
}

// Before a .geo file is meshed: its area (2D) or volume (3D) from a coarse trial mesh (the bounding
// box if that fails), its element size (mesh.element_size, or less where the file's own sizes are
// smaller: the mean segment of a trial 1D mesh, floored at 1e-5 of the model's diagonal), and from
// them the element count; InputError if that cannot fit in memory.
void refuse_oversized_geo(const std::string& path, int dim, double element_size) {
  double lo[3], hi[3];
  gmsh::model::getBoundingBox(-1, -1, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  double ext[3], diag2 = 0;
  for (int k = 0; k < 3; ++k) {
    ext[k] = hi[k] - lo[k];
    diag2 += ext[k] * ext[k];
  }
  const double diag = std::sqrt(diag2);
  if (!(diag > 0) || !std::isfinite(diag)) return;
  const double cap = max_elements(dim);
  if (!std::isfinite(cap)) return;  // unknown memory or FDEM_MEMORY_CHECK=off
  const MeshMeasure coarse = trial_mesh(dim, diag / 20, diag / 20);
  double measure = coarse.measure;
  std::string measured = "from a coarse mesh";
  if (!(coarse.count > 0 && measure > 0)) {
    // the model's bounding box (in 2D, of the two largest extents)
    double e[3] = {ext[0], ext[1], ext[2]};
    std::sort(e, e + 3);
    measure = dim == 2 ? e[2] * e[1] : e[2] * e[1] * e[0];
    measured = "of the bounding box";
  }
  const std::string unit = dim == 2 ? " m^2" : " m^3";
  const std::string what = (dim == 2 ? "area " : "volume ") + fmt(measure) + unit + " " + measured;
  if (element_size > 0)  // at least this many: the file's own sizes can only be smaller
    check_fits_in_memory(estimate_gmsh_elements(dim, measure, element_size), dim,
                         "mesh.element_size = " + fmt(element_size) + " m for " + path + " (" + what + ")",
                         element_size);
  const double floor = diag * 1e-5;
  const MeshMeasure lines = trial_mesh(1, floor, element_size > 0 ? std::max(element_size, floor) : 1e22);
  if (lines.count == 0) return;
  const double mean = lines.measure / static_cast<double>(lines.count);
  if (element_size > 0 && mean >= element_size) return;  // checked above
  const bool floored = mean <= 1.01 * floor;             // the file's sizes may be smaller still
  check_fits_in_memory(estimate_gmsh_elements(dim, measure, mean), dim,
                       "the element sizes set in " + path + " (mean segment " + (floored ? "<= " : "") +
                           fmt(mean) + " m along its curves; " + what + ")");
}

// Gmsh does not always honour a size (4.8 counts a curve's segments in an int: above 2^31 the
// curve gets one segment); a mesh whose mean edge is over twice the asked size is refused.
void check_size_honoured(const HostMesh& m, const std::string& source, double h) {
  const int npe = m.dim + 1, ne = m.num_elems();
  double sum = 0;
  std::size_t n = 0;
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a)
      for (int b = a + 1; b < npe; ++b) {
        const int p = m.elems[static_cast<std::size_t>(e) * npe + a];
        const int q = m.elems[static_cast<std::size_t>(e) * npe + b];
        double d2 = 0;
        for (int k = 0; k < m.dim; ++k) {
          const double d =
              m.X[static_cast<std::size_t>(p) * m.dim + k] - m.X[static_cast<std::size_t>(q) * m.dim + k];
          d2 += d * d;
        }
        sum += std::sqrt(d2);
        ++n;
      }
  const double mean = n ? sum / static_cast<double>(n) : 0.0;
  if (mean > 2 * h)
    throw InputError(source + ": Gmsh did not honour mesh.element_size = " + fmt(h) + " m: its mesh has " +
                     std::to_string(ne) + " elements with a mean edge of " + fmt(mean) +
                     " m; give a larger mesh.element_size (Gmsh gives a curve one segment when it "
                     "would need more than 2^31)");
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

void set_mesh_size(double h, int algorithm3d) {
  gmsh::option::setNumber("Mesh.CharacteristicLengthMin", 0.0);
  gmsh::option::setNumber("Mesh.CharacteristicLengthMax", h);
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
