#include "io/checkpoint.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "common/error.hpp"

namespace fdem {

namespace fs = std::filesystem;

namespace {

const char* kFormat = "fdem checkpoint";
// 2: contact pairs carry a penetration allowance (contact/pair_g0)
constexpr int kVersion = 2;

// Owns one HDF5 identifier.
class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id(hid_t id, Closer c) : id_(id), close_(c) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  hid_t release() {
    const hid_t i = id_;
    id_ = -1;
    return i;
  }

 private:
  hid_t id_;
  Closer close_;
};

herr_t first_error(unsigned n, const H5E_error2_t* e, void* data) {
  if (n == 0 && e && e->desc) *static_cast<std::string*>(data) = e->desc;
  return 0;
}

std::string reason() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, first_error, &msg);
  H5Eclear2(H5E_DEFAULT);
  return msg.empty() ? std::string() : " (" + msg + ")";
}

// Test hook (see checkpoint.hpp): which checkpoint of this process to kill in or after.
struct KillHook {
  int during = 0, after = 0;
  KillHook() {
    const char* e = std::getenv("FDEM_TEST_CHECKPOINT_KILL");
    if (!e) return;
    const std::string s = e;
    const auto colon = s.find(':');
    if (colon == std::string::npos) return;
    const int n = std::atoi(s.c_str() + colon + 1);
    if (s.compare(0, colon, "during") == 0) during = n;
    if (s.compare(0, colon, "after") == 0) after = n;
  }
};

void kill_now() {
  std::fflush(stdout);
  std::fflush(stderr);
  std::raise(SIGKILL);
}

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

template <class T>
void scalar_attr(hid_t loc, const char* name, hid_t ftype, hid_t mtype, T v, const std::string& file) {
  Id sp(H5Screate(H5S_SCALAR), H5Sclose);
  Id a(H5Acreate2(loc, name, ftype, sp.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.ok() || H5Awrite(a.get(), mtype, &v) < 0)
    throw InputError("cannot write checkpoint '" + file + "': attribute " + name + reason());
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

template <class T>
bool read_scalar_attr(hid_t loc, const char* name, hid_t mtype, T& out) {
  if (H5Aexists(loc, name) <= 0) return false;
  Id a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  return a.ok() && H5Aread(a.get(), mtype, &out) >= 0;
}

struct VisitData {
  StateArrays* s;
  std::string error;
};

herr_t visit_link(hid_t group, const char* name, const H5L_info_t*, void* data) {
  auto* vd = static_cast<VisitData*>(data);
  Id obj(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
  if (!obj.ok()) {
    vd->error = std::string("cannot open '") + name + "'";
    return -1;
  }
  if (H5Iget_type(obj.get()) != H5I_DATASET) return 0;
  const hid_t d = obj.get();
  Id sp(H5Dget_space(d), H5Sclose);
  Id t(H5Dget_type(d), H5Tclose);
  if (!sp.ok() || !t.ok()) {
    vd->error = std::string("cannot read '") + name + "'";
    return -1;
  }
  const hssize_t n = H5Sget_simple_extent_npoints(sp.get());
  const H5T_class_t cls = H5Tget_class(t.get());
  herr_t rc = 0;
  if (cls == H5T_FLOAT) {
    auto& v = vd->s->f64[name];
    v.resize(static_cast<size_t>(n));
    if (n > 0) rc = H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  } else if (cls == H5T_INTEGER) {
    auto& v = vd->s->i64[name];
    v.resize(static_cast<size_t>(n));
    if (n > 0) rc = H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  } else if (cls == H5T_STRING && H5Tis_variable_str(t.get()) <= 0 && n == 1) {
    std::string buf(H5Tget_size(t.get()), '\0');
    rc = H5Dread(d, t.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
    vd->s->str[name] = buf.substr(0, std::strlen(buf.c_str()));
  } else {
    vd->error = std::string("dataset '") + name + "' has an unexpected type";
    return -1;
  }
  if (rc < 0) {
    vd->error = std::string("cannot read '") + name + "'";
    return -1;
  }
  return 0;
}

}  // namespace

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

void write_checkpoint(const std::string& path, const CheckpointHeader& h, const StateArrays& s) {
  static const KillHook hook;
  static int count = 0;
  ++count;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& what) {
    const std::string why = reason();
    std::remove(tmp.c_str());
    throw InputError("cannot write checkpoint '" + path + "': " + what + why);
  };
  {
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
    H5Pset_file_locking(fapl.get(), 0, 1);
#endif
    Id file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose);
    if (!file.ok()) fail("cannot create " + tmp);
    try {
      const hid_t f = file.get();
      string_attr(f, "format", kFormat, path);
      scalar_attr<int>(f, "version", H5T_STD_I32LE, H5T_NATIVE_INT, kVersion, path);
      scalar_attr<int>(f, "dimension", H5T_STD_I32LE, H5T_NATIVE_INT, h.dim, path);
      scalar_attr<long long>(f, "num_nodes", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.nodes, path);
      scalar_attr<long long>(f, "num_elements", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.elements, path);
      scalar_attr<long long>(f, "num_interfaces", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.interfaces, path);
      string_attr(f, "case_hash", h.case_hash, path);
      string_attr(f, "mesh_hash", h.mesh_hash, path);
      scalar_attr<double>(f, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, h.time, path);
      scalar_attr<long long>(f, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, h.step, path);

      Id lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
      H5Pset_create_intermediate_group(lcpl.get(), 1);
      const size_t total = s.f64.size() + s.i64.size() + s.str.size();
      size_t written = 0;
      auto dataset = [&](const std::string& name, hid_t ftype, hid_t mtype, size_t n, const void* data) {
        const hsize_t dims[1] = {static_cast<hsize_t>(n)};
        Id sp(H5Screate_simple(1, dims, nullptr), H5Sclose);
        Id d(H5Dcreate2(f, name.c_str(), ftype, sp.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
        if (!d.ok()) fail("cannot create dataset '" + name + "'");
        if (n > 0 && H5Dwrite(d.get(), mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
          fail("cannot write dataset '" + name + "'");
        if (++written == total / 2 && hook.during == count) kill_now();
      };
      for (const auto& [name, v] : s.f64) dataset(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.size(), v.data());
      for (const auto& [name, v] : s.i64) dataset(name, H5T_STD_I64LE, H5T_NATIVE_LLONG, v.size(), v.data());
      for (const auto& [name, v] : s.str) {
        Id t(H5Tcopy(H5T_C_S1), H5Tclose);
        H5Tset_size(t.get(), std::max<size_t>(1, v.size()));
        Id sp(H5Screate(H5S_SCALAR), H5Sclose);
        Id d(H5Dcreate2(f, name.c_str(), t.get(), sp.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
        const std::string buf = v.empty() ? std::string(1, '\0') : v;
        if (!d.ok() || H5Dwrite(d.get(), t.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
          fail("cannot write dataset '" + name + "'");
        if (++written == total / 2 && hook.during == count) kill_now();
      }
    } catch (...) {
      H5Fclose(file.release());
      std::remove(tmp.c_str());
      throw;
    }
    if (H5Fclose(file.release()) < 0) fail("cannot close " + tmp + " (disk full?)");
  }
  try {
    fsync_path(tmp, false, path);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw InputError("cannot write checkpoint '" + path + "' (renaming " + tmp + "): " + std::strerror(err));
  }
  const fs::path dir = fs::path(path).parent_path();
  fsync_path(dir.empty() ? std::string(".") : dir.string(), true, path);
  if (hook.after == count) kill_now();
}

StateArrays read_checkpoint(const std::string& path, CheckpointHeader& h) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError("restart file '" + path + "' does not exist");
  if (fs::is_directory(path, ec)) throw InputError("restart file '" + path + "' is a folder, not a checkpoint");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError("restart file '" + path + "' is not an HDF5 file (give a checkpoint.h5 written by --checkpoint-every)");
  }
  Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  H5Pset_file_locking(fapl.get(), 0, 1);
#endif
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!file.ok()) throw InputError("restart file '" + path + "' cannot be opened" + reason());
  const hid_t f = file.get();
  std::string format;
  int version = 0;
  if (!read_string_attr(f, "format", format) || format != kFormat)
    throw InputError("restart file '" + path + "' is an HDF5 file but not an fdem checkpoint");
  if (!read_scalar_attr(f, "version", H5T_NATIVE_INT, version) || version != kVersion)
    throw InputError("restart file '" + path + "' is a checkpoint of format version " +
                     std::to_string(version) + "; this fdem reads version " + std::to_string(kVersion));
  bool ok = read_scalar_attr(f, "dimension", H5T_NATIVE_INT, h.dim) &&
            read_scalar_attr(f, "num_nodes", H5T_NATIVE_LLONG, h.nodes) &&
            read_scalar_attr(f, "num_elements", H5T_NATIVE_LLONG, h.elements) &&
            read_scalar_attr(f, "num_interfaces", H5T_NATIVE_LLONG, h.interfaces) &&
            read_string_attr(f, "case_hash", h.case_hash) && read_string_attr(f, "mesh_hash", h.mesh_hash) &&
            read_scalar_attr(f, "time", H5T_NATIVE_DOUBLE, h.time) &&
            read_scalar_attr(f, "step", H5T_NATIVE_LLONG, h.step);
  if (!ok) throw InputError("restart file '" + path + "': checkpoint header is incomplete" + reason());
  StateArrays s;
  s.file = path;
  VisitData vd{&s, {}};
  if (H5Lvisit(f, H5_INDEX_NAME, H5_ITER_INC, visit_link, &vd) < 0)
    throw InputError("restart file '" + path + "' is damaged: " +
                     (vd.error.empty() ? std::string("cannot list its contents") : vd.error) + reason());
  return s;
}

}  // namespace fdem
