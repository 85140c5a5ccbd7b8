#pragma once
// Results a person can look at: history.csv (one row per output interval), summary.json, and
// snapshots as HDF5 + XDMF that ParaView opens (deformed mesh, displacement, velocity, stress,
// interfaces with their damage).
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh/mesh.hpp"

namespace fdem {

// Creates `dir` (and parents) if needed; throws InputError if it cannot be created or written.
void ensure_output_dir(const std::string& dir);

// Writes `text` to `path` atomically (to path.tmp in the same folder, fsync, then rename): a
// reader sees the old or the new content, never part of it. Throws InputError naming the file on
// failure (full disk, unwritable folder); the old content is then left as it was.
void write_file_atomic(const std::string& path, const std::string& text);

// history.csv (and fragments.csv): header "name [unit]" columns, one row per call. Each row is
// formatted whole and written with one write(2), unbuffered, so that a killed run keeps every row
// written so far; when a write fails (full disk, file size limit) the file is cut back to its
// last complete row and InputError naming the file is thrown.
class HistoryWriter {
 public:
  HistoryWriter(const std::string& path, const std::vector<std::string>& columns);
  // Continues a history (restart): the file is rewritten atomically with the header and
  // `earlier_rows` (row-major, columns.size() values each), then appended to.
  HistoryWriter(const std::string& path, const std::vector<std::string>& columns,
                const std::vector<double>& earlier_rows);
  ~HistoryWriter();
  HistoryWriter(const HistoryWriter&) = delete;
  HistoryWriter& operator=(const HistoryWriter&) = delete;
  void row(const std::vector<double>& values);
  // One row as written to the file (%.10g, comma separated, newline).
  static std::string format_row(const std::vector<double>& values);
  const std::vector<std::string>& columns() const { return columns_; }

 private:
  // Appends `text` whole, or cuts the file back to `complete_` bytes and throws.
  void append(const std::string& text);
  int fd_ = -1;
  long long complete_ = 0;  // bytes of the file in complete lines
  std::string path_;
  std::vector<std::string> columns_;
};

// One snapshot's fields, on the host. Sizes: x, u, v: num_nodes*dim; stress: num_elems*6
// (xx, yy, zz, xy, yz, xz); damage: num_ifaces (mean over the interface's points, 1 = failed).
// Optional per-element integer field `fragment` (may be null).
struct SnapshotFrame {
  double time = 0;
  long step = 0;
  const double* x = nullptr;
  const double* u = nullptr;
  const double* v = nullptr;
  const double* stress = nullptr;
  const double* damage = nullptr;
  const int* fragment = nullptr;
};

// DIR/snapshots.h5 holds /mesh (topology, element region, interface topology = A-side nodes) and one
// group /step_NNNNNNNN per frame; DIR/snapshots.xdmf is a temporal collection with two grids per
// frame ("bulk": triangles/tetrahedra, "interfaces": polylines/triangles on the current A-side
// nodes) and is rewritten after every frame, so it is valid whenever the run stops.
class SnapshotWriter {
 public:
  SnapshotWriter(const std::string& dir, const HostMesh& mesh);
  // Continues DIR/snapshots.h5 (restart): keeps the frames `steps` (with their `times`), deletes
  // any later frame and rewrites the XDMF. When the file cannot be continued (missing, damaged,
  // another mesh, a kept frame missing) it is moved to snapshots.h5.damaged, a new file is
  // started and `note` says so (empty otherwise).
  SnapshotWriter(const std::string& dir, const HostMesh& mesh, const std::vector<long>& steps,
                 const std::vector<double>& times, std::string& note);
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;
  void write(const SnapshotFrame& frame);
  int frames() const { return static_cast<int>(times_.size()); }
  const std::vector<long>& steps() const { return steps_; }
  const std::vector<double>& times() const { return times_; }

 private:
  void write_xdmf() const;
  void create(const HostMesh& mesh);
  bool reopen(const std::vector<long>& steps, const std::vector<double>& times, std::string& why);
  std::string dir_;
  int dim_, nn_, ne_, ni_;
  long long file_ = -1;  // hid_t
  std::vector<double> times_;
  std::vector<long> steps_;
  bool has_fragment_ = false;
};

}  // namespace fdem
