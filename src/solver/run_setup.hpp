#pragma once
// The set-up that run_case (solver/run.cpp) and the run over several processes
// (solver/run_processes.cpp) share. Internal to src/solver.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "solver/run.hpp"
#include "solver/run_loop.hpp"

namespace fdem {

// What run_case and the run over several processes set up alike before the model is built: the
// checkpoint to go on from, the output folder, and on the process that writes (one process, or
// process 0 of several) the folder made and locked, the prepared mesh, a restart's match with the
// case and mesh, a new run's old outputs removed, the case's derived values (resolve_defaults).
struct PreparedRun {
  std::string out;                   // the output folder
  std::unique_ptr<OutputLock> lock;  // the folder is this run's until it ends
  bool restarting = false;           // RunOptions::restart given
  StateArrays restart;               // its checkpoint
  CheckpointHeader header;
  HostMesh mesh;   // over several processes on process 0 only
  HostMesh coarse;  // a refined case's coarse mesh (prepare_mesh's), where `mesh` is
  // over several processes: the parts are built locally from `coarse` (solver/local_setup.hpp;
  // process 0 decides and has no `mesh` yet, nor the defaults or the mesh's hash)
  bool local = false;
  RunIdentity id;  // (the mesh's hash on the process that writes)
  // The checkpoint the run goes on from; null: a new run.
  const StateArrays* checkpoint() const { return restarting ? &restart : nullptr; }
};

// Whether the run is over several processes (RunOptions::comm).
bool over_processes(const RunOptions& opt);

// The shared set-up (PreparedRun); over several processes every process calls it, and process 0
// alone touches the output folder and meshes the case.
PreparedRun prepare_run(const std::string& case_path, Case& c, const RunOptions& opt);

// A case's mesh as built, a refined case's coarse mesh renumbered (prepare_mesh's first phase),
// and the rest of prepare_mesh on it (warn: the mesh's warnings on stderr; false where a run
// builds the mesh again and has said them once).
HostMesh prepare_coarse(const Case& c);
HostMesh finish_mesh(const Case& c, HostMesh mesh, HostMesh* coarse = nullptr, bool warn = true);
// The regions named by "region.<name>" node sets in the boundary conditions, loads and monitors.
std::vector<std::string> region_sets_used(const Case& c);
// The hash of a mesh's coordinates and connectivity a checkpoint's header keeps: for the nodes'
// reference coordinates, the elements' and the interfaces' node numbers, each kind's rows hashed
// with their whole-mesh index and summed modulo 2^64 (ckpt::rows_hash, the checksum of a
// checkpoint's rows), so that the processes of a run whose mesh none holds get it by summing
// their own rows' (solver/local_setup.hpp); then the three sums hashed, as 16 hex digits.
struct MeshHash {
  uint64_t sums[3] = {0, 0, 0};  // nodes, elements, interfaces
  void node(long long id, const double* x, int dim);
  void elem(long long id, const int* nodes, int count);
  void iface(long long id, const int* nodes, int count);
  std::string hex() const;
};
std::string mesh_hash(const HostMesh& mesh);
// The hash checkpoints written before 2026-12-07 keep (FNV-1a over the arrays in order): a
// restart from one of them is still recognised.
std::string mesh_hash_before_2026_12_07(const HostMesh& mesh);

// A run over several processes (solver/run_processes.cpp): every process calls it.
nlohmann::json run_over_processes(const std::string& case_path, Case& c, const RunOptions& opt);

}  // namespace fdem
