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

// The files fdem writes into an output folder, with the temporary names they are written under
// before a rename: case.json (src/solver/run.cpp), summary.json and checkpoint.h5
// (src/solver/run_loop.cpp, src/io/checkpoint.cpp), history.csv (src/solver/history_table.cpp),
// fragments.csv (src/solver/run_output.cpp), snapshots.h5 (+ .damaged) and snapshots.xdmf
// (src/io/snapshot_writer.cpp, src/io/snapshot_xdmf.cpp). The lock file (OutputLock) is not one
// of them: it stays.
const std::vector<std::string>& output_file_names();

// A fresh run's output folder holds only its own results: removes from `dir` the regular files
// named in output_file_names() (symbolic links and anything else are left alone). Returns the
// names removed; throws InputError naming the file if one cannot be removed.
std::vector<std::string> remove_old_outputs(const std::string& dir);

// Throws InputError when a file fdem writes into `dir` (output_file_names()) is one of `inputs`
// (the same file: std::filesystem::equivalent), e.g. `fdem run case.json --out .` in the case's
// folder, where the resolved case.json would replace the case file.
void refuse_inputs_among_outputs(const std::string& dir, const std::vector<std::string>& inputs);

// An output folder belongs to one run at a time: holds an exclusive flock(2) on DIR/.fdem.lock
// (which holds the pid of the run) for its lifetime. The kernel drops the lock when the process
// ends, however it ends, so a killed run leaves no stale lock. Throws InputError naming the
// folder and the holder's pid when another process holds it.
class OutputLock {
 public:
  explicit OutputLock(const std::string& dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;
  static constexpr const char* kName = ".fdem.lock";

 private:
  int fd_ = -1;
};

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
// What /mesh holds before its datasets: a run over processes whose mesh no process holds
// (src/solver/local_setup.hpp) writes them later, from every process's rows.
struct MeshShell {
  int dim = 3;
  long nodes = 0, elems = 0, ifaces = 0;
  std::vector<std::string> region_names;
};

class SnapshotWriter {
 public:
  SnapshotWriter(const std::string& dir, const HostMesh& mesh);
  // A new file whose /mesh holds the shell's sizes and region names only: its datasets come from
  // write_mesh (a mesh gathered on this process) or from every process's rows
  // (ParallelFrames::write_mesh, src/io/snapshot_parallel.hpp, after close_file), before the first frame.
  explicit SnapshotWriter(const std::string& dir, const MeshShell& shell);
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
  // Static per-interface fields of a run with interface materials by place or a strength scatter
  // (docs/case-format.md, "fracture"): /mesh/interface_material (index into `names`, written as
  // /mesh/interface_material_names) and, if not empty, /mesh/strength_factor; shown on the
  // "interfaces" grid of every frame. Kept when the file already has them (restart).
  void add_interface_fields(const std::vector<std::string>& names, const std::vector<int>& material,
                            const std::vector<float>& strength);
  // A shell's datasets from the whole mesh (then as the first constructor's file).
  void write_mesh(const HostMesh& mesh);
  // A shell whose interface fields every process writes its rows of (ParallelFrames::write_mesh):
  // /mesh/interface_material_names here, and the frames' XDMF shows the fields.
  void interface_fields_by_rows(const std::vector<std::string>& names, bool strength);
  // A run over several processes that writes its frames with ParallelFrames
  // (src/io/snapshot_parallel.hpp): closes this handle (every frame opens the file on every
  // process), then counts each frame written there and rewrites the XDMF.
  void close_file();
  void frame_written(double time, long step, bool fragment);
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
  std::vector<char> fragment_;     // per frame: whether it has /fragment
  bool imat_ = false, istrength_ = false;  // /mesh/interface_material, /mesh/strength_factor
  bool shell_ = false;                     // /mesh without its datasets yet
};

}  // namespace fdem
