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

// The rows a process writes: its own items', ids[i] the whole mesh's index of local row i (i < count).
struct OwnRows {
  int dim = 3;
  long long whole_nodes = 0, whole_elems = 0, whole_ifaces = 0;
  const int* node_ids = nullptr;
  const int* elem_ids = nullptr;
  const int* iface_ids = nullptr;
  size_t nodes = 0, elems = 0, ifaces = 0;
};

// A process's part of one frame.
struct FramePart : OwnRows {
  double time = 0;
  long step = 0;
  const double* x = nullptr;       // nodes x dim: current positions
  const double* u = nullptr;       // nodes x dim
  const double* v = nullptr;       // nodes x dim
  const double* stress = nullptr;  // elems x 6 (xx, yy, zz, xy, yz, xz)
  const double* damage = nullptr;  // ifaces
  bool has_fragment = false;       // the same on every process
  const int* fragment = nullptr;   // elems: the own elements' fragment ids
};

// A process's rows of the group /mesh (the datasets SnapshotWriter writes from a whole mesh), for
// a run whose whole mesh no process holds (src/solver/local_setup.hpp); node numbers are the whole
// mesh's.
struct MeshPart : OwnRows {
  const double* X = nullptr;        // nodes x dim: reference coordinates
  const int* elements = nullptr;    // elems x (dim + 1): whole node numbers
  const int* region = nullptr;      // elems
  const int* interfaces = nullptr;  // ifaces x dim: side A's whole node numbers
  bool with_material = false;       // /mesh/interface_material (the same on every process)
  const int* material = nullptr;    // ifaces
  bool with_strength = false;       // /mesh/strength_factor (the same on every process)
  const double* strength = nullptr; // ifaces
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
  // Collective, before the first frame: the datasets of /mesh from every process's rows (the
  // group, its sizes and names written by process 0's SnapshotWriter shell, closed).
  void write_mesh(const std::string& dir, const MeshPart& part) const;

 private:
  long long open(const std::string& path) const;
  long long fapl_;
  mutable long long file_ = -1;
};

}  // namespace fdem
