// libFuzzer target: mesh reader. The input is written to a temporary .msh file and read with
// read_gmsh(path, 2) and read_gmsh(path, 3). fdem::InputError is the only allowed failure.
// Gmsh (libgmsh) is not instrumented: ASan sees its heap use but not its stack/global accesses.
// Gmsh leaks on some error paths; scripts/fuzz passes tests/fuzz/lsan.supp.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/error.hpp"
#include "fuzz_common.hpp"
#include "mesh/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      fdem_fuzz::write_temp("mesh.msh", reinterpret_cast<const char*>(data), size);
  for (int dim : {2, 3}) {
    try {
      fdem::HostMesh m = fdem::read_gmsh(path, dim);
      (void)m;
    } catch (const fdem::InputError&) {
    } catch (...) {
      fdem_fuzz::unexpected(dim == 2 ? "read_gmsh(dim 2)" : "read_gmsh(dim 3)");
    }
  }
  return 0;
}
