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
struct StateArrays;
class Comm;

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
  // bisection) and sends each process its part (src/parallel/decompose.hpp); each runs its part
  // and process 0 writes the outputs (docs/parallel.md: what such a run does not do yet is refused
  // with the key to change).
  std::shared_ptr<const Comm> comm;
  // Set by run_case over several processes with contact (solver/run.cpp): where the run loop leaves
  // the whole state when the parts are to be cut anew (Simulation::recut_due), the cuts so far, and
  // the checkpoint the run first went on from (null: none).
  StateArrays* recut = nullptr;
  int recuts = 0;
  // Of those cuts, the ones the balance asked for (Simulation::recut_reason "work"), the excess of the
  // most loaded process's work over the mean that asked for each, and the excess at the first
  // check after each cut (docs/parallel.md "Rebalancing"); and on process 0 each element's part at
  // the last cut (a checkpoint holds it: a restart on as many processes cuts its parts the same).
  int rebalances = 0;
  std::vector<double> excess_at_rebalances, excess_after_cuts;
  double excess_largest = 0;
  std::string last_cut_reason;  // for the progress note of the cut
  // Each cut of this invocation: why ("work", "zones", "test"; Simulation::recut_reason) and, on
  // process 0, how many elements changed process; and the elements moved by all the run's cuts
  // (a checkpoint holds it).
  std::vector<std::string> cut_reasons;
  std::vector<long long> elements_moved_at_cuts;
  long long elements_moved = 0;
  // This process's time in the loop outside the exchange (which includes waiting for the others)
  // in the parts before the last cut: the measured side of the balance.
  double busy_seconds = 0;
  // The wall time of the cuts so far (process 0's; the others wait for it): the whole state
  // gathered, the partition, the parts and state sent, the new parts set up and checked.
  double cut_seconds = 0;
  std::vector<int> cut_parts;
  const StateArrays* restarted = nullptr;
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
// element centroids), interfaces inserted. Throws InputError. Also used by `fdem partition`.
HostMesh prepare_mesh(const Case& c);

}  // namespace fdem
