#pragma once
// Checkpoint files (HDF5): the complete state of a run, so that `fdem run --restart FILE` goes on
// exactly as if the run had not stopped. The solver puts its state into a StateArrays (named flat
// arrays of doubles, integers and strings); this file writes and reads them, atomically.
//
// checkpoint.h5 layout:
//   /  attributes: format = "fdem checkpoint", version (int32), dimension, num_nodes, num_elements,
//      num_interfaces (int64), case_hash, mesh_hash (strings, 16 hex digits), time (float64),
//      step (int64), checksum (string: FNV-1a 64 of the header values and of every dataset's name
//      and checksum, in name order)
//   one dataset per state entry, at its name ("model/x", "contact/pair_fn", "run/next_history",
//   ...): float64 or int64, one-dimensional; strings as fixed-length string scalars. Each has the
//   attribute checksum (FNV-1a 64 of its values' bytes, 16 hex digits), or, when every process of
//   a run wrote its rows, the checksum of the rows with their width in checksum_rows (version 4).
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace fdem {

struct StateArrays {
  std::map<std::string, std::vector<double>> f64;
  std::map<std::string, std::vector<long long>> i64;
  std::map<std::string, std::string> str;

  void put(const std::string& name, double v) { f64[name] = {v}; }
  void put_int(const std::string& name, long long v) { i64[name] = {v}; }
  // Read back; throw InputError naming `file` when the entry is missing or has another size
  // (expected < 0: any size).
  double get(const std::string& name) const;
  long long get_int(const std::string& name) const;
  const std::vector<double>& array(const std::string& name, long long expected = -1) const;
  const std::vector<long long>& int_array(const std::string& name, long long expected = -1) const;
  const std::string& string(const std::string& name) const;
  bool has(const std::string& name) const {
    return f64.count(name) || i64.count(name) || str.count(name);
  }

  std::string file;  // for messages
  // read_checkpoint(..., skip_rows = true): the entries written by rows, left in the file (their
  // stored checksums; read_rows reads a process's rows of them)
  std::map<std::string, std::string> by_rows;
};

struct CheckpointHeader {
  int dim = 0;
  long long nodes = 0, elements = 0, interfaces = 0;
  std::string case_hash, mesh_hash;
  double time = 0;
  long long step = 0;
};

// FNV-1a 64-bit hash as 16 hex digits.
std::string hash_hex(const void* data, size_t bytes, uint64_t seed = 1469598103934665603ull);
uint64_t fnv1a(const void* data, size_t bytes, uint64_t h = 1469598103934665603ull);
namespace ckpt {
// The checksum of rows that several processes write: the sum (mod 2^64) over the rows of FNV-1a 64
// of the row's bytes seeded with the row's index (first_row + r), so that each process adds its
// rows' terms and the sums add up, in any order; a changed byte or two rows swapped change it.
// (Also the mesh's hash, MeshHash in src/solver/run_setup.hpp.)
uint64_t rows_hash(const void* data, size_t rows, size_t row_bytes, uint64_t first_row);
}  // namespace ckpt

// Writes `path` atomically: to `path`.tmp in the same folder, fsync, rename over `path`, fsync the
// folder. Until the rename the previous file at `path` stays as it was. Throws InputError naming
// the file (full disk, unwritable folder). Test hook: the environment variable
// FDEM_TEST_CHECKPOINT_KILL = "during:N" or "after:N" kills the process (SIGKILL) in the middle of
// writing the N-th checkpoint of this process (half of the datasets written) or right after it.
void write_checkpoint(const std::string& path, const CheckpointHeader& h, const StateArrays& s);

// An entry of the whole run's state with one row per node or per interface (`blocks` blocks of
// `whole_rows` rows of `width` values), of which this process holds the rows (*ids)[i], i < own:
// values[(b * own + i) * width + c]. Integer entries are written as int64.
struct RowPart {
  std::string name;
  bool integer = false;
  long long whole_rows = 0;
  int blocks = 1, width = 1;
  const std::vector<int>* ids = nullptr;
  size_t own = 0;
  std::vector<double> values;
};

// What a checkpoint written by every process of a run needs of the processes.
struct CheckpointProcesses {
  long long fapl = -1;  // MPI-IO file access (Comm::h5_parallel_access); write_checkpoint_rows closes it
  bool root = false;    // process 0: writes the header, the entries of `s` and the checksums
  std::function<void(double*, int)> sum;  // in place over all processes, the same on each (Comm::sum)
};

// The same file as write_checkpoint, written by every process of a run (collective; an MPI build
// with the parallel HDF5): each process writes its own rows of every entry in `rows` (the same
// entries, in the same order, on every process) at their rows in the whole mesh; the checksums of
// those rows (checkpoint_internal.hpp: rows_hash) are summed over the processes; then process 0
// adds the header, every entry of its `s` (the others' is ignored) and the checksums, and renames
// the file into place. No process holds another's rows.
void write_checkpoint_rows(const std::string& path, const CheckpointHeader& h, const StateArrays& s,
                           const std::vector<RowPart>& rows, const CheckpointProcesses& p);

// Reads a checkpoint. Throws InputError naming `path` when it is missing, not HDF5, not a
// checkpoint of this format version, or damaged: a dataset whose values fail their checksum (the
// message names the dataset), a header or dataset list that fails the root checksum.
// skip_rows: the entries that every process wrote by rows (write_checkpoint_rows) are not read
// (StateArrays::by_rows names them): each process of a restart reads its own rows (read_rows).
StateArrays read_checkpoint(const std::string& path, CheckpointHeader& h, bool skip_rows = false);

// A process's rows of an entry left in the file (StateArrays::by_rows): rows ids[i], i < count, of
// each of `blocks` blocks of whole_rows rows of `width` values, as values[(b * count + i) * width +
// c]; `own_hash` gets the rows_hash (checkpoint_internal.hpp) of the first `hashed` of them (the
// rows this process owns: summed over the processes it must give the stored checksum; checked
// with rows_checksum_matches). Throws InputError naming the file and the entry when the dataset is
// missing or of another size.
std::vector<double> read_rows(const StateArrays& s, const std::string& name, const std::vector<int>& ids,
                              size_t count, size_t hashed, int blocks, long long whole_rows, int width,
                              uint64_t& own_hash);
// The sums (mod 2^64) over the processes of each process's checksum terms `mine`, exactly: each as
// two 32-bit halves summed as doubles by `sum` (Comm::sum); the same on every process. Collective.
std::vector<uint64_t> sum_hashes_over_processes(const std::vector<uint64_t>& mine,
                                                const std::function<void(double*, int)>& sum);
// Whether the sum over the processes of the entry's own_hash (sum_hashes_over_processes) is its
// stored checksum.
bool rows_checksum_matches(const StateArrays& s, const std::string& name, uint64_t total);

}  // namespace fdem
