#pragma once
// Declarations shared by the Gmsh files of the mesh module (not part of its public interface): the
// Gmsh session (gmsh_io.cpp), a session in a child process (gmsh_child.cpp) and the size checks
// around the meshing (gmsh_sizes.cpp). What the other mesh files share is in mesh_internal.hpp.
#include <functional>
#include <string>

#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::mesh_detail {

// One Gmsh session (gmsh_io.cpp): Gmsh initialized with its logger started, always finalized. Gmsh
// is one global state: one session at a time (run_gmsh_isolated holds a mutex while it runs one).
class GmshSession {
 public:
  // `terminal`: Gmsh's messages also to the terminal output (in a child process, which the parent
  // captures).
  explicit GmshSession(bool terminal);
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  // First error Gmsh logged so far in this session ("" if none), without the "Error: " prefix.
  static std::string first_error();
  // Forget the messages logged so far (after a trial meshing whose errors do not count).
  static void clear_log();

 private:
  static void finish();
};

// Runs work() -> Extracted in a Gmsh session in a child process (gmsh_child.cpp; in this process if
// no child can be made); Gmsh errors, crashes and aborts become InputError naming `source` ("Gmsh
// could not <doing>"). Adds the session's times to the set-up phases (setup_times.hpp).
Extracted run_gmsh_isolated(const std::string& source, const std::string& doing,
                            const std::function<Extracted()>& work);

// The size checks (gmsh_sizes.cpp). Inside a Gmsh session, before a .geo file is meshed: InputError
// if the mesh it would give (its area or volume from a coarse trial mesh, its element size from
// mesh.element_size or a trial 1D mesh) cannot fit in memory.
void refuse_oversized_geo(const std::string& path, int dim, double element_size);
// After meshing: InputError if the mesh's mean edge is over twice the asked size `h`.
void check_size_honoured(const HostMesh& m, const std::string& source, double h);

}  // namespace fdem::mesh_detail
