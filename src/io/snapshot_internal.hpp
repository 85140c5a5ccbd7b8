#pragma once
// Internal to the snapshot writer (src/io/snapshot_writer.cpp, src/io/snapshot_xdmf.cpp): file
// names and the group name of a frame. Not a public header.
#include <cstdio>
#include <string>

namespace fdem {
namespace snapshot {

inline constexpr const char* kH5Name = "snapshots.h5";
inline constexpr const char* kXdmfName = "snapshots.xdmf";

// Group of one frame in snapshots.h5 (without the leading '/'): step_NNNNNNNN.
inline std::string step_name(long step) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "step_%08ld", step);
  return buf;
}

}  // namespace snapshot
}  // namespace fdem
