#include "solver/kept_mesh.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <utility>

#include <unistd.h>

#include "common/huge_pages.hpp"
#include "parallel/decompose.hpp"

namespace fdem {

void KeptMesh::write(const HostMesh& m) {
  drop();
  const char* t = std::getenv("TMPDIR");
  std::string path = std::string(t && *t ? t : "/tmp") + "/fdem-mesh-XXXXXX";
  const int fd = mkstemp(path.data());
  if (fd >= 0) unlink(path.c_str());
  f_ = fd >= 0 ? fdopen(fd, "w+b") : nullptr;
  bytes_ = f_ ? write_mesh_file(f_, m) : -1;
  if (bytes_ < 0)
    throw std::runtime_error("cannot keep a mesh of " + std::to_string(m.num_elems()) + " elements in a temporary file in " +
                             path.substr(0, path.rfind('/')) + " " + purpose_ + ": set TMPDIR to a folder with room");
}

HostMesh KeptMesh::read() const {
  if (!f_ || std::fseek(f_, 0, SEEK_SET) != 0)
    throw std::runtime_error("cannot read back the mesh kept in a temporary file " + purpose_);
  return read_mesh_file(f_, bytes_);
}

void KeptMesh::drop() {
  if (f_) std::fclose(f_);
  f_ = nullptr;
  bytes_ = 0;
}

void PartMeshAside::set_aside() {
  if (aside_) return;
  HostMesh& m = part_.mesh;
  try {
    file_.write(m);
  } catch (const std::runtime_error& e) {  // (no room: the run goes on with the mesh in memory, as before)
    file_.drop();
    std::fprintf(stderr, "fdem: warning: %s; the part's mesh stays in memory\n", e.what());
    return;
  }
  HostMesh shell;  // the counts and names the run may still ask of it
  shell.dim = m.dim;
  shell.region_names = m.region_names;
  shell.bodies = m.bodies;
  shell.owned_nodes = m.owned_nodes;
  shell.owned_elems = m.owned_elems;
  shell.owned_ifaces = m.owned_ifaces;
  shell.bulk_elems = m.bulk_elems;
  shell.whole_set_size = m.whole_set_size;
  shell.node_sets = std::move(m.node_sets);  // (small: kept, should anything read them)
  shell.face_sets = std::move(m.face_sets);
  shell.iface_sets = std::move(m.iface_sets);
  shell.pieces = m.pieces;
  shell.whole_min_size = m.whole_min_size;
  m = std::move(shell);
  aside_ = true;
  release_free_heap();
}

void PartMeshAside::take_back() {
  if (!aside_) return;
  HostMesh back = file_.read();  // (the sets were kept: the file's are the same)
  part_.mesh = std::move(back);
  aside_ = false;
}

void PartMeshAside::forget() {
  file_.drop();
  aside_ = false;
}

}  // namespace fdem
