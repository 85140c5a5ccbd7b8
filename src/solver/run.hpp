#pragma once
// Host orchestration of a run: case -> mesh -> interfaces -> device model -> time loop -> output.
#include <csignal>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fdem {

struct Case;
struct HostMesh;
class Comm;
enum class PartitionMethod;

// What the user sets for a run (the command line's options). The state of the run itself (the
// cuts of the parts anew over several processes: CutHistory, solver/run_state.hpp) is the run's.
struct RunOptions {
  std::string out_dir;                // default: ./out/<case name>
  std::vector<std::string> overrides;  // --set key.path=value
  bool progress = true;               // progress line on a terminal / periodic lines in logs
  double checkpoint_every = -1;       // s of simulated time; < 0: the case's output.checkpoint_every
  std::string restart;                // checkpoint to go on from (same case and --set options)
  // Set (to the signal's number) by a signal handler to stop the run: the loop reads it once per
  // step on the host; the run then ends after the step with a checkpoint and summary.json (stop
  // reason "interrupted", "signal" the number). Null: not watched.
  const volatile std::sig_atomic_t* interrupt = nullptr;
  // The processes of a run under mpirun (an MPI build's main sets it; src/parallel/comm.hpp).
  // With more than one, process 0 meshes the case, partitions it (METIS, else coordinate
  // bisection) and sends each process its part (src/parallel/decompose.hpp), or for a refined case
  // each process builds its own from the coarse mesh (src/solver/local_setup.hpp); each runs its part
  // and process 0 writes the outputs (docs/parallel.md: what such a run does not do yet is refused
  // with the key to change).
  std::shared_ptr<const Comm> comm;
};

// Runs a case; returns the summary written to out_dir/summary.json. Throws InputError (bad input,
// a restart file that is missing, damaged or of another case, an output file that cannot be
// written) or NumericalError (instability), both with a clear message.
// With a checkpoint interval the run writes out_dir/checkpoint.h5 (atomically) every that much
// simulated time; with `restart` it goes on from such a file: history.csv and fragments.csv keep
// the rows up to the checkpoint (rewritten from the checkpoint), snapshots.h5 keeps the frames up
// to it, and the run gives the same results and files as one that did not stop.
nlohmann::json run_case(const std::string& case_path, const RunOptions& opt);

// Validates a case file and its mesh without running it; returns a short report (counts, mesh
// quality, stable time step). Throws InputError.
nlohmann::json check_case(const std::string& case_path, const std::vector<std::string>& overrides,
                          bool moduli = false);

// Mesh of a case, ready for the solver: built or read, checked, renumbered (Morton order of the
// element centroids; a refined mesh: the coarse mesh's, each coarse element's children together),
// interfaces inserted. Throws InputError. Also used by `fdem partition`. coarse (a refined case):
// the coarse mesh as it was refined (renumbered), for what is computed from it alone.
HostMesh prepare_mesh(const Case& c, HostMesh* coarse = nullptr);
// The elements of prepare_mesh's mesh come in groups of this many consecutive ones, each a coarse
// element's children (mesh.refine, src/mesh/refine.hpp; 1: no refinement): a partition keeps
// them together (partition_elements' group).
int refined_group(const Case& c);
// The mean element size a case's defaults derive from (resolve_defaults): mesh_quality's, or for
// a refined case refined_mean_size (src/mesh/refine.hpp), which the processes of a run that refine
// only their own coarse elements compute to the same bits.
double mean_element_size(const Case& c, const HostMesh& mesh);
// A refined case's partition into `parts` computed from its coarse mesh (partition_coarse,
// src/parallel/partition.hpp), one part id per fine element (each coarse element's children
// together): what a run over processes and `fdem partition` use, and what a process that refines
// only its own coarse elements computes alike.
std::vector<int> refined_partition(const Case& c, const HostMesh& coarse, int parts, PartitionMethod method);

}  // namespace fdem
