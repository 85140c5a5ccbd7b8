// Output module: snapshots (HDF5 + XDMF), history.csv, output directory checks.
#include <hdf5.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/output.hpp"
#include "io/snapshot_parallel.hpp"
#include "mesh/mesh.hpp"
#include "test_files.hpp"

namespace fs = std::filesystem;
using fdem::HostMesh;

namespace {

std::string fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("fdem_test_output_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  return d.string();
}

using fdem::test::slurp;

// Two triangles sharing the edge (1,2) that has been split: 6 nodes, 1 interface.
//   element 0: nodes 0,1,2   element 1: nodes 3,5,4 (copies 4 of 1 and 5 of 2, node 3 at (1,1))
HostMesh mesh2d() {
  HostMesh m;
  m.dim = 2;
  m.X = {0, 0, 1, 0, 0, 1, 1, 1, 1, 0, 0, 1};
  m.elems = {0, 1, 2, 3, 5, 4};
  m.elem_region = {0, 1};
  m.region_names = {"rock", "inclusion"};
  // Interface: A side (1, 2), B side (4, 5).
  m.ifaces = {1, 2, 4, 5};
  m.iface_elems = {0, 1};
  m.node_origin = {0, 1, 2, 3, 1, 2};
  return m;
}

// Two tetrahedra sharing the face (1,2,3), split: 8 nodes, 1 interface.
HostMesh mesh3d() {
  HostMesh m;
  m.dim = 3;
  m.X = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.elems = {0, 1, 2, 3, 4, 5, 7, 6};
  m.elem_region = {0, 0};
  m.region_names = {"body"};
  m.ifaces = {1, 2, 3, 5, 6, 7};
  m.iface_elems = {0, 1};
  m.node_origin = {0, 1, 2, 3, 4, 1, 2, 3};
  return m;
}

struct FrameData {
  std::vector<double> x, u, v, stress, damage;
  std::vector<int> fragment;
};

FrameData make_frame(const HostMesh& m, int k) {
  FrameData f;
  const int nn = m.num_nodes(), ne = m.num_elems(), ni = m.num_ifaces(), d = m.dim;
  for (int i = 0; i < nn * d; ++i) {
    f.u.push_back(0.001 * (i + 1) * (k + 1));
    f.v.push_back(-0.5 * i + k);
    f.x.push_back(m.X[i] + f.u.back());
  }
  for (int e = 0; e < ne * 6; ++e) f.stress.push_back(1.0e6 * (e + 1) + 17.25 * k);
  for (int i = 0; i < ni; ++i) f.damage.push_back(0.25 * (k + 1) + 0.125 * i);
  for (int e = 0; e < ne; ++e) f.fragment.push_back(e + 10 * k);
  return f;
}

double von_mises(const double* s) {
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

// Reads a dataset of any rank; returns its dimensions and data converted to `mem_type`.
template <typename T>
std::vector<T> read_ds(hid_t file, const std::string& name, hid_t mem_type,
                       std::vector<hsize_t>* dims_out) {
  hid_t d = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(d, 0) << name;
  if (d < 0) return {};
  hid_t s = H5Dget_space(d);
  const int rank = H5Sget_simple_extent_ndims(s);
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(s, dims.data(), nullptr);
  hsize_t n = 1;
  for (auto x : dims) n *= x;
  std::vector<T> out(n);
  if (n) {
    EXPECT_GE(H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), 0) << name;
  }
  H5Sclose(s);
  H5Dclose(d);
  if (dims_out) *dims_out = dims;
  return out;
}

std::vector<double> read_d(hid_t f, const std::string& n, std::vector<hsize_t>* dims = nullptr) {
  return read_ds<double>(f, n, H5T_NATIVE_DOUBLE, dims);
}
std::vector<int> read_i(hid_t f, const std::string& n, std::vector<hsize_t>* dims = nullptr) {
  return read_ds<int>(f, n, H5T_NATIVE_INT, dims);
}

template <typename T>
T read_attr(hid_t file, const std::string& obj, const char* name, hid_t mem_type) {
  T v{};
  hid_t a = H5Aopen_by_name(file, obj.c_str(), name, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(a, 0) << obj << "@" << name;
  if (a >= 0) {
    EXPECT_GE(H5Aread(a, mem_type, &v), 0);
    H5Aclose(a);
  }
  return v;
}

std::vector<double> pad3(const std::vector<double>& a, int dim) {
  std::vector<double> out;
  for (size_t i = 0; i < a.size() / dim; ++i)
    for (int k = 0; k < 3; ++k) out.push_back(k < dim ? a[i * dim + k] : 0.0);
  return out;
}

// Checks every DataItem in the XDMF: the dataset exists and has the stated dimensions. Returns
// the number of DataItems checked.
int check_xdmf_against_h5(const std::string& dir) {
  const std::string xml = slurp(dir + "/snapshots.xdmf");
  EXPECT_NE(xml.find("CollectionType=\"Temporal\""), std::string::npos);
  hid_t f = H5Fopen((dir + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0);
  // Each reference reads <DataItem Dimensions="D1 D2" ...>FILE:/PATH</DataItem>.
  const std::string open = "<DataItem Dimensions=\"", close = "</DataItem>";
  int count = 0;
  for (size_t pos = xml.find(open); pos != std::string::npos; pos = xml.find(open, pos + 1)) {
    const size_t dims_begin = pos + open.size();
    const size_t dims_end = xml.find('"', dims_begin);
    const size_t text_begin = xml.find('>', dims_end) + 1;
    const size_t text_end = xml.find(close, text_begin);
    if (text_end == std::string::npos) {
      ADD_FAILURE() << "unterminated DataItem";
      break;
    }
    const std::string dims_s = xml.substr(dims_begin, dims_end - dims_begin);
    const std::string text = xml.substr(text_begin, text_end - text_begin);
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
      ADD_FAILURE() << "DataItem is not FILE:/PATH: " << text;
      continue;
    }
    const std::string file = text.substr(0, colon), path = text.substr(colon + 1);
    ++count;
    EXPECT_EQ(file, "snapshots.h5");
    std::vector<hsize_t> want;
    std::istringstream ds(dims_s);
    for (hsize_t v; ds >> v;) want.push_back(v);
    if (H5Lexists(f, path.c_str(), H5P_DEFAULT) <= 0) {
      ADD_FAILURE() << "XDMF refers to missing dataset " << path;
      continue;
    }
    hid_t d = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
    hid_t s = H5Dget_space(d);
    std::vector<hsize_t> have(static_cast<size_t>(H5Sget_simple_extent_ndims(s)));
    H5Sget_simple_extent_dims(s, have.data(), nullptr);
    EXPECT_EQ(have, want) << path;
    H5Sclose(s);
    H5Dclose(d);
  }
  H5Fclose(f);
  return count;
}

// A python3 that can import h5py, or "" if none.
std::string python_with_h5py() {
  static const std::string found = [] {
    for (const char* py : {"python3", "/usr/bin/python3"}) {
      const std::string cmd = std::string(py) + " -c \"import h5py\" >/dev/null 2>&1";
      if (std::system(cmd.c_str()) == 0) return std::string(py);
    }
    return std::string();
  }();
  return found;
}

int run_checker(const std::string& dir) {
  const std::string py = python_with_h5py();
  if (py.empty()) return -1;
  const std::string cmd =
      py + " " + FDEM_SOURCE_DIR + "/scripts/check_snapshots.py " + dir + " > " + dir + "/check.txt 2>&1";
  const int rc = std::system(cmd.c_str());
  std::printf("%s", slurp(dir + "/check.txt").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 255;
}

// Writes two frames (the second with a fragment field) and checks everything read back.
void roundtrip(const HostMesh& m, const std::string& dir) {
  const int nn = m.num_nodes(), ne = m.num_elems(), ni = m.num_ifaces(), d = m.dim;
  std::vector<FrameData> frames = {make_frame(m, 0), make_frame(m, 1)};
  const double times[2] = {0.0, 1.25e-4};
  const long steps[2] = {0, 400};
  {
    fdem::SnapshotWriter w(dir, m);
    for (int k = 0; k < 2; ++k) {
      fdem::SnapshotFrame fr;
      fr.time = times[k];
      fr.step = steps[k];
      fr.x = frames[k].x.data();
      fr.u = frames[k].u.data();
      fr.v = frames[k].v.data();
      fr.stress = frames[k].stress.data();
      fr.damage = frames[k].damage.data();
      fr.fragment = k == 1 ? frames[k].fragment.data() : nullptr;
      w.write(fr);
      EXPECT_EQ(w.frames(), k + 1);
      // The XDMF is complete after every frame.
      EXPECT_NE(slurp(dir + "/snapshots.xdmf").find("</Xdmf>"), std::string::npos);
      EXPECT_FALSE(fs::exists(dir + "/snapshots.xdmf.tmp"));
    }
  }

  hid_t f = H5Fopen((dir + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dims;
  EXPECT_EQ(read_i(f, "/mesh/elements", &dims), m.elems);
  EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ne), hsize_t(d + 1)}));
  EXPECT_EQ(read_i(f, "/mesh/region", &dims), m.elem_region);
  EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ne)}));
  std::vector<int> ia;
  for (int i = 0; i < ni; ++i)
    for (int k = 0; k < d; ++k) ia.push_back(m.ifaces[2 * d * i + k]);
  EXPECT_EQ(read_i(f, "/mesh/interfaces", &dims), ia);
  EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ni), hsize_t(d)}));
  EXPECT_EQ(read_d(f, "/mesh/reference_coordinates", &dims), pad3(m.X, d));
  EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(nn), 3}));
  EXPECT_EQ(read_attr<int>(f, "/mesh", "dim", H5T_NATIVE_INT), d);

  for (int k = 0; k < 2; ++k) {
    char g[64];
    std::snprintf(g, sizeof g, "/step_%08ld", steps[k]);
    const std::string G = g;
    EXPECT_EQ(read_attr<double>(f, G, "time", H5T_NATIVE_DOUBLE), times[k]);
    EXPECT_EQ(read_attr<long long>(f, G, "step", H5T_NATIVE_LLONG), steps[k]);
    EXPECT_EQ(read_d(f, G + "/coordinates", &dims), pad3(frames[k].x, d));
    EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(nn), 3}));
    EXPECT_EQ(read_d(f, G + "/displacement"), pad3(frames[k].u, d));
    EXPECT_EQ(read_d(f, G + "/velocity"), pad3(frames[k].v, d));
    EXPECT_EQ(read_d(f, G + "/stress", &dims), frames[k].stress);
    EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ne), 6}));
    const auto vm = read_d(f, G + "/von_mises", &dims);
    EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ne)}));
    for (int e = 0; e < ne; ++e) EXPECT_EQ(vm[e], von_mises(&frames[k].stress[6 * e]));
    EXPECT_EQ(read_d(f, G + "/damage", &dims), frames[k].damage);
    EXPECT_EQ(dims, (std::vector<hsize_t>{hsize_t(ni)}));
    if (k == 1) {
      EXPECT_EQ(read_i(f, G + "/fragment"), frames[k].fragment);
    } else {
      EXPECT_EQ(H5Lexists(f, (G + "/fragment").c_str(), H5P_DEFAULT), 0);
    }
  }
  H5Fclose(f);

  const std::string xml = slurp(dir + "/snapshots.xdmf");
  EXPECT_NE(xml.find(d == 2 ? "TopologyType=\"Triangle\"" : "TopologyType=\"Tetrahedron\""),
            std::string::npos);
  EXPECT_NE(xml.find(d == 2 ? "TopologyType=\"Polyline\"" : "Name=\"interfaces\""),
            std::string::npos);
  EXPECT_NE(xml.find("AttributeType=\"Tensor6\""), std::string::npos);
  EXPECT_NE(xml.find("<Time Value=\"0.000125\"/>"), std::string::npos);
  // fragment only in the second frame
  EXPECT_EQ(xml.find("/step_00000000/fragment"), std::string::npos);
  EXPECT_NE(xml.find("/step_00000400/fragment"), std::string::npos);
  // 2 frames x (bulk: topology, geometry, 5 attributes (+fragment in frame 2);
  // interfaces: topology, geometry, damage)
  EXPECT_EQ(check_xdmf_against_h5(dir), 2 * (7 + 3) + 1);
}

}  // namespace

TEST(OutputSnapshots, Triangles2DRoundTrip) {
  const std::string dir = fresh_dir("2d");
  roundtrip(mesh2d(), dir);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, Tetrahedra3DRoundTrip) {
  const std::string dir = fresh_dir("3d");
  roundtrip(mesh3d(), dir);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, CheckerScriptAccepts2DAnd3D) {
  if (python_with_h5py().empty()) GTEST_SKIP() << "no python3 with h5py";
  for (int d : {2, 3}) {
    const std::string dir = fresh_dir("check" + std::to_string(d));
    const HostMesh m = d == 2 ? mesh2d() : mesh3d();
    {
      fdem::SnapshotWriter w(dir, m);
      for (int k = 0; k < 2; ++k) {
        FrameData fd = make_frame(m, k);
        fdem::SnapshotFrame fr;
        fr.time = 1e-5 * k;
        fr.step = 10 * k;
        fr.x = fd.x.data();
        fr.u = fd.u.data();
        fr.v = fd.v.data();
        fr.stress = fd.stress.data();
        fr.damage = fd.damage.data();
        fr.fragment = fd.fragment.data();
        w.write(fr);
      }
    }
    EXPECT_EQ(run_checker(dir), 0) << "dim " << d;
    fs::remove_all(dir);
  }
}

TEST(OutputSnapshots, CheckerScriptRejectsMismatch) {
  if (python_with_h5py().empty()) GTEST_SKIP() << "no python3 with h5py";
  const std::string dir = fresh_dir("mismatch");
  const HostMesh m = mesh2d();
  {
    fdem::SnapshotWriter w(dir, m);
    FrameData fd = make_frame(m, 0);
    fdem::SnapshotFrame fr;
    fr.x = fd.x.data();
    w.write(fr);
  }
  std::string xml = slurp(dir + "/snapshots.xdmf");
  const std::string from = "Dimensions=\"6 3\"";
  const auto pos = xml.find(from);
  ASSERT_NE(pos, std::string::npos);
  xml.replace(pos, from.size(), "Dimensions=\"7 3\"");
  fdem::write_file_atomic(dir + "/snapshots.xdmf", xml);
  EXPECT_EQ(run_checker(dir), 1);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, NoInterfacesOmitsInterfaceGrid) {
  const std::string dir = fresh_dir("noiface");
  HostMesh m = mesh2d();
  m.ifaces.clear();
  m.iface_elems.clear();
  {
    fdem::SnapshotWriter w(dir, m);
    FrameData fd = make_frame(m, 0);
    fdem::SnapshotFrame fr;
    fr.time = 0.5;
    fr.step = 3;
    fr.x = fd.x.data();
    fr.u = fd.u.data();
    fr.v = fd.v.data();
    fr.stress = fd.stress.data();
    w.write(fr);
  }
  const std::string xml = slurp(dir + "/snapshots.xdmf");
  EXPECT_EQ(xml.find("interfaces"), std::string::npos);
  EXPECT_EQ(check_xdmf_against_h5(dir), 7);
  hid_t f = H5Fopen((dir + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dims;
  read_d(f, "/step_00000003/damage", &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{0}));
  read_i(f, "/mesh/interfaces", &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{0, 2}));
  H5Fclose(f);
  if (!python_with_h5py().empty()) {
    EXPECT_EQ(run_checker(dir), 0);
  }
  fs::remove_all(dir);
}

TEST(OutputSnapshots, MissingFieldsAreZeroAndXIsReferencePlusU) {
  const std::string dir = fresh_dir("missing");
  const HostMesh m = mesh2d();
  FrameData fd = make_frame(m, 0);
  {
    fdem::SnapshotWriter w(dir, m);
    fdem::SnapshotFrame fr;
    fr.u = fd.u.data();
    w.write(fr);
  }
  hid_t f = H5Fopen((dir + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<double> xu(m.X.size());
  for (size_t i = 0; i < xu.size(); ++i) xu[i] = m.X[i] + fd.u[i];
  EXPECT_EQ(read_d(f, "/step_00000000/coordinates"), pad3(xu, 2));
  EXPECT_EQ(read_d(f, "/step_00000000/velocity"), std::vector<double>(18, 0.0));
  EXPECT_EQ(read_d(f, "/step_00000000/stress"), std::vector<double>(12, 0.0));
  EXPECT_EQ(read_d(f, "/step_00000000/damage"), std::vector<double>(1, 0.0));
  H5Fclose(f);
  fs::remove_all(dir);
}

namespace {

// What a process writes with ParallelFrames (src/io/snapshot_parallel.hpp): its rows in its own
// order with their whole-mesh indices. One process holding every row in a shuffled order (the
// default build's HDF5 opens the file with its default driver; the runs over MPI check several
// processes' parts: tests/mpi/check_runs.py) must give the file and the XDMF SnapshotWriter::write
// gives for the rows in the whole mesh's order. The group /mesh likewise (a run whose whole mesh no
// process holds: SnapshotWriter's shell, then ParallelFrames::write_mesh), with interface fields.
void own_rows_as_whole(const HostMesh& m, const std::string& dir) {
  const int nn = m.num_nodes(), ne = m.num_elems(), ni = m.num_ifaces(), d = m.dim;
  const FrameData whole = make_frame(m, 1);
  const std::string a = dir + "/whole", b = dir + "/own";
  const std::vector<std::string> names{"weak", "strong"};
  std::vector<int> material(ni);
  std::vector<float> strength(ni);
  for (int q = 0; q < ni; ++q) {
    material[q] = q % 2;
    strength[q] = 1.0f + 0.01f * static_cast<float>(q);
  }
  {
    fdem::SnapshotWriter w(a, m);
    w.add_interface_fields(names, material, strength);
    fdem::SnapshotFrame fr;
    fr.time = 2.5e-5;
    fr.step = 30;
    fr.x = whole.x.data();
    fr.u = whole.u.data();
    fr.v = whole.v.data();
    fr.stress = whole.stress.data();
    fr.damage = whole.damage.data();
    fr.fragment = whole.fragment.data();
    w.write(fr);
  }
  // local row i is whole row ids[i]: the reversed order, then rotated by one
  auto shuffled = [](int n) {
    std::vector<int> ids;
    for (int i = n - 1; i >= 0; --i) ids.push_back(i);
    if (n > 1) std::rotate(ids.begin(), ids.begin() + 1, ids.end());
    return ids;
  };
  const std::vector<int> nid = shuffled(nn), eid = shuffled(ne), iid = shuffled(ni);
  auto rows = [](const std::vector<double>& v, const std::vector<int>& ids, int w) {
    std::vector<double> out;
    for (int i : ids) out.insert(out.end(), v.begin() + i * w, v.begin() + (i + 1) * w);
    return out;
  };
  const std::vector<double> x = rows(whole.x, nid, d), u = rows(whole.u, nid, d), v = rows(whole.v, nid, d),
                            s = rows(whole.stress, eid, 6), dmg = rows(whole.damage, iid, 1);
  std::vector<int> elems, region, ifaces, mat;
  std::vector<double> X, factor;
  for (int e : eid) {
    for (int k = 0; k <= d; ++k) elems.push_back(m.elems[static_cast<size_t>(e) * (d + 1) + k]);
    region.push_back(m.elem_region.empty() ? 0 : m.elem_region[e]);
  }
  for (int q : iid) {
    for (int k = 0; k < d; ++k) ifaces.push_back(m.ifaces[static_cast<size_t>(q) * 2 * d + k]);
    mat.push_back(material[q]);
    factor.push_back(strength[q]);
  }
  for (int n : nid)
    for (int k = 0; k < d; ++k) X.push_back(m.X[static_cast<size_t>(n) * d + k]);
  {
    fdem::MeshShell shell;
    shell.dim = d;
    shell.nodes = nn;
    shell.elems = ne;
    shell.ifaces = ni;
    shell.region_names = m.region_names;
    fdem::SnapshotWriter w(b, shell);
    w.interface_fields_by_rows(names, true);
    w.close_file();
    fdem::ParallelFrames frames(H5Pcreate(H5P_FILE_ACCESS));
    fdem::MeshPart mp;
    static_cast<fdem::OwnRows&>(mp) = {d, nn, ne, ni, nid.data(), eid.data(), iid.data(), nid.size(), eid.size(),
                                       iid.size()};
    mp.X = X.data();
    mp.elements = elems.data();
    mp.region = region.data();
    mp.interfaces = ifaces.data();
    mp.with_material = mp.with_strength = true;
    mp.material = mat.data();
    mp.strength = factor.data();
    frames.write_mesh(b, mp);
    fdem::FramePart p;
    static_cast<fdem::OwnRows&>(p) = mp;
    p.time = 2.5e-5;
    p.step = 30;
    p.x = x.data();
    p.u = u.data();
    p.v = v.data();
    p.stress = s.data();
    p.damage = dmg.data();
    p.has_fragment = true;
    p.fragment = whole.fragment.data();
    frames.write(b, p);
    w.frame_written(p.time, p.step, true);
    EXPECT_EQ(w.frames(), 1);
  }
  EXPECT_EQ(slurp(a + "/snapshots.xdmf"), slurp(b + "/snapshots.xdmf"));
  hid_t fa = H5Fopen((a + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t fb = H5Fopen((b + "/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(fa, 0);
  ASSERT_GE(fb, 0);
  for (const char* ds : {"coordinates", "displacement", "velocity", "stress", "von_mises", "damage"}) {
    const std::string n = std::string("/step_00000030/") + ds;
    std::vector<hsize_t> da, db;
    EXPECT_EQ(read_d(fa, n, &da), read_d(fb, n, &db)) << n;
    EXPECT_EQ(da, db) << n;
  }
  EXPECT_EQ(read_i(fa, "/step_00000030/fragment"), read_i(fb, "/step_00000030/fragment"));
  for (const char* ds : {"/mesh/elements", "/mesh/region", "/mesh/interfaces", "/mesh/interface_material"})
    EXPECT_EQ(read_i(fa, ds), read_i(fb, ds)) << ds;
  for (const char* ds : {"/mesh/reference_coordinates", "/mesh/strength_factor"}) {
    std::vector<hsize_t> da, db;
    EXPECT_EQ(read_d(fa, ds, &da), read_d(fb, ds, &db)) << ds;
    EXPECT_EQ(da, db) << ds;
  }
  EXPECT_EQ(read_attr<int>(fb, "/mesh", "num_interfaces", H5T_NATIVE_INT), ni);
  EXPECT_EQ(H5Lexists(fb, "/mesh/interface_material_names", H5P_DEFAULT) > 0, true);
  EXPECT_EQ(H5Lexists(fb, "/mesh/region_names", H5P_DEFAULT) > 0, !m.region_names.empty());
  EXPECT_EQ(read_attr<double>(fb, "/step_00000030", "time", H5T_NATIVE_DOUBLE), 2.5e-5);
  EXPECT_EQ(read_attr<long long>(fb, "/step_00000030", "step", H5T_NATIVE_LLONG), 30);
  H5Fclose(fa);
  H5Fclose(fb);
}

}  // namespace

TEST(OutputSnapshots, OwnRowsInAnyOrderGiveTheWholeFrame2D) {
  const std::string dir = fresh_dir("own2d");
  own_rows_as_whole(mesh2d(), dir);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, OwnRowsInAnyOrderGiveTheWholeFrame3D) {
  const std::string dir = fresh_dir("own3d");
  own_rows_as_whole(mesh3d(), dir);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, DuplicateStepIsALogicError) {
  const std::string dir = fresh_dir("dup");
  const HostMesh m = mesh2d();
  fdem::SnapshotWriter w(dir, m);
  fdem::SnapshotFrame fr;
  w.write(fr);
  EXPECT_THROW(w.write(fr), std::logic_error);
  EXPECT_EQ(w.frames(), 1);
  fs::remove_all(dir);
}

TEST(OutputSnapshots, StaleXdmfIsRemovedOnStart) {
  const std::string dir = fresh_dir("stale");
  fs::create_directories(dir);
  fdem::write_file_atomic(dir + "/snapshots.xdmf", "<Xdmf>old</Xdmf>\n");
  {
    fdem::SnapshotWriter w(dir, mesh2d());
    EXPECT_FALSE(fs::exists(dir + "/snapshots.xdmf"));
  }
  fs::remove_all(dir);
}

TEST(OutputSnapshots, UnwritableH5IsInputErrorNamingFile) {
  const std::string dir = fresh_dir("h5dir");
  fs::create_directories(dir + "/snapshots.h5");  // a directory where the file should go
  try {
    fdem::SnapshotWriter w(dir, mesh2d());
    FAIL() << "expected InputError";
  } catch (const fdem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("snapshots.h5"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(OutputHistory, CsvRoundTrip) {
  const std::string dir = fresh_dir("hist");
  fdem::ensure_output_dir(dir);
  const std::string path = dir + "/history.csv";
  const std::vector<std::string> cols = {"time [s]", "step [-]", "kinetic energy [J]",
                                         "max damage [-]"};
  const std::vector<std::vector<double>> rows = {
      {0.0, 0, 0.0, 0.0}, {1.5e-6, 100, 3.14159265358979, 0.5}, {3e-6, 200, -2.5e-300, 1.0}};
  {
    fdem::HistoryWriter h(path, cols);
    EXPECT_EQ(h.columns(), cols);
    h.row(rows[0]);
    h.row(rows[1]);
    // Flushed each row: the file already holds them while the writer is alive.
    std::ifstream in(path);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) ++n;
    EXPECT_EQ(n, 3);
    h.row(rows[2]);
    EXPECT_THROW(h.row({1.0, 2.0}), std::logic_error);
  }
  std::ifstream in(path);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "time [s],step [-],kinetic energy [J],max damage [-]");
  for (const auto& want : rows) {
    ASSERT_TRUE(std::getline(in, line));
    std::vector<double> got;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) got.push_back(std::stod(cell));
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) {
      EXPECT_NEAR(got[i], want[i], 1e-9 * std::abs(want[i])) << line;
    }
  }
  EXPECT_FALSE(std::getline(in, line));
  fs::remove_all(dir);
}

TEST(OutputHistory, UnopenablePathIsInputError) {
  const std::string path = "/etc/hostname/history.csv";
  try {
    fdem::HistoryWriter h(path, {"time [s]"});
    FAIL() << "expected InputError";
  } catch (const fdem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(OutputDir, CreatesNestedDirectories) {
  const std::string base = fresh_dir("nested");
  const std::string dir = base + "/a/b/c";
  fdem::ensure_output_dir(dir);
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_TRUE(fs::is_empty(dir));  // the probe file is gone
  fdem::ensure_output_dir(dir);    // existing is fine
  fs::remove_all(base);
}

TEST(OutputDir, UnderARegularFileIsInputError) {
  for (const std::string dir : {"/etc/hostname/x", "/proc/fdem_x"}) {
    try {
      fdem::ensure_output_dir(dir);
      ADD_FAILURE() << "expected InputError for " << dir;
    } catch (const fdem::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
    }
  }
}

TEST(OutputDir, ExistingFileIsInputError) {
  const std::string dir = fresh_dir("isfile");
  fdem::write_file_atomic(dir, "not a directory\n");
  EXPECT_THROW(fdem::ensure_output_dir(dir), fdem::InputError);
  fs::remove(dir);
}

TEST(OutputDir, WriteFileAtomicReplacesContent) {
  const std::string dir = fresh_dir("atomic");
  fdem::ensure_output_dir(dir);
  const std::string p = dir + "/summary.json";
  fdem::write_file_atomic(p, "{\"a\": 1}\n");
  fdem::write_file_atomic(p, "{\"a\": 2}\n");
  EXPECT_EQ(slurp(p), "{\"a\": 2}\n");
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  EXPECT_THROW(fdem::write_file_atomic(dir + "/no/such/dir/file", "x"), fdem::InputError);
  fs::remove_all(dir);
}
