#pragma once
// The whole run's state over several processes (docs/parallel.md, "Checkpoints"): what a
// checkpoint of a run over processes holds and what a cut of the parts anew moves, gathered from
// the parts and given back to them. The run over processes calls these (solver/run_parts.hpp); a
// run on one process saves and loads its Simulation's state as it is. Every function is
// collective: every process calls it at the same step.
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "solver/simulation.hpp"

namespace fdem {

// The checkpoint state of the whole run in the whole mesh's order, as one process would write
// it, on process 0 (the others' `whole` stays empty): the owners' rows of every per-node and
// per-interface entry, the sums of the per-process accumulators (and each process's own values
// under "processes/", so that a restart on as many processes goes on to the bit). With `rows`, the
// per-node and per-interface entries are not gathered: each process gets its own rows of them
// there, for every process to write its own (write_checkpoint_rows, src/io/checkpoint.hpp);
// process 0's `whole` holds the rest.
template <int D>
void save_whole_state(const Simulation<D>& sim, StateArrays& whole, std::vector<RowPart>* rows = nullptr);

// Takes such a state (or one process's checkpoint) on any number of processes: each picks the rows
// of its own and ghost items; the accumulators go back to their processes, or all to process 0 on
// another count. Of a checkpoint written by rows each process reads and verifies its own rows; of
// a state marked by PartRows::mark (a cut's, on a process other than 0) it takes the rows as they are.
template <int D>
void load_whole_state(Simulation<D>& sim, const StateArrays& whole);

// A part's rows of a whole state (a cut's, as each entry arrives: solver/run_processes.cpp), so
// that a process other than 0 need not hold the whole state: keep() cuts each per-node and
// per-interface entry to the rows of the part's local nodes or interfaces (node_global,
// iface_global: local -> whole index), in their local order, and leaves the other entries; mark()
// then tells load_whole_state that the rows are the part's already.
struct PartRows {
  int dim = 0;
  const std::vector<int>* node_global = nullptr;
  const std::vector<int>* iface_global = nullptr;
  long whole_nodes = 0, whole_ifaces = 0;
  void keep(const std::string& name, std::vector<double>& v) const;
  void keep(const std::string& name, std::vector<long long>& v) const;
  static void mark(StateArrays& s);
};

// The mass and momentum summed over every process's own nodes, and the sum of m |v_k| (the scale
// of the momentum's round-off): 5 values (a 2D run's third momentum component 0).
template <int D>
std::vector<double> whole_mass_momentum(const Simulation<D>& sim);

// Right after load_whole_state at a cut: every node, element and interface owned by one process,
// and the whole state gathered again must be `given` (every node's position and velocity, every
// interface's history and handover flag, every contact pair with a history: nothing lost, nothing
// twice); process 0 throws std::logic_error naming what differs.
template <int D>
void check_whole_state(const Simulation<D>& sim, const StateArrays& given);

}  // namespace fdem
