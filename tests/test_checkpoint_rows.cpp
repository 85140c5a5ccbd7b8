// Checkpoints whose per-row entries every process of a run writes itself (src/io/checkpoint.hpp:
// write_checkpoint_rows). In the default build one process writes all rows, given in a shuffled
// order, with HDF5's default file driver; the MPI checks (tests/mpi/check_runs.py) compare the
// file that 2 processes write with the one gathered on process 0, bit for bit. Here: the rows land
// at their whole-mesh rows, the checksum of rows adds up over parts and catches a changed value
// and two swapped rows, and the other entries are process 0's.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/checkpoint.hpp"
#include "io/checkpoint_internal.hpp"

namespace {

namespace fs = std::filesystem;

struct Written {
  std::string path;
  std::vector<double> x, fs_;  // whole: 5 nodes x 2; 2 blocks x 5 nodes x 2
  std::vector<long long> flags;  // whole: 4 interfaces
};

// Local row i is whole row ids[i].
Written write_shuffled(const std::string& name) {
  Written w;
  const fs::path dir = fs::temp_directory_path() / ("fdem_test_ckrows_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  w.path = (dir / (name + ".h5")).string();
  const int nn = 5, ni = 4;
  for (int i = 0; i < nn * 2; ++i) w.x.push_back(0.1 * i + 1e-17 * i * i);
  for (int i = 0; i < 2 * nn * 2; ++i) w.fs_.push_back(-3.0 * i);
  for (int i = 0; i < ni; ++i) w.flags.push_back(i % 2 ? 7 : -1);
  static const std::vector<int> nid = {3, 0, 4, 1, 2}, iid = {2, 3, 1, 0};
  fdem::RowPart x{"model/x", false, nn, 1, 2, &nid, nid.size(), {}};
  for (int i : nid) x.values.insert(x.values.end(), {w.x[2 * i], w.x[2 * i + 1]});
  fdem::RowPart f{"model/platen_fs", false, nn, 2, 2, &nid, nid.size(), {}};
  for (int b = 0; b < 2; ++b)
    for (int i : nid) f.values.insert(f.values.end(), {w.fs_[(b * nn + i) * 2], w.fs_[(b * nn + i) * 2 + 1]});
  fdem::RowPart c{"model/icontact", true, ni, 1, 1, &iid, iid.size(), {}};
  for (int i : iid) c.values.push_back(static_cast<double>(w.flags[i]));
  fdem::StateArrays s;
  s.put("simulation/t", 2.5e-4);
  s.put_int("run/step", 300);
  s.str["run/note"] = "process 0's";
  s.f64["model/x"] = {99.0};  // an entry of the rows is the rows'
  fdem::CheckpointHeader h;
  h.dim = 2;
  h.nodes = nn;
  h.elements = 3;
  h.interfaces = ni;
  h.case_hash = "0123456789abcdef";
  h.mesh_hash = "fedcba9876543210";
  h.time = 2.5e-4;
  h.step = 300;
  fdem::write_checkpoint_rows(w.path, h, s, {x, f, c},
                              {H5Pcreate(H5P_FILE_ACCESS), true, [](double*, int) {}});  // one process
  return w;
}

TEST(CheckpointRows, RowsInAnyOrderReadBackInTheWholeMeshsOrder) {
  const Written w = write_shuffled("order");
  fdem::CheckpointHeader h;
  const fdem::StateArrays s = fdem::read_checkpoint(w.path, h);
  EXPECT_EQ(s.array("model/x"), w.x);
  EXPECT_EQ(s.array("model/platen_fs"), w.fs_);
  EXPECT_EQ(s.int_array("model/icontact"), w.flags);
  EXPECT_EQ(s.get("simulation/t"), 2.5e-4);
  EXPECT_EQ(s.get_int("run/step"), 300);
  EXPECT_EQ(s.string("run/note"), "process 0's");
  EXPECT_EQ(h.step, 300);
  EXPECT_EQ(h.nodes, 5);
  EXPECT_FALSE(fs::exists(w.path + ".tmp"));
  hid_t f = H5Fopen(w.path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  int version = 0, width = 0;
  {
    hid_t a = H5Aopen(f, "version", H5P_DEFAULT);
    H5Aread(a, H5T_NATIVE_INT, &version);
    H5Aclose(a);
    a = H5Aopen_by_name(f, "model/platen_fs", fdem::ckpt::kRowsAttr, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(a, 0);
    H5Aread(a, H5T_NATIVE_INT, &width);
    H5Aclose(a);
  }
  EXPECT_EQ(version, 4);
  EXPECT_EQ(width, 2);
  H5Fclose(f);
  fs::remove(w.path);
}

// A restart over processes reads the file without the entries by rows, then each process its
// rows: two "processes" here, holding nodes {4, 1} and {0, 3, 2} (with node 1 also as a ghost of
// the second: read, not counted), whose own rows' checksum terms add up to the stored checksum.
TEST(CheckpointRows, EachProcessReadsItsRowsAndTheirChecksumsAddUp) {
  const Written w = write_shuffled("parts");
  fdem::CheckpointHeader h;
  const fdem::StateArrays s = fdem::read_checkpoint(w.path, h, true);
  EXPECT_FALSE(s.f64.count("model/x"));
  EXPECT_EQ(s.by_rows.count("model/x"), 1u);
  EXPECT_EQ(s.by_rows.count("model/platen_fs"), 1u);
  EXPECT_EQ(s.get("simulation/t"), 2.5e-4);
  const std::vector<int> a = {4, 1}, b = {0, 3, 2, 1};
  uint64_t ha = 0, hb = 0;
  const std::vector<double> xa = fdem::read_rows(s, "model/platen_fs", a, a.size(), a.size(), 2, 5, 2, ha);
  const std::vector<double> xb = fdem::read_rows(s, "model/platen_fs", b, b.size(), 3, 2, 5, 2, hb);
  ASSERT_EQ(xa.size(), 2u * 2 * 2);
  ASSERT_EQ(xb.size(), 2u * 4 * 2);
  for (int blk = 0; blk < 2; ++blk) {
    for (size_t i = 0; i < a.size(); ++i)
      for (int c = 0; c < 2; ++c) EXPECT_EQ(xa[(blk * a.size() + i) * 2 + c], w.fs_[(blk * 5 + a[i]) * 2 + c]);
    for (size_t i = 0; i < b.size(); ++i)
      for (int c = 0; c < 2; ++c) EXPECT_EQ(xb[(blk * b.size() + i) * 2 + c], w.fs_[(blk * 5 + b[i]) * 2 + c]);
  }
  EXPECT_TRUE(fdem::rows_checksum_matches(s, "model/platen_fs", ha + hb));
  EXPECT_FALSE(fdem::rows_checksum_matches(s, "model/platen_fs", ha));  // a process's rows alone
  uint64_t hi = 0;  // the integer entry, read as doubles
  const std::vector<int> all = {0, 1, 2, 3};
  const std::vector<double> flags = fdem::read_rows(s, "model/icontact", all, 4, 4, 1, 4, 1, hi);
  EXPECT_EQ(flags, (std::vector<double>{-1, 7, -1, 7}));
  EXPECT_TRUE(fdem::rows_checksum_matches(s, "model/icontact", hi));
  fs::remove(w.path);
}

TEST(CheckpointRows, RowChecksumsAddUpOverParts) {
  std::vector<double> v;
  for (int i = 0; i < 30; ++i) v.push_back(1.0 / (i + 1));
  using fdem::ckpt::rows_hash;
  const uint64_t whole = rows_hash(v.data(), 10, 24, 0);
  // rows 0-3 on one process, 4-9 on another (the sum is mod 2^64, in any order)
  EXPECT_EQ(rows_hash(v.data() + 12, 6, 24, 4) + rows_hash(v.data(), 4, 24, 0), whole);
  std::vector<double> swapped = v;
  std::swap_ranges(swapped.begin(), swapped.begin() + 3, swapped.begin() + 3);  // rows 0 and 1
  EXPECT_NE(rows_hash(swapped.data(), 10, 24, 0), whole);
}

// Overwrites one value, or swaps two rows, of a rows dataset in place.
void alter(const std::string& path, const char* dataset, bool swap_rows) {
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  hid_t d = H5Dopen2(f, dataset, H5P_DEFAULT);
  std::vector<double> v(10);
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  if (swap_rows) {
    std::swap(v[0], v[2]);
    std::swap(v[1], v[3]);
  } else {
    v[7] += 1e-12;
  }
  H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Dclose(d);
  H5Fclose(f);
}

TEST(CheckpointRows, ChangedValueOrSwappedRowsAreRefusedNamingTheDataset) {
  for (bool swap_rows : {false, true}) {
    const Written w = write_shuffled(swap_rows ? "swapped" : "changed");
    alter(w.path, "model/x", swap_rows);
    fdem::CheckpointHeader h;
    try {
      fdem::read_checkpoint(w.path, h);
      FAIL() << "expected InputError";
    } catch (const fdem::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("dataset 'model/x' fails its checksum"), std::string::npos)
          << e.what();
    }
    fs::remove(w.path);
  }
}

}  // namespace
