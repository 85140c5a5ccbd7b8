#include "solver/kept_mesh.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <utility>
#include <vector>

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

void release_part_mesh(SubMesh& part) {
  HostMesh& m = part.mesh;
  std::vector<double>().swap(m.X);
  for (std::vector<int>* v : {&m.elems, &m.elem_region, &m.ifaces, &m.iface_elems, &m.node_origin, &m.outer_faces,
                              &m.iface_ids})
    std::vector<int>().swap(*v);
  release_free_heap();
}

}  // namespace fdem
