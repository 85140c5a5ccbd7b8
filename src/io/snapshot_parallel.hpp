#pragma once
// One snapshot frame of a run over several processes written by every process into the one
// snapshots.h5 (an MPI build with the parallel HDF5; docs/parallel.md, "Output"): the frame's group
// and datasets are created by all processes together, then each process writes its own items' rows
// at their rows in the whole mesh, in one collective write per dataset. The file's layout is the
// one SnapshotWriter writes (src/io/output.hpp): ParaView, h5py and a restart see no difference,
// and no process holds a whole frame. The group /mesh and snapshots.xdmf stay process 0's
// (SnapshotWriter). Host only.
#include <cstddef>
#include <string>

namespace fdem {

// A process's part of one frame. Rows of the own items: ids[i] is the whole mesh's index of local
// row i (i < count).
struct FramePart {
  double time = 0;
  long step = 0;
  int dim = 3;
  long long whole_nodes = 0, whole_elems = 0, whole_ifaces = 0;
  const int* node_ids = nullptr;
  const int* elem_ids = nullptr;
  const int* iface_ids = nullptr;
  size_t nodes = 0, elems = 0, ifaces = 0;
  const double* x = nullptr;       // nodes x dim: current positions
  const double* u = nullptr;       // nodes x dim
  const double* v = nullptr;       // nodes x dim
  const double* stress = nullptr;  // elems x 6 (xx, yy, zz, xy, yz, xz)
  const double* damage = nullptr;  // ifaces
  bool has_fragment = false;       // the same on every process
  const int* fragment = nullptr;   // elems: the own elements' fragment ids
};

// The frames of a run over several processes: an MPI-IO access property list
// (Comm::h5_parallel_access), owned, and the file, opened on every process at the first frame and
// kept open (flushed after every frame, as SnapshotWriter does) until the destructor, which is
// collective too.
class ParallelFrames {
 public:
  explicit ParallelFrames(long long fapl);
  ~ParallelFrames();
  ParallelFrames(const ParallelFrames&) = delete;
  ParallelFrames& operator=(const ParallelFrames&) = delete;
  // Collective: every process calls it with its part (the same `dir` every time). DIR/snapshots.h5
  // must exist with its /mesh and be closed everywhere else. Throws InputError naming the file on
  // an HDF5 error (the run's main then ends every process).
  void write(const std::string& dir, const FramePart& part) const;

 private:
  long long fapl_;
  mutable long long file_ = -1;
};

}  // namespace fdem
