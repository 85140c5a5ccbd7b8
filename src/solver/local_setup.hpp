#pragma once
// The local set-up of a refined run over processes (docs/parallel.md, "The local set-up"): process 0
// meshes the coarse mesh only and partitions it; every process refines its own coarse elements and
// a halo and cuts its part out (local_part, src/parallel/local_part.hpp); the whole mesh's facts
// are summed over the processes; the exchange lists come from the processes' requests. The parts
// are decompose()'s parts of the whole refined mesh, so the run is the one the whole set-up gives,
// to the bit. No process holds the whole fine mesh: what the run reports of it (the checkpoints'
// mesh hash, summary.json's mesh report, the unused material rules) is summed over the processes'
// own rows, and the snapshots' /mesh is written by every process's rows (RunSnapshots). Only a cut
// of the parts anew during the run (or snapshots without the parallel HDF5) gathers it on process
// 0 (gather_whole_mesh), when it comes. Internal to src/solver.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/run_setup.hpp"

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
  std::vector<int> elem_part;  // process 0 with contact: every fine element's part (the cuts')
  // The whole mesh's, summed over the processes (every process the same): the checkpoints' mesh
  // hash (mesh_hash of the whole mesh), summary.json's mesh report (mesh_report's keys; the mean
  // edge summed part by part) and the material rules that apply to no interface (warnings: on
  // process 0's stderr and in the report).
  std::string mesh_hash;
  nlohmann::json mesh_report;
};

// Collective. coarse: process 0's (prepare_coarse's, checked); the others' is ignored. Resolves
// the case's defaults (resolve_defaults) on every process.
LocalSetup local_setup(Case& c, const Comm& comm, const HostMesh& coarse, PartitionMethod method,
                       const std::vector<std::string>& region_sets);

// The hash of a part's own rows (MeshHash, solver/run_setup.hpp): the parts' sums add up to the
// whole mesh's mesh_hash (modulo 2^64).
MeshHash own_rows_hash(const SubMesh& s);

// Collective: the whole mesh on process 0 from every process's own rows of its part (any part with
// global ids: nodes' positions and origins, elements' nodes and regions, counted interfaces' nodes
// and elements, the node sets' own nodes), in the whole mesh's numbering, as the whole set-up makes
// it (its face sets aside, which nothing after the insertion reads); empty on the others.
HostMesh gather_whole_mesh(const Comm& comm, const SubMesh& s);

}  // namespace fdem
