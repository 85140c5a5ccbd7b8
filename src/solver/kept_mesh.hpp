#pragma once
// A host mesh kept in a temporary file instead of in memory beside the model, for the moments a
// run over processes reads it again: process 0's whole mesh between the cuts of the parts anew
// (solver/run_processes.cpp); and a part's mesh let go once its run loop has read it
// (release_part_mesh): what a run over processes holds of its host meshes. The file is in TMPDIR (else /tmp) and unlinked at once, so it is
// gone when the process ends, however it ends; the mesh goes to it field by field (no second copy
// in memory: write_mesh_file, parallel/decompose.hpp).
#include <cstdio>
#include <string>
#include <utility>

#include "mesh/mesh.hpp"

namespace fdem {

struct SubMesh;

class KeptMesh {
 public:
  // purpose: what the mesh is kept for, for the messages ("for cutting the parts anew")
  explicit KeptMesh(std::string purpose) : purpose_(std::move(purpose)) {}
  KeptMesh(const KeptMesh&) = delete;
  KeptMesh& operator=(const KeptMesh&) = delete;
  ~KeptMesh() { drop(); }
  bool kept() const { return f_ != nullptr; }
  // m into the file (a new one, the old one dropped); std::runtime_error naming TMPDIR when it
  // cannot be written
  void write(const HostMesh& m);
  HostMesh read() const;  // what write wrote (std::runtime_error when it cannot be read back)
  void drop();            // the file closed (and so gone)

 private:
  std::string purpose_;
  std::FILE* f_ = nullptr;
  long bytes_ = 0;
};

// This process's part's host mesh (SubMesh::mesh) let go once its run loop has built the model
// from it and, in a run whose whole mesh no process holds, the snapshots' first frame has written
// /mesh from it: nothing reads it again (the first cut of the parts anew rebuilds the whole mesh on
// process 0 from the coarse one: solver/run_processes.cpp). About 165 B per own tetrahedron that
// the run does not hold (docs/parallel.md, "The part's mesh let go"). Its nodes, elements and
// interfaces go (its counts read 0), its names, sets and own counts stay; the freed pages go
// back to the kernel.
void release_part_mesh(SubMesh& part);

}  // namespace fdem
