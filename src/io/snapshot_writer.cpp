// SnapshotWriter: HDF5 snapshots (the XDMF that describes them: src/io/snapshot_xdmf.cpp).
//
// snapshots.h5 layout (all datasets little-endian; float64 unless noted):
//   /mesh                      attributes: dim (int32), num_nodes, num_elements, num_interfaces
//   /mesh/elements             int32, ne x (dim+1)
//   /mesh/region               int32, ne
//   /mesh/region_names         fixed-length strings, one per region (absent if the mesh has none)
//   /mesh/interfaces           int32, ni x dim   (A-side node ids of each interface)
//   /mesh/reference_coordinates nn x 3 (z = 0 in 2D)
//   /mesh/interface_material   int32, ni: index into interface_material_names (only with
//                              interface materials by place or a strength scatter)
//   /mesh/interface_material_names  fixed-length strings (with interface_material)
//   /mesh/strength_factor      ni (only with a strength scatter)
//   /step_NNNNNNNN             attributes: time (float64), step (int64)
//     coordinates, displacement, velocity   nn x 3 (z = 0 in 2D)
//     stress                   ne x 6 (xx, yy, zz, xy, yz, xz)
//     von_mises                ne
//     damage                   ni
//     fragment                 int32, ne (only if the frame has one)
// snapshots.xdmf (XDMF 3) references these datasets as "snapshots.h5:/path".
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/hdf5_util.hpp"
#include "io/output.hpp"
#include "io/snapshot_internal.hpp"

namespace fdem {

namespace fs = std::filesystem;
using snapshot::kH5Name;
using snapshot::step_name;

namespace {

using h5::Id;
using h5::write_doubles;
using h5::write_ints;


void write_int_attr(hid_t loc, const char* name, int value, const std::string& file) {
  h5::write_scalar_attr<int>(loc, name, H5T_STD_I32LE, H5T_NATIVE_INT, value, file);
}

// Pads `dim`-component vectors to 3 components (z = 0 in 2D).
std::vector<double> pad3(const double* a, int n, int dim) {
  std::vector<double> out(static_cast<size_t>(n) * 3, 0.0);
  if (!a) return out;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < dim; ++k)
      out[3 * static_cast<size_t>(i) + k] = a[static_cast<size_t>(i) * dim + k];
  return out;
}

// ------------------------------------------------------------------------------------------------
// Steps of continuing a file (restart)

// Opens an existing snapshots.h5 for writing; -1 (and `why`) when it is missing, not HDF5 or
// cannot be opened.
hid_t open_existing(const std::string& path, std::string& why) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    why = "missing";
    return -1;
  }
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    why = "not a readable HDF5 file";
    return -1;
  }
  Id fapl = h5::file_access_without_locking();
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl.get());
  if (file < 0) {
    const std::string r = h5::reason();
    why = "cannot open it" + (r.empty() ? r : ": " + r);
  }
  return file;
}

// Whether /mesh of `file` is a mesh of these sizes; `why` says what is wrong if not.
bool mesh_matches(hid_t file, int dim, int nn, int ne, int ni, std::string& why) {
  Id g(H5Gopen2(file, "/mesh", H5P_DEFAULT), H5Gclose);
  int d = 0, n = 0, e = 0, i = 0;
  if (!g.ok() || !h5::read_scalar_attr(g.get(), "dim", H5T_NATIVE_INT, d) ||
      !h5::read_scalar_attr(g.get(), "num_nodes", H5T_NATIVE_INT, n) ||
      !h5::read_scalar_attr(g.get(), "num_elements", H5T_NATIVE_INT, e) ||
      !h5::read_scalar_attr(g.get(), "num_interfaces", H5T_NATIVE_INT, i)) {
    H5Eclear2(H5E_DEFAULT);
    why = "no readable /mesh";
    return false;
  }
  if (d != dim || n != nn || e != ne || i != ni) {
    why = "it holds another mesh";
    return false;
  }
  return true;
}

// The frames (groups step_*) in the root group of `file`; false if they cannot be listed.
bool list_frames(hid_t file, std::vector<std::string>& names) {
  H5G_info_t info;
  if (H5Gget_info(file, &info) < 0) return false;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len =
        H5Lget_name_by_idx(file, "/", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) return false;
    std::string n(static_cast<size_t>(len) + 1, '\0');
    H5Lget_name_by_idx(file, "/", H5_INDEX_NAME, H5_ITER_INC, i, n.data(), n.size(), H5P_DEFAULT);
    n.resize(static_cast<size_t>(len));
    if (n.rfind("step_", 0) == 0) names.push_back(n);
  }
  return true;
}

// Checks that every frame of `keep` is in the file (complete) and deletes the frames of `names`
// not in `keep`; false (and `why`) on failure.
bool keep_only(hid_t file, const std::vector<std::string>& names,
               const std::vector<std::string>& keep, std::string& why) {
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
  return true;
}

// ------------------------------------------------------------------------------------------------
// Steps of starting a file

struct MeshSizes {
  int dim, nn, ne, ni;
};

// Creates (truncates) `path`, without file locking.
hid_t create_file(const std::string& path) {
  Id fapl = h5::file_access_without_locking();
  if (!fapl.ok()) h5::fail(path, "cannot create file access property list");
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
  if (file < 0) h5::fail(path, "cannot create the file");
  return file;
}

// /mesh/<dataset> (region_names, interface_material_names): fixed-length NUL-terminated strings
// as long as the longest name.
void write_names(hid_t mesh_g, const std::vector<std::string>& names, const std::string& path,
                 const std::string& dataset = "region_names") {
  size_t len = 1;
  for (const auto& s : names) len = std::max(len, s.size() + 1);
  std::vector<char> buf(len * names.size(), '\0');
  for (size_t r = 0; r < names.size(); ++r) std::memcpy(&buf[r * len], names[r].data(), names[r].size());
  Id st(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!st.ok() || H5Tset_size(st.get(), len) < 0 || H5Tset_strpad(st.get(), H5T_STR_NULLTERM) < 0)
    h5::fail(path, "cannot create string type for '/mesh/" + dataset + "'");
  h5::write_dataset(mesh_g, dataset, st.get(), st.get(),
                    {static_cast<hsize_t>(names.size())}, buf.data(), path);
}

// The group /mesh with its sizes and region names, without its datasets (those of a run over
// processes may come from every process's rows: src/io/snapshot_parallel.hpp); flushed.
void create_mesh_group(hid_t file, const MeshSizes& m, const std::vector<std::string>& region_names,
                       const std::string& path) {
  Id mesh_g(H5Gcreate2(file, "/mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!mesh_g.ok()) h5::fail(path, "cannot create group '/mesh'");
  const hid_t g = mesh_g.get();
  write_int_attr(g, "dim", m.dim, path);
  write_int_attr(g, "num_nodes", m.nn, path);
  write_int_attr(g, "num_elements", m.ne, path);
  write_int_attr(g, "num_interfaces", m.ni, path);
  if (!region_names.empty()) write_names(g, region_names, path);
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush");
}

// The datasets of /mesh: topology, regions, interfaces (A-side nodes), reference coordinates;
// then flushes the file.
void write_mesh_datasets(hid_t file, const HostMesh& mesh, const MeshSizes& m, const std::string& path) {
  Id mesh_g(H5Gopen2(file, "/mesh", H5P_DEFAULT), H5Gclose);
  if (!mesh_g.ok()) h5::fail(path, "cannot open group '/mesh'");
  const hid_t g = mesh_g.get();
  const hsize_t npe = static_cast<hsize_t>(m.dim + 1);
  if (mesh.elems.size() != static_cast<size_t>(m.ne) * npe) {
    throw std::logic_error("SnapshotWriter: mesh.elems size is not a multiple of dim+1");
  }
  write_ints(g, "elements", {static_cast<hsize_t>(m.ne), npe}, mesh.elems.data(), path);

  std::vector<int> region(static_cast<size_t>(m.ne), 0);
  if (mesh.elem_region.size() == region.size()) region = mesh.elem_region;
  write_ints(g, "region", {static_cast<hsize_t>(m.ne)}, region.data(), path);

  std::vector<int> itopo(static_cast<size_t>(m.ni) * m.dim);
  for (int i = 0; i < m.ni; ++i)
    for (int k = 0; k < m.dim; ++k)
      itopo[static_cast<size_t>(i) * m.dim + k] = mesh.ifaces[static_cast<size_t>(2 * m.dim) * i + k];
  write_ints(g, "interfaces", {static_cast<hsize_t>(m.ni), static_cast<hsize_t>(m.dim)},
             itopo.data(), path);

  const std::vector<double> X3 = pad3(mesh.X.data(), m.nn, m.dim);
  write_doubles(g, "reference_coordinates", {static_cast<hsize_t>(m.nn), 3}, X3.data(), path);
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush");
}

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

SnapshotWriter::SnapshotWriter(const std::string& dir, const MeshShell& shell)
    : dir_(dir.empty() ? std::string(".") : dir),
      dim_(shell.dim),
      nn_(static_cast<int>(shell.nodes)),
      ne_(static_cast<int>(shell.elems)),
      ni_(static_cast<int>(shell.ifaces)),
      shell_(true) {
  HostMesh names;
  names.dim = shell.dim;
  names.region_names = shell.region_names;
  create(names);
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
  fragment_.clear();
  imat_ = istrength_ = false;
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
  h5::silence();
  const hid_t file = open_existing((fs::path(dir_) / kH5Name).string(), why);
  if (file < 0) return false;
  file_ = static_cast<long long>(file);
  if (!mesh_matches(file, dim_, nn_, ne_, ni_, why)) return false;
  // frames in the file: keep those listed, delete the others (written after the checkpoint)
  std::vector<std::string> names;
  if (!list_frames(file, names)) {
    why = "cannot list its frames";
    return false;
  }
  std::vector<std::string> keep;
  for (long st : steps) keep.push_back(step_name(st));
  if (!keep_only(file, names, keep, why)) return false;
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) {
    why = "cannot flush it";
    return false;
  }
  steps_ = steps;
  times_ = times;
  for (const auto& k : keep)
    fragment_.push_back(H5Lexists(file, ("/" + k + "/fragment").c_str(), H5P_DEFAULT) > 0);
  imat_ = H5Lexists(file, "/mesh/interface_material", H5P_DEFAULT) > 0;
  istrength_ = H5Lexists(file, "/mesh/strength_factor", H5P_DEFAULT) > 0;
  write_xdmf();
  return true;
}

void SnapshotWriter::create(const HostMesh& mesh) {
  if (dim_ != 2 && dim_ != 3) {
    throw std::logic_error("SnapshotWriter: mesh dimension must be 2 or 3, not " +
                           std::to_string(dim_));
  }
  ensure_output_dir(dir_);
  h5::silence();
  const std::string path = (fs::path(dir_) / kH5Name).string();
  // A stale XDMF from an earlier run would point into the file truncated below.
  std::error_code ec;
  fs::remove(fs::path(dir_) / snapshot::kXdmfName, ec);

  const hid_t file = create_file(path);
  file_ = static_cast<long long>(file);
  try {
    create_mesh_group(file, MeshSizes{dim_, nn_, ne_, ni_}, mesh.region_names, path);
    if (!shell_) write_mesh_datasets(file, mesh, MeshSizes{dim_, nn_, ne_, ni_}, path);
  } catch (...) {
    H5Fclose(file);
    file_ = -1;
    throw;
  }
}

SnapshotWriter::~SnapshotWriter() {
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
}

void SnapshotWriter::add_interface_fields(const std::vector<std::string>& names, const std::vector<int>& material,
                                          const std::vector<float>& strength) {
  const std::string path = (fs::path(dir_) / kH5Name).string();
  const hid_t file = static_cast<hid_t>(file_);
  if (file_ < 0) throw std::logic_error("SnapshotWriter::add_interface_fields: file is not open");
  if (material.size() != static_cast<size_t>(ni_) || (!strength.empty() && strength.size() != material.size()))
    throw std::logic_error("SnapshotWriter::add_interface_fields: one value per interface is needed");
  if (H5Lexists(file, "/mesh/interface_material", H5P_DEFAULT) > 0) return;  // restart: written
  Id g(H5Gopen2(file, "/mesh", H5P_DEFAULT), H5Gclose);
  if (!g.ok()) h5::fail(path, "cannot open group '/mesh'");
  const hsize_t n = static_cast<hsize_t>(ni_);
  write_ints(g.get(), "interface_material", {n}, material.data(), path);
  write_names(g.get(), names, path, "interface_material_names");
  if (!strength.empty()) {
    const std::vector<double> w(strength.begin(), strength.end());
    write_doubles(g.get(), "strength_factor", {n}, w.data(), path);
  }
  imat_ = true;
  istrength_ = !strength.empty();
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush");
  write_xdmf();
}

void SnapshotWriter::write_mesh(const HostMesh& mesh) {
  const std::string path = (fs::path(dir_) / kH5Name).string();
  if (!shell_ || file_ < 0) throw std::logic_error("SnapshotWriter::write_mesh: not a shell, or the file is closed");
  if (mesh.num_nodes() != nn_ || mesh.num_elems() != ne_ || mesh.num_ifaces() != ni_ || mesh.dim != dim_)
    throw std::logic_error("SnapshotWriter::write_mesh: another mesh than the shell's");
  write_mesh_datasets(static_cast<hid_t>(file_), mesh, MeshSizes{dim_, nn_, ne_, ni_}, path);
  shell_ = false;
}

void SnapshotWriter::interface_fields_by_rows(const std::vector<std::string>& names, bool strength) {
  const std::string path = (fs::path(dir_) / kH5Name).string();
  if (!shell_ || file_ < 0)
    throw std::logic_error("SnapshotWriter::interface_fields_by_rows: not a shell, or the file is closed");
  Id g(H5Gopen2(static_cast<hid_t>(file_), "/mesh", H5P_DEFAULT), H5Gclose);
  if (!g.ok()) h5::fail(path, "cannot open group '/mesh'");
  write_names(g.get(), names, path, "interface_material_names");
  if (H5Fflush(static_cast<hid_t>(file_), H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush");
  imat_ = true;
  istrength_ = strength;
}

void SnapshotWriter::close_file() {
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
  file_ = -1;
}

void SnapshotWriter::frame_written(double time, long step, bool fragment) {
  if (file_ >= 0) throw std::logic_error("SnapshotWriter::frame_written: the file is still open here");
  times_.push_back(time);
  steps_.push_back(step);
  fragment_.push_back(fragment);
  write_xdmf();
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
    Id d(H5Dopen2(file, "/mesh/reference_coordinates", H5P_DEFAULT), H5Dclose);
    if (!d.ok() || (nn > 0 && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                      X3.data()) < 0))
      h5::fail(path, "cannot read '/mesh/reference_coordinates'");
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
    Id g(H5Gcreate2(file, gname.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!g.ok()) h5::fail(path, "cannot create group '" + gname + "'");
    h5::write_scalar_attr<double>(g.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, fr.time, path);
    h5::write_scalar_attr<long long>(g.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG,
                                 static_cast<long long>(fr.step), path);
    write_doubles(g.get(), "coordinates", {hn, 3}, x3.data(), path);
    write_doubles(g.get(), "displacement", {hn, 3}, u3.data(), path);
    write_doubles(g.get(), "velocity", {hn, 3}, v3.data(), path);
    write_doubles(g.get(), "stress", {he, 6}, stress.data(), path);
    write_doubles(g.get(), "von_mises", {he}, vm.data(), path);
    write_doubles(g.get(), "damage", {static_cast<hsize_t>(ni_)}, damage.data(), path);
    if (fr.fragment) {
      write_ints(g.get(), "fragment", {he}, fr.fragment, path);
    }
  }
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush after " + gname);
  fragment_.push_back(fr.fragment != nullptr);
  times_.push_back(fr.time);
  steps_.push_back(fr.step);
  write_xdmf();
}

}  // namespace fdem
