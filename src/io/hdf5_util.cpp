#include "io/hdf5_util.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace fdem {
namespace h5 {

namespace {

// No clean-up of HDF5 at exit. When a file cannot be closed (its last writes fail: a full disk),
// HDF5 1.10 keeps a half-closed file in its tables, and its exit handler, closing it again, crashes
// the process (SIGSEGV after the error message). fdem closes every file it opens (h5::Id and the
// writers' destructors), so the handler has nothing else to do. Must run before the library
// initialises itself, i.e. before any other HDF5 call: here, at static initialisation.
const bool kNoCleanupAtExit = H5dont_atexit() >= 0;

herr_t first_error(unsigned n, const H5E_error2_t* e, void* data) {
  if (n == 0 && e && e->desc) *static_cast<std::string*>(data) = e->desc;
  return 0;
}

// A failed write of the file driver: "file write failed: time = ..., filename = ..., errno = 28,
// error message = 'No space left on device', buf = ..." -> "file write failed: No space left on
// device". Other messages as they are.
std::string shorten(const std::string& desc) {
  const std::string key = "error message = '";
  const auto at = desc.find(key);
  if (at == std::string::npos) return desc;
  const auto end = desc.find('\'', at + key.size());
  const auto colon = desc.find(':');
  const std::string what = colon < at ? desc.substr(0, colon) + ": " : std::string();
  return what + desc.substr(at + key.size(), end == std::string::npos ? end : end - at - key.size());
}

}  // namespace

void silence() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

std::string reason() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, first_error, &msg);
  H5Eclear2(H5E_DEFAULT);
  (void)kNoCleanupAtExit;
  return shorten(msg);
}

Id file_access_without_locking() {
  Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  if (fapl.ok()) H5Pset_file_locking(fapl.get(), 0, 1);
#endif
  return fapl;
}

bool read_string_attr(hid_t loc, const char* name, std::string& out) {
  if (H5Aexists(loc, name) <= 0) return false;
  Id a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return false;
  Id t(H5Aget_type(a.get()), H5Tclose);
  if (H5Tget_class(t.get()) != H5T_STRING || H5Tis_variable_str(t.get()) > 0) return false;
  const size_t n = H5Tget_size(t.get());
  std::string buf(n, '\0');
  if (H5Aread(a.get(), t.get(), buf.data()) < 0) return false;
  out = buf.substr(0, std::strlen(buf.c_str()));
  return true;
}

std::vector<size_t> order_by(const int* ids, size_t n) {
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [ids](size_t a, size_t b) { return ids[a] < ids[b]; });
  return order;
}

bool select_runs(hid_t space, const Runs& r) {
  const int rank = H5Sget_simple_extent_ndims(space);
  hsize_t dims[2] = {0, 1};
  if (rank < 1 || rank > 2 || H5Sget_simple_extent_dims(space, dims, nullptr) < 0) return false;
  bool ok = H5Sselect_none(space) >= 0;
  for (const auto& [first, count] : r.runs) {
    const hsize_t start[2] = {first, 0}, cnt[2] = {count, dims[1]};
    ok = ok && H5Sselect_hyperslab(space, H5S_SELECT_OR, start, nullptr, cnt, nullptr) >= 0;
  }
  return ok;
}

Id memory_space(hsize_t n) {
  const hsize_t dim = std::max<hsize_t>(n, 1);
  Id space(H5Screate_simple(1, &dim, nullptr), H5Sclose);
  if (space.ok() && n == 0 && H5Sselect_none(space.get()) < 0) return Id();
  return space;
}

Id written_once() {
  Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (dcpl.ok() && (H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_NEVER) < 0 ||
                    H5Pset_alloc_time(dcpl.get(), H5D_ALLOC_TIME_EARLY) < 0))
    return Id();
  return dcpl;
}

void fail(const std::string& file, const std::string& what) {
  const std::string why = reason();
  throw InputError("HDF5 error in '" + file + "': " + what + (why.empty() ? "" : " (" + why + ")"));
}

void write_dataset(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type,
                   const std::vector<hsize_t>& dims, const void* data, const std::string& file) {
  Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!space.ok()) fail(file, "cannot create dataspace for '" + name + "'");
  Id dset(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                     H5P_DEFAULT),
          H5Dclose);
  if (!dset.ok()) fail(file, "cannot create dataset '" + name + "'");
  hsize_t count = 1;
  for (hsize_t d : dims) count *= d;
  if (count > 0 && H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    fail(file, "cannot write dataset '" + name + "'");
  }
}

void write_doubles(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                   const double* data, const std::string& file) {
  write_dataset(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dims, data, file);
}

void write_ints(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                const int* data, const std::string& file) {
  write_dataset(loc, name, H5T_STD_I32LE, H5T_NATIVE_INT, dims, data, file);
}

}  // namespace h5
}  // namespace fdem
