#include "io/checkpoint.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>

#include "common/error.hpp"
#include "io/checkpoint_internal.hpp"
#include "io/hdf5_util.hpp"

namespace fdem {

namespace fs = std::filesystem;

namespace ckpt {

using h5::Id;

std::string reason() {
  const std::string msg = h5::reason();
  return msg.empty() ? std::string() : " (" + msg + ")";
}

KillHook::KillHook() {
  const char* e = std::getenv("FDEM_TEST_CHECKPOINT_KILL");
  if (!e) return;
  const std::string s = e;
  const auto colon = s.find(':');
  if (colon == std::string::npos) return;
  const int n = std::atoi(s.c_str() + colon + 1);
  if (s.compare(0, colon, "during") == 0) during = n;
  if (s.compare(0, colon, "after") == 0) after = n;
}

const KillHook& kill_hook() {
  static const KillHook hook;
  return hook;
}

void kill_now() {
  std::fflush(stdout);
  std::fflush(stderr);
  std::raise(SIGKILL);
  std::_Exit(137);  // (SIGKILL cannot be caught: not reached)
}

namespace {

void fsync_path(const std::string& p, bool dir, const std::string& file) {
  const int fd = ::open(p.c_str(), dir ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) {
    if (dir) return;  // some file systems do not open folders: the rename is still atomic
    throw InputError("cannot write checkpoint '" + file + "' (opening " + p + " to sync): " +
                     std::strerror(errno));
  }
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0 && !dir)
    throw InputError("cannot write checkpoint '" + file + "' (syncing " + p + "): " + std::strerror(err));
}

}  // namespace

void string_attr(hid_t loc, const char* name, const std::string& v, const std::string& file) {
  Id t(H5Tcopy(H5T_C_S1), H5Tclose);
  Id sp(H5Screate(H5S_SCALAR), H5Sclose);
  if (!t.ok() || !sp.ok() || H5Tset_size(t.get(), std::max<size_t>(1, v.size())) < 0)
    throw InputError("cannot write checkpoint '" + file + "': string type" + reason());
  Id a(H5Acreate2(loc, name, t.get(), sp.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  std::string buf = v.empty() ? std::string(1, '\0') : v;
  if (!a.ok() || H5Awrite(a.get(), t.get(), buf.data()) < 0)
    throw InputError("cannot write checkpoint '" + file + "': attribute " + name + reason());
}

namespace {

template <class T>
void scalar_attr(hid_t loc, const char* name, hid_t ftype, hid_t mtype, T v, const std::string& file) {
  Id sp(H5Screate(H5S_SCALAR), H5Sclose);
  Id a(H5Acreate2(loc, name, ftype, sp.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok() || H5Awrite(a.get(), mtype, &v) < 0)
    throw InputError("cannot write checkpoint '" + file + "': attribute " + name + reason());
}

struct VisitData {
  StateArrays* s;
  std::string error;
  std::map<std::string, std::string> checksums;  // of every dataset, verified (or by_rows: as stored)
  bool skip_rows = false;  // read_checkpoint's: the datasets by rows are left in the file
};

}  // namespace

std::string values_checksum(const void* data, size_t bytes) { return hash_hex(data, bytes); }

uint64_t rows_hash(const void* data, size_t rows, size_t row_bytes, uint64_t first_row) {
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t sum = 0;
  for (size_t r = 0; r < rows; ++r) {
    const uint64_t index = first_row + r;
    sum += fnv1a(p + r * row_bytes, row_bytes, fnv1a(&index, sizeof index));
  }
  return sum;
}

std::string hex(uint64_t x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(x));
  return buf;
}

std::string root_checksum(const CheckpointHeader& h, int version,
                          const std::map<std::string, std::string>& datasets) {
  std::string text = std::string(kFormat) + '\n' + std::to_string(version) + '\n' + std::to_string(h.dim) +
                     ' ' + std::to_string(h.nodes) + ' ' + std::to_string(h.elements) + ' ' +
                     std::to_string(h.interfaces) + '\n' + h.case_hash + '\n' + h.mesh_hash + '\n' +
                     std::to_string(h.step) + '\n';
  uint64_t x = fnv1a(&h.time, sizeof h.time, fnv1a(text.data(), text.size()));
  for (const auto& [name, sum] : datasets) {
    x = fnv1a(name.c_str(), name.size() + 1, x);
    x = fnv1a(sum.data(), sum.size(), x);
  }
  return hex(x);
}

namespace {

// visit_link's phases for one dataset: a dataset by rows left in the file (its stored checksum
// only), or its values read, their checksum computed and compared with the stored one. Each
// returns -1 with vd.error set on failure (H5Lvisit's stop), else 0.

// A dataset by rows that read_checkpoint leaves in the file (skip_rows).
bool left_by_rows(hid_t d, const VisitData& vd) {
  int rows_width = 0;
  return vd.skip_rows && h5::read_scalar_attr(d, kRowsAttr, H5T_NATIVE_INT, rows_width) && rows_width > 0;
}

herr_t record_rows_checksum(hid_t d, const char* name, VisitData& vd) {
  std::string stored;
  if (!h5::read_string_attr(d, kChecksum, stored)) {
    vd.error = std::string("dataset '") + name + "' has no checksum";
    return -1;
  }
  vd.s->by_rows[name] = stored;  // (its rows are read and verified by their owners: read_rows)
  vd.checksums[name] = stored;
  return 0;
}

// The values into vd.s (f64, i64 or str by the dataset's class); cls and n: its class and size.
herr_t read_values(hid_t d, const char* name, VisitData& vd, H5T_class_t& cls, hssize_t& n) {
  Id sp(H5Dget_space(d), H5Sclose);
  Id t(H5Dget_type(d), H5Tclose);
  if (!sp.ok() || !t.ok()) {
    vd.error = std::string("cannot read '") + name + "'";
    return -1;
  }
  n = H5Sget_simple_extent_npoints(sp.get());
  cls = H5Tget_class(t.get());
  herr_t rc = 0;
  if (cls == H5T_FLOAT) {
    auto& v = vd.s->f64[name];
    v.resize(static_cast<size_t>(n));
    if (n > 0) rc = H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  } else if (cls == H5T_INTEGER) {
    auto& v = vd.s->i64[name];
    v.resize(static_cast<size_t>(n));
    if (n > 0) rc = H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  } else if (cls == H5T_STRING && H5Tis_variable_str(t.get()) <= 0 && n == 1) {
    std::string buf(H5Tget_size(t.get()), '\0');
    rc = H5Dread(d, t.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
    vd.s->str[name] = buf.substr(0, std::strlen(buf.c_str()));
  } else {
    vd.error = std::string("dataset '") + name + "' has an unexpected type";
    return -1;
  }
  if (rc < 0) {
    vd.error = std::string("cannot read '") + name + "'";
    return -1;
  }
  return 0;
}

// The checksum of the values read (a flipped bit in the data reads back without an HDF5 error):
// of the rows (written by every process of a run: checkpoint_internal.hpp) or of the bytes.
std::string read_values_checksum(hid_t d, const char* name, const VisitData& vd, H5T_class_t cls,
                                 hssize_t n) {
  int width = 0;
  if (h5::read_scalar_attr(d, kRowsAttr, H5T_NATIVE_INT, width) && width > 0 && cls != H5T_STRING) {
    const void* p = cls == H5T_FLOAT ? static_cast<const void*>(vd.s->f64[name].data())
                                     : static_cast<const void*>(vd.s->i64[name].data());
    const size_t w = static_cast<size_t>(width);
    return hex(rows_hash(p, static_cast<size_t>(n) / w, 8 * w, 0));
  } else if (cls == H5T_FLOAT) {
    const auto& v = vd.s->f64[name];
    return values_checksum(v.data(), v.size() * sizeof(double));
  } else if (cls == H5T_INTEGER) {
    const auto& v = vd.s->i64[name];
    return values_checksum(v.data(), v.size() * sizeof(long long));
  } else {
    const auto& v = vd.s->str[name];
    return values_checksum(v.data(), v.size());
  }
}

herr_t verify_checksum(hid_t d, const char* name, const std::string& sum, VisitData& vd) {
  std::string stored;
  if (!h5::read_string_attr(d, kChecksum, stored)) {
    vd.error = std::string("dataset '") + name + "' has no checksum";
    return -1;
  }
  if (stored != sum) {
    vd.error = std::string("dataset '") + name + "' fails its checksum (stored " + stored + ", computed " +
               sum + ")";
    return -1;
  }
  vd.checksums[name] = sum;
  return 0;
}

// H5Lvisit's callback: every dataset of the file into vd->s, verified against its checksum.
herr_t visit_link(hid_t group, const char* name, const H5L_info_t*, void* data) {
  auto* vd = static_cast<VisitData*>(data);
  Id obj(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
  if (!obj.ok()) {
    vd->error = std::string("cannot open '") + name + "'";
    return -1;
  }
  if (H5Iget_type(obj.get()) != H5I_DATASET) return 0;
  const hid_t d = obj.get();
  if (left_by_rows(d, *vd)) return record_rows_checksum(d, name, *vd);
  H5T_class_t cls = H5T_NO_CLASS;
  hssize_t n = 0;
  if (read_values(d, name, *vd, cls, n) < 0) return -1;
  return verify_checksum(d, name, read_values_checksum(d, name, *vd, cls, n), *vd);
}

}  // namespace
}  // namespace ckpt

uint64_t fnv1a(const void* data, size_t bytes, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string hash_hex(const void* data, size_t bytes, uint64_t seed) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a(data, bytes, seed)));
  return buf;
}

// ------------------------------------------------------------------------------------------------
// StateArrays

namespace {
[[noreturn]] void missing(const StateArrays& s, const std::string& name, const std::string& what) {
  throw InputError("checkpoint '" + s.file + "': " + what + " '" + name +
                   "' (the file is damaged or was written by another version)");
}
}  // namespace

double StateArrays::get(const std::string& name) const { return array(name, 1)[0]; }

long long StateArrays::get_int(const std::string& name) const { return int_array(name, 1)[0]; }

const std::vector<double>& StateArrays::array(const std::string& name, long long expected) const {
  auto it = f64.find(name);
  if (it == f64.end()) missing(*this, name, "no entry");
  if (expected >= 0 && static_cast<long long>(it->second.size()) != expected)
    missing(*this, name, "wrong size (" + std::to_string(it->second.size()) + ", expected " +
                             std::to_string(expected) + ") of");
  return it->second;
}

const std::vector<long long>& StateArrays::int_array(const std::string& name, long long expected) const {
  auto it = i64.find(name);
  if (it == i64.end()) missing(*this, name, "no entry");
  if (expected >= 0 && static_cast<long long>(it->second.size()) != expected)
    missing(*this, name, "wrong size (" + std::to_string(it->second.size()) + ", expected " +
                             std::to_string(expected) + ") of");
  return it->second;
}

const std::string& StateArrays::string(const std::string& name) const {
  auto it = str.find(name);
  if (it == str.end()) missing(*this, name, "no entry");
  return it->second;
}

// ------------------------------------------------------------------------------------------------
// write / read

namespace ckpt {

void Writing::fail(const std::string& what) const {
  const std::string why = reason();
  std::remove(tmp.c_str());
  throw InputError("cannot write checkpoint '" + path + "': " + what + why);
}

void write_header(hid_t f, const CheckpointHeader& h, const std::string& path) {
  string_attr(f, "format", kFormat, path);
  scalar_attr<int>(f, "version", H5T_STD_I32LE, H5T_NATIVE_INT, kVersion, path);
  scalar_attr<int>(f, "dimension", H5T_STD_I32LE, H5T_NATIVE_INT, h.dim, path);
  scalar_attr<long long>(f, "num_nodes", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.nodes, path);
  scalar_attr<long long>(f, "num_elements", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.elements, path);
  scalar_attr<long long>(f, "num_interfaces", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.interfaces,
                         path);
  string_attr(f, "case_hash", h.case_hash, path);
  string_attr(f, "mesh_hash", h.mesh_hash, path);
  scalar_attr<double>(f, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, h.time, path);
  scalar_attr<long long>(f, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.step, path);
}

void write_datasets(hid_t f, const StateArrays& s, const Writing& w,
                    std::map<std::string, std::string>& sums) {
  Id lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  const size_t total = s.f64.size() + s.i64.size() + s.str.size();
  size_t written = 0;
  auto one_more = [&] {
    if (++written == total / 2 && w.kill_midway) kill_now();
  };
  auto dataset = [&](const std::string& name, hid_t ftype, hid_t mtype, size_t n, const void* data) {
    if (sums.count(name)) return;  // written by rows already (write_checkpoint_rows)
    const hsize_t dims[1] = {static_cast<hsize_t>(n)};
    Id sp(H5Screate_simple(1, dims, nullptr), H5Sclose);
    Id d(H5Dcreate2(f, name.c_str(), ftype, sp.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    if (!d.ok()) w.fail("cannot create dataset '" + name + "'");
    if (n > 0 && H5Dwrite(d.get(), mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
      w.fail("cannot write dataset '" + name + "'");
    sums[name] = values_checksum(data, n * 8);  // float64 / int64
    string_attr(d.get(), kChecksum, sums[name], w.path);
    one_more();
  };
  for (const auto& [name, v] : s.f64) dataset(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.size(), v.data());
  for (const auto& [name, v] : s.i64) dataset(name, H5T_STD_I64LE, H5T_NATIVE_LLONG, v.size(), v.data());
  for (const auto& [name, v] : s.str) {
    if (sums.count(name)) continue;
    Id t(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(t.get(), std::max<size_t>(1, v.size()));
    Id sp(H5Screate(H5S_SCALAR), H5Sclose);
    Id d(H5Dcreate2(f, name.c_str(), t.get(), sp.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    const std::string buf = v.empty() ? std::string(1, '\0') : v;
    if (!d.ok() || H5Dwrite(d.get(), t.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
      w.fail("cannot write dataset '" + name + "'");
    sums[name] = values_checksum(v.data(), v.size());
    string_attr(d.get(), kChecksum, sums[name], w.path);
    one_more();
  }
}

namespace {

// Writes the whole checkpoint to w.tmp; on failure w.tmp is removed.
void write_tmp(const CheckpointHeader& h, const StateArrays& s, const Writing& w) {
  Id fapl = h5::file_access_without_locking();
  Id file(H5Fcreate(w.tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose);
  if (!file.ok()) w.fail("cannot create " + w.tmp);
  try {
    write_header(file.get(), h, w.path);
    std::map<std::string, std::string> sums;
    write_datasets(file.get(), s, w, sums);
    string_attr(file.get(), kChecksum, root_checksum(h, kVersion, sums), w.path);
  } catch (...) {
    H5Fclose(file.release());
    std::remove(w.tmp.c_str());
    throw;
  }
  if (H5Fclose(file.release()) < 0) w.fail("cannot close " + w.tmp + " (disk full?)");
}

}  // namespace

void commit(const Writing& w) {
  try {
    fsync_path(w.tmp, false, w.path);
  } catch (...) {
    std::remove(w.tmp.c_str());
    throw;
  }
  if (std::rename(w.tmp.c_str(), w.path.c_str()) != 0) {
    const int err = errno;
    std::remove(w.tmp.c_str());
    throw InputError("cannot write checkpoint '" + w.path + "' (renaming " + w.tmp + "): " +
                     std::strerror(err));
  }
  const fs::path dir = fs::path(w.path).parent_path();
  fsync_path(dir.empty() ? std::string(".") : dir.string(), true, w.path);
}

int next_checkpoint() {
  static int count = 0;
  return ++count;
}

}  // namespace ckpt

using namespace ckpt;

void write_checkpoint(const std::string& path, const CheckpointHeader& h, const StateArrays& s) {
  const int count = next_checkpoint();
  h5::silence();
  const std::string tmp = path + ".tmp";
  const Writing w{path, tmp, kill_hook().during == count};
  write_tmp(h, s, w);
  commit(w);
  if (kill_hook().after == count) kill_now();
}

StateArrays read_checkpoint(const std::string& path, CheckpointHeader& h, bool skip_rows) {
  h5::silence();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError("restart file '" + path + "' does not exist");
  if (fs::is_directory(path, ec))
    throw InputError("restart file '" + path + "' is a folder, not a checkpoint");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError("restart file '" + path +
                     "' is not an HDF5 file (give a checkpoint.h5 written by --checkpoint-every)");
  }
  Id fapl = h5::file_access_without_locking();
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!file.ok()) throw InputError("restart file '" + path + "' cannot be opened" + reason());
  const hid_t f = file.get();
  std::string format;
  int version = 0;
  if (!h5::read_string_attr(f, "format", format) || format != kFormat)
    throw InputError("restart file '" + path + "' is an HDF5 file but not an fdem checkpoint");
  if (!h5::read_scalar_attr(f, "version", H5T_NATIVE_INT, version) || version < 3 || version > kVersion)
    throw InputError("restart file '" + path + "' is a checkpoint of format version " +
                     std::to_string(version) + "; this fdem reads versions 3 to " + std::to_string(kVersion) +
                     (version > 0 && version < 3
                          ? " (earlier versions carry no checksum and are not accepted: start the run "
                            "again, or finish it with the fdem that wrote the checkpoint)"
                          : ""));
  bool ok = h5::read_scalar_attr(f, "dimension", H5T_NATIVE_INT, h.dim) &&
            h5::read_scalar_attr(f, "num_nodes", H5T_NATIVE_LLONG, h.nodes) &&
            h5::read_scalar_attr(f, "num_elements", H5T_NATIVE_LLONG, h.elements) &&
            h5::read_scalar_attr(f, "num_interfaces", H5T_NATIVE_LLONG, h.interfaces) &&
            h5::read_string_attr(f, "case_hash", h.case_hash) &&
            h5::read_string_attr(f, "mesh_hash", h.mesh_hash) &&
            h5::read_scalar_attr(f, "time", H5T_NATIVE_DOUBLE, h.time) &&
            h5::read_scalar_attr(f, "step", H5T_NATIVE_LLONG, h.step);
  if (!ok) throw InputError("restart file '" + path + "': checkpoint header is incomplete" + reason());
  StateArrays s;
  s.file = path;
  VisitData vd{&s, {}, {}, skip_rows};
  if (H5Lvisit(f, H5_INDEX_NAME, H5_ITER_INC, visit_link, &vd) < 0)
    throw InputError("restart file '" + path + "' is damaged: " +
                     (vd.error.empty() ? std::string("cannot list its contents") : vd.error) + reason());
  std::string stored;
  if (!h5::read_string_attr(f, kChecksum, stored))
    throw InputError("restart file '" + path + "' is damaged: the file has no checksum");
  if (stored != root_checksum(h, version, vd.checksums))
    throw InputError("restart file '" + path +
                     "' is damaged: the header or the list of datasets fails the checksum");
  return s;
}

}  // namespace fdem
