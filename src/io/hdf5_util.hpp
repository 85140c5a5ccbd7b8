#pragma once
// Internal helpers shared by the HDF5 writers and readers of src/io (snapshots, checkpoints):
// an owning handle, the HDF5 error stack as a message, dataset and attribute writes, attribute
// reads. Not a public header.
#include <hdf5.h>

#include <string>
#include <utility>
#include <vector>

namespace fdem {
namespace h5 {

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id() = default;
  Id(hid_t id, Closer c) : id_(id), close_(c) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  ~Id() {
    if (id_ >= 0 && close_) close_(id_);
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  // Gives up ownership: the caller closes the identifier.
  hid_t release() {
    const hid_t i = id_;
    id_ = -1;
    return i;
  }

 private:
  hid_t id_ = -1;
  Closer close_ = nullptr;
};

// Turns off HDF5's printing of its error stack: the callers report errors themselves.
void silence();

// The most specific message on HDF5's error stack (it names e.g. the OS error), or "". Clears the
// stack.
std::string reason();

// A file access property list without file locking (HDF5 >= 1.10.7), so that ParaView or h5py
// can open a file while a run writes it. Not ok() when the list cannot be created.
Id file_access_without_locking();

// Reads the scalar attribute `name` of `loc` as `mem_type`; false if it is missing or unreadable.
template <class T>
bool read_scalar_attr(hid_t loc, const char* name, hid_t mem_type, T& out) {
  if (H5Aexists(loc, name) <= 0) return false;
  Id a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  return a.ok() && H5Aread(a.get(), mem_type, &out) >= 0;
}

// Throws InputError "HDF5 error in 'FILE': WHAT (reason)"; `file` names the file for the message.
[[noreturn]] void fail(const std::string& file, const std::string& what);

// Writes the dataset `name` of shape `dims` from `data` (in `mem_type`) as `file_type`; throws
// (fail) on error.
void write_dataset(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type,
                   const std::vector<hsize_t>& dims, const void* data, const std::string& file);
// float64 from doubles; int32 from ints.
void write_doubles(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                   const double* data, const std::string& file);
void write_ints(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                const int* data, const std::string& file);

// Writes the scalar attribute `name` of `loc`; throws (fail) on error.
template <typename T>
void write_scalar_attr(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, T value,
                       const std::string& file) {
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  if (!space.ok()) fail(file, std::string("cannot create dataspace for attribute '") + name + "'");
  Id attr(H5Acreate2(loc, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.ok()) fail(file, std::string("cannot create attribute '") + name + "'");
  if (H5Awrite(attr.get(), mem_type, &value) < 0) {
    fail(file, std::string("cannot write attribute '") + name + "'");
  }
}

// Reads the fixed-length string attribute `name` of `loc` (up to its first NUL); false if it is
// missing, unreadable or not a fixed-length string.
bool read_string_attr(hid_t loc, const char* name, std::string& out);

// A process's part of a dataset that every process of a run writes or reads its rows of
// (src/io/snapshot_parallel.cpp, src/io/checkpoint_parallel.cpp):
// Local rows 0..n-1 in increasing ids[i].
std::vector<size_t> order_by(const int* ids, size_t n);
// Runs of consecutive indices, (first, count); add() extends the last run where it ends at `first`.
struct Runs {
  std::vector<std::pair<hsize_t, hsize_t>> runs;
  void add(hsize_t first, hsize_t count) {
    if (!runs.empty() && runs.back().first + runs.back().second == first)
      runs.back().second += count;
    else
      runs.emplace_back(first, count);
  }
};
// Selects in `space` the runs' rows (rank 2: with all their columns) or values (rank 1); none when
// there are no runs. False on an HDF5 error.
bool select_runs(hid_t space, const Runs& r);
// A one-dimensional memory space of n values (none selected when n is 0); not ok() on an error.
Id memory_space(hsize_t n);
// Creation properties of a dataset whose every value one process writes: allocated when created
// (as parallel HDF5 needs), no fill values written; not ok() on an error.
Id written_once();

}  // namespace h5
}  // namespace fdem
