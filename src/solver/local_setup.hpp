#pragma once
// The local set-up of a refined run over processes (docs/parallel.md, "The local set-up"): process 0
// meshes the coarse mesh only and partitions it; every process refines its own coarse elements and
// a halo and cuts its part out (local_part, src/parallel/local_part.hpp); the whole mesh's facts
// are summed over the processes; the exchange lists come from the processes' requests. The parts
// are decompose()'s parts of the whole refined mesh, so the run is the one the whole set-up gives,
// to the bit. Process 0 then gathers the whole mesh from the parts for what it still needs it for
// (the snapshots' /mesh group, the summary's mesh report, the cuts of the parts anew during the
// run): it no longer refines, inserts or decomposes it. Internal to src/solver.
#include <string>
#include <vector>

#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"

namespace fdem {

class Comm;

// Why a run over processes cannot set up locally ("" when it can): a case that is not refined, a
// region that is not fracturable or a surface cut, a jitter (drawn over the whole mesh), a restart,
// or FDEM_WHOLE_SETUP=1 (the measurement switch: the whole mesh on process 0, as before).
std::string local_setup_refusal(const Case& c, const HostMesh& coarse, bool restarting);

struct LocalSetup {
  SubMesh part;             // this process's, with its exchange lists
  double mean_size = 0;     // what the case's defaults derive from (mean_element_size's)
  double reach = 0;         // the contact zones' reach (0: no contact)
  std::vector<int> elem_part;  // process 0: every fine element's part
  HostMesh whole;           // process 0: the whole mesh, gathered from the parts
};

// Collective. coarse: process 0's (prepare_coarse's, checked); the others' is ignored. Resolves
// the case's defaults (resolve_defaults) on every process.
LocalSetup local_setup(Case& c, const Comm& comm, const HostMesh& coarse, PartitionMethod method,
                       const std::vector<std::string>& region_sets);

}  // namespace fdem
