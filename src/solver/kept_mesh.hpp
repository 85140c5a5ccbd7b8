#pragma once
// A host mesh kept in a temporary file instead of in memory beside the model, for the moments a
// run over processes reads it again: process 0's whole mesh between the cuts of the parts anew
// (solver/run_processes.cpp), and each process's part's mesh between its set-up and the next time
// it is read (PartMeshAside). The file is in TMPDIR (else /tmp) and unlinked at once, so it is
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

// This process's part's host mesh (SubMesh::mesh) set aside in a KeptMesh between the set-up of
// its run loop, which builds the model from it, and the next time it is read: the snapshots'
// first frame of a run whose whole mesh no process holds (its /mesh) and the first cut of the
// parts anew (which gathers the whole mesh from the parts). About 165 B per own tetrahedron that
// the run does not hold meanwhile at 1e7 (docs/parallel.md, "The part's mesh set aside"). While it
// is aside the part's mesh holds its counts, names and sets only (no nodes, elements or interfaces).
class PartMeshAside {
 public:
  explicit PartMeshAside(SubMesh& part) : part_(part), file_("for the part's mesh until it is read again") {}
  bool aside() const { return aside_; }
  // (its pages given back to the kernel; where the file cannot be written, a warning and the mesh
  // stays in memory)
  void set_aside();
  void take_back();  // (nothing when it is not aside)
  // The part was replaced by another (a cut's, a set-up's): nothing of the old one is taken back.
  void forget();

 private:
  SubMesh& part_;
  KeptMesh file_;
  bool aside_ = false;
};

}  // namespace fdem
