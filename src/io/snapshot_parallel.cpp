// ParallelFrames: one snapshot frame written by every process into snapshots.h5 with MPI-IO
// (src/io/snapshot_parallel.hpp). Each dataset is created by all processes with the whole mesh's
// shape; each process selects the rows of its own items (sorted by their whole-mesh index, as runs
// of consecutive rows) and all write together. Every row has one owner, so every row is written
// once and no fill values are written.
#include "io/snapshot_parallel.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <utility>
#include <vector>

#include "io/hdf5_util.hpp"
#include "io/snapshot_internal.hpp"

namespace fdem {

namespace {

using h5::Id;

// A process's own rows in increasing whole-mesh index, and the runs of consecutive indices.
struct Rows {
  std::vector<size_t> order;  // local rows
  h5::Runs runs;              // (first whole index, length)
};

Rows sorted_rows(const int* ids, size_t n) {
  Rows r;
  r.order = h5::order_by(ids, n);
  for (size_t i : r.order) r.runs.add(static_cast<hsize_t>(ids[i]), 1);
  return r;
}

// Values of the rows in `r.order`, `width` each, padded or cut to `out_width` columns (zeros).
template <class T>
std::vector<T> pack(const T* a, size_t width, size_t out_width, const Rows& r) {
  std::vector<T> out(r.order.size() * out_width, T{});
  for (size_t k = 0; k < r.order.size(); ++k)
    for (size_t c = 0; c < std::min(width, out_width); ++c)
      out[k * out_width + c] = a[r.order[k] * width + c];
  return out;
}

struct Target {
  hid_t group, dxpl;
  const std::string& path;
};

// The dataset `name` of `whole` rows of `width` values (one-dimensional when width is 0), of which
// this process writes the rows `r` from `packed` (in r's order). Collective.
void write_rows(const Target& t, const std::string& name, hid_t file_type, hid_t mem_type,
                hsize_t whole, hsize_t width, const Rows& r, const void* packed) {
  const hsize_t w = width ? width : 1;
  const hsize_t dims[2] = {whole, w};
  Id fspace(H5Screate_simple(width ? 2 : 1, dims, nullptr), H5Sclose);
  Id dcpl = h5::written_once();
  if (!fspace.ok() || !dcpl.ok()) h5::fail(t.path, "cannot prepare dataset '" + name + "'");
  Id dset(H5Dcreate2(t.group, name.c_str(), file_type, fspace.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
          H5Dclose);
  if (!dset.ok()) h5::fail(t.path, "cannot create dataset '" + name + "'");
  if (whole == 0) return;  // no rows anywhere (a case without interfaces): nothing to write
  const hsize_t n = static_cast<hsize_t>(r.order.size()) * w;
  Id mspace = h5::memory_space(n);
  if (!h5::select_runs(fspace.get(), r.runs) || !mspace.ok())
    h5::fail(t.path, "cannot select this process's rows of '" + name + "'");
  static const double none = 0;
  if (H5Dwrite(dset.get(), mem_type, mspace.get(), fspace.get(), t.dxpl, n > 0 ? packed : &none) < 0)
    h5::fail(t.path, "cannot write dataset '" + name + "'");
}

}  // namespace

ParallelFrames::ParallelFrames(long long fapl) : fapl_(fapl) {
#if H5_VERSION_GE(1, 10, 7)
  // process 0 wrote /mesh with its own (serial) handle, closed before every frame
  if (fapl_ >= 0) H5Pset_file_locking(static_cast<hid_t>(fapl_), 0, 1);
#endif
}

ParallelFrames::~ParallelFrames() {
  if (file_ >= 0) H5Fclose(static_cast<hid_t>(file_));
  if (fapl_ >= 0) H5Pclose(static_cast<hid_t>(fapl_));
}

// The file, opened on every process at the first call (kept open); a collective transfer list.
long long ParallelFrames::open(const std::string& path) const {
  h5::silence();
  if (file_ < 0) {
    file_ = H5Fopen(path.c_str(), H5F_ACC_RDWR, static_cast<hid_t>(fapl_));
    if (file_ < 0) h5::fail(path, "cannot open it on every process (MPI-IO)");
  }
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  if (dxpl < 0) h5::fail(path, "cannot create a transfer property list");
#ifdef H5_HAVE_PARALLEL
  if (H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE) < 0) {
    H5Pclose(dxpl);
    h5::fail(path, "cannot ask for collective writes");
  }
#endif
  return dxpl;
}

void ParallelFrames::write_mesh(const std::string& dir, const MeshPart& m) const {
  const std::string path = (std::filesystem::path(dir.empty() ? "." : dir) / snapshot::kH5Name).string();
  Id dxpl(static_cast<hid_t>(open(path)), H5Pclose);
  const hid_t file = static_cast<hid_t>(file_);
  Id g(H5Gopen2(file, "/mesh", H5P_DEFAULT), H5Gclose);
  if (!g.ok()) h5::fail(path, "cannot open group '/mesh'");
  const Target t{g.get(), dxpl.get(), path};
  const size_t dim = static_cast<size_t>(m.dim), npe = dim + 1;
  // (the order SnapshotWriter writes them in)
  const Rows elems = sorted_rows(m.elem_ids, m.elems);
  const hsize_t ne = static_cast<hsize_t>(m.whole_elems);
  const std::vector<int> topo = pack(m.elements, npe, npe, elems);
  write_rows(t, "elements", H5T_STD_I32LE, H5T_NATIVE_INT, ne, npe, elems, topo.data());
  const std::vector<int> region = pack(m.region, 1, 1, elems);
  write_rows(t, "region", H5T_STD_I32LE, H5T_NATIVE_INT, ne, 0, elems, region.data());
  const Rows ifaces = sorted_rows(m.iface_ids, m.ifaces);
  const hsize_t ni = static_cast<hsize_t>(m.whole_ifaces);
  const std::vector<int> itopo = pack(m.interfaces, dim, dim, ifaces);
  write_rows(t, "interfaces", H5T_STD_I32LE, H5T_NATIVE_INT, ni, dim, ifaces, itopo.data());
  const Rows nodes = sorted_rows(m.node_ids, m.nodes);
  const std::vector<double> X3 = pack(m.X, dim, 3, nodes);
  write_rows(t, "reference_coordinates", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, static_cast<hsize_t>(m.whole_nodes), 3,
             nodes, X3.data());
  if (m.with_material) {
    const std::vector<int> mat = pack(m.material, 1, 1, ifaces);
    write_rows(t, "interface_material", H5T_STD_I32LE, H5T_NATIVE_INT, ni, 0, ifaces, mat.data());
  }
  if (m.with_strength) {
    const std::vector<double> w = pack(m.strength, 1, 1, ifaces);
    write_rows(t, "strength_factor", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ni, 0, ifaces, w.data());
  }
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush after /mesh");
}

void ParallelFrames::write(const std::string& dir, const FramePart& f) const {
  const std::string path = (std::filesystem::path(dir.empty() ? "." : dir) / snapshot::kH5Name).string();
  Id dxpl(static_cast<hid_t>(open(path)), H5Pclose);
  const hid_t file = static_cast<hid_t>(file_);
  const std::string gname = "/" + snapshot::step_name(f.step);
  Id g(H5Gcreate2(file, gname.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!g.ok()) h5::fail(path, "cannot create group '" + gname + "'");
  h5::write_scalar_attr<double>(g.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f.time, path);
  h5::write_scalar_attr<long long>(g.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG,
                                   static_cast<long long>(f.step), path);
  const Target t{g.get(), dxpl.get(), path};
  const size_t dim = static_cast<size_t>(f.dim);

  const Rows nodes = sorted_rows(f.node_ids, f.nodes);
  const hsize_t nn = static_cast<hsize_t>(f.whole_nodes);
  const std::pair<const char*, const double*> vectors[] = {
      {"coordinates", f.x}, {"displacement", f.u}, {"velocity", f.v}};
  for (const auto& [name, a] : vectors) {
    const std::vector<double> p = pack(a, dim, 3, nodes);
    write_rows(t, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, nn, 3, nodes, p.data());
  }

  const Rows elems = sorted_rows(f.elem_ids, f.elems);
  const hsize_t ne = static_cast<hsize_t>(f.whole_elems);
  const std::vector<double> s = pack(f.stress, 6, 6, elems);
  write_rows(t, "stress", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ne, 6, elems, s.data());
  std::vector<double> vm(elems.order.size());
  for (size_t e = 0; e < vm.size(); ++e) {  // as SnapshotWriter::write
    const double* q = &s[6 * e];
    const double a = q[0] - q[1], b = q[1] - q[2], c = q[2] - q[0];
    vm[e] = std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (q[3] * q[3] + q[4] * q[4] + q[5] * q[5]));
  }
  write_rows(t, "von_mises", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ne, 0, elems, vm.data());

  const Rows ifaces = sorted_rows(f.iface_ids, f.ifaces);
  const std::vector<double> d = pack(f.damage, 1, 1, ifaces);
  write_rows(t, "damage", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, static_cast<hsize_t>(f.whole_ifaces), 0,
             ifaces, d.data());

  if (f.has_fragment) {  // every process its own elements' ids (solver/fragment_parts.hpp)
    const std::vector<int> fr = pack(f.fragment, 1, 1, elems);
    write_rows(t, "fragment", H5T_STD_I32LE, H5T_NATIVE_INT, ne, 0, elems, fr.data());
  }
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) h5::fail(path, "cannot flush after " + gname);
}

}  // namespace fdem
