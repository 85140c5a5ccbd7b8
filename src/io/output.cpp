// Output: output directory checks, atomic text files, history.csv, and HDF5 + XDMF snapshots.
//
// snapshots.h5 layout (all datasets little-endian; float64 unless noted):
//   /mesh                      attributes: dim (int32), num_nodes, num_elements, num_interfaces
//   /mesh/elements             int32, ne x (dim+1)
//   /mesh/region               int32, ne
//   /mesh/region_names         fixed-length strings, one per region (absent if the mesh has none)
//   /mesh/interfaces           int32, ni x dim   (A-side node ids of each interface)
//   /mesh/reference_coordinates nn x 3 (z = 0 in 2D)
//   /step_NNNNNNNN             attributes: time (float64), step (int64)
//     coordinates, displacement, velocity   nn x 3 (z = 0 in 2D)
//     stress                   ne x 6 (xx, yy, zz, xy, yz, xz)
//     von_mises                ne
//     damage                   ni
//     fragment                 int32, ne (only if the frame has one)
// snapshots.xdmf (XDMF 3) references these datasets as "snapshots.h5:/path".
#include "io/output.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace fdem {

namespace fs = std::filesystem;

// ------------------------------------------------------------------------------------------------
// Directories and files

void ensure_output_dir(const std::string& dir_in) {
  const std::string dir = dir_in.empty() ? std::string(".") : dir_in;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    throw InputError("cannot create output directory '" + dir + "': " + ec.message());
  }
  if (!fs::is_directory(dir, ec)) {
    throw InputError("output directory '" + dir + "' exists but is not a directory");
  }
  const std::string probe =
      (fs::path(dir) / (".fdem_write_probe_" + std::to_string(static_cast<long>(::getpid()))))
          .string();
  std::FILE* f = std::fopen(probe.c_str(), "w");
  if (!f) {
    const int err = errno;
    throw InputError("output directory '" + dir + "' is not writable: " + std::strerror(err));
  }
  const bool bad = std::fputs("probe\n", f) < 0;
  const bool close_bad = std::fclose(f) != 0;
  const int err = errno;
  std::remove(probe.c_str());
  if (bad || close_bad) {
    throw InputError("output directory '" + dir + "' is not writable: " + std::strerror(err));
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& what, int err) {
    std::remove(tmp.c_str());
    throw InputError("cannot write '" + path + "' (" + what + "): " + std::strerror(err));
  };
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    const int err = errno;
    throw InputError("cannot write '" + path + "' (opening " + tmp + "): " + std::strerror(err));
  }
  const size_t n = text.empty() ? 0 : std::fwrite(text.data(), 1, text.size(), f);
  if (n != text.size()) {
    const int err = errno;
    std::fclose(f);
    fail("writing " + tmp, err);
  }
  if (std::fflush(f) != 0) {
    const int err = errno;
    std::fclose(f);
    fail("flushing " + tmp, err);
  }
  if (::fsync(fileno(f)) != 0) {
    const int err = errno;
    if (err != EINVAL && err != EROFS) {  // not syncable (a pipe, a special file): go on
      std::fclose(f);
      fail("syncing " + tmp, err);
    }
  }
  if (std::fclose(f) != 0) fail("closing " + tmp, errno);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail("renaming " + tmp, errno);
}

// ------------------------------------------------------------------------------------------------
// history.csv

namespace {
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}
}  // namespace

HistoryWriter::HistoryWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), columns_(columns) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for writing: " + std::strerror(err));
  }
  std::string header;
  for (size_t i = 0; i < columns_.size(); ++i) {
    if (i) header += ',';
    header += csv_field(columns_[i]);
  }
  header += '\n';
  if (std::fputs(header.c_str(), f_) < 0 || std::fflush(f_) != 0) {
    const int err = errno;
    std::fclose(f_);
    f_ = nullptr;
    throw InputError("cannot write history file '" + path + "': " + std::strerror(err));
  }
}

HistoryWriter::HistoryWriter(const std::string& path, const std::vector<std::string>& columns,
                             const std::vector<double>& earlier_rows)
    : path_(path), columns_(columns) {
  const size_t nc = columns_.size();
  if (nc == 0 || earlier_rows.size() % nc != 0)
    throw std::logic_error("HistoryWriter: earlier rows do not fit the columns of '" + path + "'");
  std::string text;
  for (size_t i = 0; i < nc; ++i) {
    if (i) text += ',';
    text += csv_field(columns_[i]);
  }
  text += '\n';
  std::vector<double> row(nc);
  for (size_t r = 0; r < earlier_rows.size() / nc; ++r) {
    row.assign(earlier_rows.begin() + static_cast<long>(r * nc), earlier_rows.begin() + static_cast<long>((r + 1) * nc));
    text += format_row(row);
  }
  write_file_atomic(path, text);
  f_ = std::fopen(path.c_str(), "a");
  if (!f_) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for appending: " + std::strerror(err));
  }
}

std::string HistoryWriter::format_row(const std::vector<double>& values) {
  std::string line;
  char buf[64];
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) line += ',';
    std::snprintf(buf, sizeof buf, "%.10g", values[i]);
    line += buf;
  }
  line += '\n';
  return line;
}

HistoryWriter::~HistoryWriter() {
  if (f_) std::fclose(f_);
}

void HistoryWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_.size()) {
    throw std::logic_error("HistoryWriter::row: " + std::to_string(values.size()) +
                           " values for " + std::to_string(columns_.size()) + " columns in '" +
                           path_ + "'");
  }
  const std::string line = format_row(values);
  if (std::fputs(line.c_str(), f_) < 0 || std::fflush(f_) != 0) {
    const int err = errno;
    throw InputError("cannot write history file '" + path_ + "': " + std::strerror(err));
  }
}

// ------------------------------------------------------------------------------------------------
// HDF5 helpers

namespace {

// Owns one HDF5 identifier and closes it with the matching H5?close.
class H5Id {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Id() = default;
  H5Id(hid_t id, Closer c) : id_(id), close_(c) {}
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  H5Id(H5Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  ~H5Id() {
    if (id_ >= 0 && close_) close_(id_);
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  Closer close_ = nullptr;
};

void silence_hdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

herr_t first_error_cb(unsigned n, const H5E_error2_t* e, void* data) {
  auto* out = static_cast<std::string*>(data);
  if (n == 0 && e && e->desc) *out = e->desc;
  return 0;
}

// The most specific message on HDF5's error stack (it names e.g. the OS error), or "".
std::string hdf5_reason() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, first_error_cb, &msg);
  H5Eclear2(H5E_DEFAULT);
  return msg;
}

[[noreturn]] void h5fail(const std::string& file, const std::string& what) {
  const std::string why = hdf5_reason();
  throw InputError("HDF5 error in '" + file + "': " + what + (why.empty() ? "" : " (" + why + ")"));
}

void write_dataset(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type,
                   const std::vector<hsize_t>& dims, const void* data, const std::string& file) {
  H5Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!space.ok()) h5fail(file, "cannot create dataspace for '" + name + "'");
  H5Id dset(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                       H5P_DEFAULT),
            H5Dclose);
  if (!dset.ok()) h5fail(file, "cannot create dataset '" + name + "'");
  hsize_t count = 1;
  for (hsize_t d : dims) count *= d;
  if (count > 0 && H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    h5fail(file, "cannot write dataset '" + name + "'");
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

template <typename T>
void write_scalar_attr(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, T value,
                       const std::string& file) {
  H5Id space(H5Screate(H5S_SCALAR), H5Sclose);
  if (!space.ok()) h5fail(file, std::string("cannot create dataspace for attribute '") + name + "'");
  H5Id attr(H5Acreate2(loc, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.ok()) h5fail(file, std::string("cannot create attribute '") + name + "'");
  if (H5Awrite(attr.get(), mem_type, &value) < 0) {
    h5fail(file, std::string("cannot write attribute '") + name + "'");
  }
}

// Pads `dim`-component vectors to 3 components (z = 0 in 2D).
std::vector<double> pad3(const double* a, int n, int dim) {
  std::vector<double> out(static_cast<size_t>(n) * 3, 0.0);
  if (!a) return out;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < dim; ++k) out[3 * static_cast<size_t>(i) + k] = a[static_cast<size_t>(i) * dim + k];
  return out;
}

std::string step_name(long step) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "step_%08ld", step);
  return buf;
}

// Shortest of %.15g / %.17g that reads back to the same double.
std::string fmt_double(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  if (std::strtod(buf, nullptr) != v) std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

const char* kH5Name = "snapshots.h5";
const char* kXdmfName = "snapshots.xdmf";

}  // namespace

// ------------------------------------------------------------------------------------------------
// SnapshotWriter

SnapshotWriter::SnapshotWriter(const std::string& dir, const HostMesh& mesh)
    : dir_(dir.empty() ? std::string(".") : dir),
      dim_(mesh.dim),
      nn_(mesh.num_nodes()),
      ne_(mesh.num_elems()),
      ni_(mesh.num_ifaces()) {
  create(mesh);
}

SnapshotWriter::SnapshotWriter(const std::string& dir, const HostMesh& mesh,
                               const std::vector<long>& steps, const std::vector<double>& times,
                               std::string& note)
    : dir_(dir.empty() ? std::string(".") : dir),
      dim_(mesh.dim),
      nn_(mesh.num_nodes()),
      ne_(mesh.num_elems()),
      ni_(mesh.num_ifaces()) {
  note.clear();
  std::string why;
  if (reopen(steps, times, why)) return;
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
  file_ = -1;
  times_.clear();
  steps_.clear();
  has_fragment_ = false;
  const fs::path h5 = fs::path(dir_) / kH5Name;
  std::error_code ec;
  if (fs::exists(h5, ec)) {
    fs::rename(h5, fs::path(dir_) / (std::string(kH5Name) + ".damaged"), ec);
    note = h5.string() + " cannot be continued (" + why + "); moved to " + kH5Name +
           ".damaged; the new file holds the frames from the restart on";
  } else {
    note = h5.string() + " is missing; the new file holds the frames from the restart on";
  }
  create(mesh);
}

bool SnapshotWriter::reopen(const std::vector<long>& steps, const std::vector<double>& times,
                            std::string& why) {
  silence_hdf5();
  const std::string path = (fs::path(dir_) / kH5Name).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    why = "missing";
    return false;
  }
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    why = "not a readable HDF5 file";
    return false;
  }
  H5Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  H5Pset_file_locking(fapl.get(), 0, 1);
#endif
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl.get());
  if (file < 0) {
    why = "cannot open it" + [] { const std::string r = hdf5_reason(); return r.empty() ? r : ": " + r; }();
    return false;
  }
  file_ = static_cast<long long>(file);
  auto attr = [&](const char* name, int& out) {
    hid_t a = H5Aopen_by_name(file, "/mesh", name, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) return false;
    const bool ok = H5Aread(a, H5T_NATIVE_INT, &out) >= 0;
    H5Aclose(a);
    return ok;
  };
  int d = 0, nn = 0, ne = 0, ni = 0;
  if (!attr("dim", d) || !attr("num_nodes", nn) || !attr("num_elements", ne) ||
      !attr("num_interfaces", ni)) {
    H5Eclear2(H5E_DEFAULT);
    why = "no readable /mesh";
    return false;
  }
  if (d != dim_ || nn != nn_ || ne != ne_ || ni != ni_) {
    why = "it holds another mesh";
    return false;
  }
  // frames in the file: keep those listed, delete the others (written after the checkpoint)
  std::vector<std::string> names;
  {
    H5G_info_t info;
    if (H5Gget_info(file, &info) < 0) {
      why = "cannot list its frames";
      return false;
    }
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      const ssize_t len = H5Lget_name_by_idx(file, "/", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
      if (len < 0) {
        why = "cannot list its frames";
        return false;
      }
      std::string n(static_cast<size_t>(len) + 1, '\0');
      H5Lget_name_by_idx(file, "/", H5_INDEX_NAME, H5_ITER_INC, i, n.data(), n.size(), H5P_DEFAULT);
      n.resize(static_cast<size_t>(len));
      if (n.rfind("step_", 0) == 0) names.push_back(n);
    }
  }
  std::vector<std::string> keep;
  for (long st : steps) keep.push_back(step_name(st));
  for (const auto& k : keep)
    if (std::find(names.begin(), names.end(), k) == names.end() ||
        H5Lexists(file, ("/" + k + "/damage").c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      why = "frame '" + k + "' is missing";
      return false;
    }
  for (const auto& n : names)
    if (std::find(keep.begin(), keep.end(), n) == keep.end() &&
        H5Ldelete(file, ("/" + n).c_str(), H5P_DEFAULT) < 0) {
      why = "cannot delete frame '" + n + "' written after the checkpoint";
      return false;
    }
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) {
    why = "cannot flush it";
    return false;
  }
  steps_ = steps;
  times_ = times;
  for (const auto& k : keep)
    if (H5Lexists(file, ("/" + k + "/fragment").c_str(), H5P_DEFAULT) > 0) has_fragment_ = true;
  write_xdmf();
  return true;
}

void SnapshotWriter::create(const HostMesh& mesh) {
  if (dim_ != 2 && dim_ != 3) {
    throw std::logic_error("SnapshotWriter: mesh dimension must be 2 or 3, not " +
                           std::to_string(dim_));
  }
  ensure_output_dir(dir_);
  silence_hdf5();
  const std::string path = (fs::path(dir_) / kH5Name).string();
  // A stale XDMF from an earlier run would point into the file truncated below.
  std::error_code ec;
  fs::remove(fs::path(dir_) / kXdmfName, ec);

  H5Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!fapl.ok()) h5fail(path, "cannot create file access property list");
#if H5_VERSION_GE(1, 10, 7)
  // Without locking, ParaView (or h5py) can open the file while the run is still writing it.
  H5Pset_file_locking(fapl.get(), 0, 1);
#endif
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
  if (file < 0) h5fail(path, "cannot create the file");
  file_ = static_cast<long long>(file);

  try {
    H5Id mesh_g(H5Gcreate2(file, "/mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!mesh_g.ok()) h5fail(path, "cannot create group '/mesh'");
    write_scalar_attr<int>(mesh_g.get(), "dim", H5T_STD_I32LE, H5T_NATIVE_INT, dim_, path);
    write_scalar_attr<int>(mesh_g.get(), "num_nodes", H5T_STD_I32LE, H5T_NATIVE_INT, nn_, path);
    write_scalar_attr<int>(mesh_g.get(), "num_elements", H5T_STD_I32LE, H5T_NATIVE_INT, ne_, path);
    write_scalar_attr<int>(mesh_g.get(), "num_interfaces", H5T_STD_I32LE, H5T_NATIVE_INT, ni_,
                           path);

    const hsize_t npe = static_cast<hsize_t>(dim_ + 1);
    if (mesh.elems.size() != static_cast<size_t>(ne_) * npe) {
      throw std::logic_error("SnapshotWriter: mesh.elems size is not a multiple of dim+1");
    }
    write_ints(mesh_g.get(), "elements", {static_cast<hsize_t>(ne_), npe}, mesh.elems.data(), path);

    std::vector<int> region(static_cast<size_t>(ne_), 0);
    if (mesh.elem_region.size() == region.size()) region = mesh.elem_region;
    write_ints(mesh_g.get(), "region", {static_cast<hsize_t>(ne_)}, region.data(), path);

    if (!mesh.region_names.empty()) {
      size_t len = 1;
      for (const auto& s : mesh.region_names) len = std::max(len, s.size() + 1);
      std::vector<char> buf(len * mesh.region_names.size(), '\0');
      for (size_t r = 0; r < mesh.region_names.size(); ++r)
        std::memcpy(&buf[r * len], mesh.region_names[r].data(), mesh.region_names[r].size());
      H5Id st(H5Tcopy(H5T_C_S1), H5Tclose);
      if (!st.ok() || H5Tset_size(st.get(), len) < 0 || H5Tset_strpad(st.get(), H5T_STR_NULLTERM) < 0)
        h5fail(path, "cannot create string type for '/mesh/region_names'");
      write_dataset(mesh_g.get(), "region_names", st.get(), st.get(),
                    {static_cast<hsize_t>(mesh.region_names.size())}, buf.data(), path);
    }

    std::vector<int> itopo(static_cast<size_t>(ni_) * dim_);
    for (int i = 0; i < ni_; ++i)
      for (int k = 0; k < dim_; ++k)
        itopo[static_cast<size_t>(i) * dim_ + k] = mesh.ifaces[static_cast<size_t>(2 * dim_) * i + k];
    write_ints(mesh_g.get(), "interfaces", {static_cast<hsize_t>(ni_), static_cast<hsize_t>(dim_)},
               itopo.data(), path);

    const std::vector<double> X3 = pad3(mesh.X.data(), nn_, dim_);
    write_doubles(mesh_g.get(), "reference_coordinates", {static_cast<hsize_t>(nn_), 3}, X3.data(),
                  path);
    if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5fail(path, "cannot flush");
  } catch (...) {
    H5Fclose(file);
    file_ = -1;
    throw;
  }
}

SnapshotWriter::~SnapshotWriter() {
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
}

void SnapshotWriter::write(const SnapshotFrame& fr) {
  const std::string path = (fs::path(dir_) / kH5Name).string();
  const hid_t file = static_cast<hid_t>(file_);
  if (file_ < 0) throw std::logic_error("SnapshotWriter::write: file is not open");
  const std::string gname = "/" + step_name(fr.step);
  {
    const htri_t exists = H5Lexists(file, gname.c_str(), H5P_DEFAULT);
    if (exists > 0) {
      throw std::logic_error("SnapshotWriter::write: step " + std::to_string(fr.step) +
                             " was already written to '" + path + "'");
    }
  }

  const size_t nn = static_cast<size_t>(nn_), ne = static_cast<size_t>(ne_);
  const hsize_t hn = static_cast<hsize_t>(nn_), he = static_cast<hsize_t>(ne_);

  // Missing fields are written as zeros; missing x is X + u (reference coordinates if u is absent).
  std::vector<double> x3, u3 = pad3(fr.u, nn_, dim_), v3 = pad3(fr.v, nn_, dim_);
  if (fr.x) {
    x3 = pad3(fr.x, nn_, dim_);
  } else {
    std::vector<double> X3(nn * 3);
    H5Id d(H5Dopen2(file, "/mesh/reference_coordinates", H5P_DEFAULT), H5Dclose);
    if (!d.ok() || (nn > 0 && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                      X3.data()) < 0))
      h5fail(path, "cannot read '/mesh/reference_coordinates'");
    x3.resize(nn * 3);
    for (size_t i = 0; i < nn * 3; ++i) x3[i] = X3[i] + u3[i];
  }
  std::vector<double> stress(ne * 6, 0.0), vm(ne, 0.0);
  if (fr.stress) stress.assign(fr.stress, fr.stress + ne * 6);
  for (size_t e = 0; e < ne; ++e) {
    const double* s = &stress[6 * e];
    const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
    vm[e] = std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
  }
  std::vector<double> damage(static_cast<size_t>(ni_), 0.0);
  if (fr.damage) damage.assign(fr.damage, fr.damage + ni_);

  {
    H5Id g(H5Gcreate2(file, gname.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!g.ok()) h5fail(path, "cannot create group '" + gname + "'");
    write_scalar_attr<double>(g.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, fr.time, path);
    write_scalar_attr<long long>(g.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG,
                                 static_cast<long long>(fr.step), path);
    write_doubles(g.get(), "coordinates", {hn, 3}, x3.data(), path);
    write_doubles(g.get(), "displacement", {hn, 3}, u3.data(), path);
    write_doubles(g.get(), "velocity", {hn, 3}, v3.data(), path);
    write_doubles(g.get(), "stress", {he, 6}, stress.data(), path);
    write_doubles(g.get(), "von_mises", {he}, vm.data(), path);
    write_doubles(g.get(), "damage", {static_cast<hsize_t>(ni_)}, damage.data(), path);
    if (fr.fragment) {
      write_ints(g.get(), "fragment", {he}, fr.fragment, path);
      has_fragment_ = true;
    }
  }
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5fail(path, "cannot flush after " + gname);
  times_.push_back(fr.time);
  steps_.push_back(fr.step);
  write_xdmf();
}

void SnapshotWriter::write_xdmf() const {
  const hid_t file = static_cast<hid_t>(file_);
  const std::string h5 = kH5Name;
  const std::string nn = std::to_string(nn_), ne = std::to_string(ne_), ni = std::to_string(ni_);
  const std::string npe = std::to_string(dim_ + 1);
  const char* bulk_topo = dim_ == 2 ? "Triangle" : "Tetrahedron";

  auto item = [&](const std::string& dims, bool is_int, const std::string& ds) {
    return std::string("<DataItem Dimensions=\"") + dims + "\" NumberType=\"" +
           (is_int ? "Int" : "Float") + "\" Precision=\"" + (is_int ? "4" : "8") +
           "\" Format=\"HDF\">" + h5 + ":" + ds + "</DataItem>";
  };
  // Lines of a uniform grid sit at 8 spaces, their children deeper.
  auto attr = [&](const std::string& name, const char* type, const char* center,
                  const std::string& dims, bool is_int, const std::string& ds) {
    return std::string("          <Attribute Name=\"") + name + "\" AttributeType=\"" + type +
           "\" Center=\"" + center + "\">\n            " + item(dims, is_int, ds) +
           "\n          </Attribute>\n";
  };

  std::ostringstream o;
  o << "<?xml version=\"1.0\" ?>\n"
    << "<Xdmf Version=\"3.0\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"fdem\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (size_t f = 0; f < steps_.size(); ++f) {
    const std::string g = "/" + step_name(steps_[f]);
    const std::string t = fmt_double(times_[f]);
    const std::string geom = "          <Geometry GeometryType=\"XYZ\">\n            " +
                             item(nn + " 3", false, g + "/coordinates") +
                             "\n          </Geometry>\n";
    const bool frag = H5Lexists(file, (g + "/fragment").c_str(), H5P_DEFAULT) > 0;
    o << "      <Grid Name=\"" << step_name(steps_[f])
      << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
      << "        <Time Value=\"" << t << "\"/>\n";
    // bulk
    o << "        <Grid Name=\"bulk\" GridType=\"Uniform\">\n"
      << "          <Time Value=\"" << t << "\"/>\n"
      << "          <Topology TopologyType=\"" << bulk_topo << "\" NumberOfElements=\"" << ne
      << "\" NodesPerElement=\"" << npe << "\">\n"
      << "            " << item(ne + " " + npe, true, "/mesh/elements") << "\n"
      << "          </Topology>\n"
      << geom
      << attr("displacement", "Vector", "Node", nn + " 3", false, g + "/displacement")
      << attr("velocity", "Vector", "Node", nn + " 3", false, g + "/velocity")
      << attr("stress", "Tensor6", "Cell", ne + " 6", false, g + "/stress")
      << attr("von_mises", "Scalar", "Cell", ne, false, g + "/von_mises")
      << attr("region", "Scalar", "Cell", ne, true, "/mesh/region");
    if (frag) o << attr("fragment", "Scalar", "Cell", ne, true, g + "/fragment");
    o << "        </Grid>\n";
    // interfaces (A-side nodes on the current geometry)
    if (ni_ > 0) {
      o << "        <Grid Name=\"interfaces\" GridType=\"Uniform\">\n"
        << "          <Time Value=\"" << t << "\"/>\n";
      if (dim_ == 2) {
        o << "          <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << ni
          << "\" NodesPerElement=\"2\">\n";
      } else {
        o << "          <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << ni
          << "\" NodesPerElement=\"3\">\n";
      }
      o << "            " << item(ni + " " + std::to_string(dim_), true, "/mesh/interfaces")
        << "\n"
        << "          </Topology>\n"
        << geom << attr("damage", "Scalar", "Cell", ni, false, g + "/damage")
        << "        </Grid>\n";
    }
    o << "      </Grid>\n";
  }
  o << "    </Grid>\n"
    << "  </Domain>\n"
    << "</Xdmf>\n";
  write_file_atomic((fs::path(dir_) / kXdmfName).string(), o.str());
}

}  // namespace fdem
