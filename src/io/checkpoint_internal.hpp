#pragma once
// Internal to the checkpoint writers (src/io/checkpoint.cpp: one process; checkpoint_parallel.cpp:
// every process of a run its rows). Not a public header.
#include <hdf5.h>

#include <cstdint>
#include <map>
#include <string>

#include "io/checkpoint.hpp"

namespace fdem::ckpt {

inline constexpr const char* kFormat = "fdem checkpoint";
// 2: contact pairs carry a penetration allowance (contact/pair_g0)
// 3: every dataset carries an FNV-1a 64 checksum of its values (attribute "checksum") and the root
//    one of the header and the dataset list; run/fragment_rows. Earlier versions are refused: they
//    cannot be verified, and their restart would lose fragments.csv's rows.
// 4: a dataset written by every process of a run (its own rows) carries the checksum of its rows
//    (rows_hash) with the row width in the attribute "checksum_rows". Version 3 is still read.
inline constexpr int kVersion = 4;
inline constexpr const char* kChecksum = "checksum";
inline constexpr const char* kRowsAttr = "checksum_rows";

// The HDF5 error as " (message)", or "".
std::string reason();

// Test hook (checkpoint.hpp: FDEM_TEST_CHECKPOINT_KILL): which checkpoint of this process to kill
// in or after.
struct KillHook {
  int during = 0, after = 0;
  KillHook();
};
const KillHook& kill_hook();
[[noreturn]] void kill_now();
// The number of this checkpoint of this process (1, 2, ...), for the hook.
int next_checkpoint();

void string_attr(hid_t loc, const char* name, const std::string& v, const std::string& file);

// The checksum of a dataset: FNV-1a 64 of its values' bytes in memory (float64 / int64 of a
// little-endian host: the file's types) or of the string's characters, as 16 hex digits.
std::string values_checksum(const void* data, size_t bytes);
// (rows_hash: io/checkpoint.hpp)
std::string hex(uint64_t x);
// The root checksum: the header's values, then every dataset's name and checksum in name order,
// so that an altered header attribute or a dataset removed or added shows too.
std::string root_checksum(const CheckpointHeader& h, int version,
                          const std::map<std::string, std::string>& datasets);

// One checkpoint being written: to `tmp`, then renamed to `path`.
struct Writing {
  const std::string& path;
  const std::string& tmp;
  bool kill_midway;  // test hook: kill the process when half of the datasets are written
  // Removes `tmp` and throws InputError naming `path`, with HDF5's reason.
  [[noreturn]] void fail(const std::string& what) const;
};

// The attributes of the root group (layout: checkpoint.hpp), without the root checksum.
void write_header(hid_t f, const CheckpointHeader& h, const std::string& path);
// One dataset per state entry, at its name (intermediate groups created): float64, int64, then
// fixed-length string scalars; each with its checksum, also put into `sums` (by name). An entry
// already in `sums` is left out (written by rows: write_checkpoint_rows).
void write_datasets(hid_t f, const StateArrays& s, const Writing& w,
                    std::map<std::string, std::string>& sums);
// Syncs w.tmp, renames it over w.path and syncs the folder.
void commit(const Writing& w);

}  // namespace fdem::ckpt
