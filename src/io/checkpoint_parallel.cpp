// write_checkpoint_rows: a checkpoint written by every process of a run (src/io/checkpoint.hpp).
// First all processes create CHECKPOINT.tmp with MPI-IO and write their own rows of each per-row
// entry (their rows selected as runs of consecutive whole-mesh indices, one collective write per
// entry); the rows' checksums are summed over the processes; then process 0 alone reopens the file,
// adds the header, its entries and every checksum, syncs it and renames it over CHECKPOINT (as
// write_checkpoint does), so a reader sees the old checkpoint or the new one, never part of it.
#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "io/checkpoint.hpp"
#include "io/checkpoint_internal.hpp"
#include "io/hdf5_util.hpp"

namespace fdem {

using namespace ckpt;
using h5::Id;

namespace {

// This process's rows of one entry: the file's value positions (runs over every block) and the
// values in that order; the sum of their rows' hashes.
struct OwnRows {
  h5::Runs runs;  // (first value, count of values)
  std::vector<double> f64;
  std::vector<long long> i64;
  uint64_t hash = 0;
};

OwnRows own_rows(const RowPart& r) {
  OwnRows o;
  const size_t w = static_cast<size_t>(r.width);
  const std::vector<int>& ids = *r.ids;
  const std::vector<size_t> order = h5::order_by(ids.data(), r.own);
  for (int b = 0; b < r.blocks; ++b) {
    for (size_t i : order) {
      const uint64_t row = static_cast<uint64_t>(b) * static_cast<uint64_t>(r.whole_rows) +
                           static_cast<uint64_t>(ids[i]);
      const double* v = &r.values[(static_cast<size_t>(b) * r.own + i) * w];
      o.runs.add(static_cast<hsize_t>(row * w), w);
      if (r.integer) {
        for (size_t c = 0; c < w; ++c) o.i64.push_back(static_cast<long long>(v[c]));
        o.hash += rows_hash(&o.i64[o.i64.size() - w], 1, 8 * w, row);
      } else {
        o.f64.insert(o.f64.end(), v, v + w);
        o.hash += rows_hash(v, 1, 8 * w, row);
      }
    }
  }
  return o;
}

// Every process: CHECKPOINT.tmp with the row entries, each process's rows written; returns the
// sums of the rows' hashes of this process, per entry.
std::vector<uint64_t> write_rows(const std::vector<RowPart>& rows, const CheckpointProcesses& p,
                                 const Writing& w) {
  Id fapl(H5Pcopy(static_cast<hid_t>(p.fapl)), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  if (fapl.ok()) H5Pset_file_locking(fapl.get(), 0, 1);
#endif
  Id file(H5Fcreate(w.tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose);
  if (!file.ok()) w.fail("cannot create " + w.tmp + " on every process (MPI-IO)");
  Id dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  Id lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  Id dcpl = h5::written_once();
  if (!dxpl.ok() || !lcpl.ok() || !dcpl.ok() || H5Pset_create_intermediate_group(lcpl.get(), 1) < 0)
    w.fail("cannot create property lists");
#ifdef H5_HAVE_PARALLEL
  if (H5Pset_dxpl_mpio(dxpl.get(), H5FD_MPIO_COLLECTIVE) < 0) w.fail("cannot ask for collective writes");
#endif
  std::vector<uint64_t> hashes;
  for (const RowPart& r : rows) {
    const OwnRows o = own_rows(r);
    hashes.push_back(o.hash);
    const hsize_t n = static_cast<hsize_t>(r.blocks) * static_cast<hsize_t>(r.whole_rows) *
                      static_cast<hsize_t>(r.width);
    Id fspace(H5Screate_simple(1, &n, nullptr), H5Sclose);
    Id d(H5Dcreate2(file.get(), r.name.c_str(), r.integer ? H5T_STD_I64LE : H5T_IEEE_F64LE, fspace.get(),
                    lcpl.get(), dcpl.get(), H5P_DEFAULT),
         H5Dclose);
    if (!fspace.ok() || !d.ok()) w.fail("cannot create dataset '" + r.name + "'");
    // an empty entry (no platens, no interfaces: the same on every process) has nothing to write;
    // HDF5 refuses a write into a dataset of no values
    if (n == 0) continue;
    const hsize_t m = r.integer ? o.i64.size() : o.f64.size();
    Id mspace = h5::memory_space(m);
    if (!h5::select_runs(fspace.get(), o.runs) || !mspace.ok())
      w.fail("cannot select this process's rows of '" + r.name + "'");
    static const long long none = 0;
    const void* data = m == 0      ? static_cast<const void*>(&none)
                       : r.integer ? static_cast<const void*>(o.i64.data())
                                   : static_cast<const void*>(o.f64.data());
    const hid_t type = r.integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE;
    if (H5Dwrite(d.get(), type, mspace.get(), fspace.get(), dxpl.get(), data) < 0)
      w.fail("cannot write this process's rows of '" + r.name + "'");
  }
  if (H5Fclose(file.release()) < 0) w.fail("cannot close " + w.tmp + " (disk full?)");
  return hashes;
}

}  // namespace

void write_checkpoint_rows(const std::string& path, const CheckpointHeader& h, const StateArrays& s,
                           const std::vector<RowPart>& rows, const CheckpointProcesses& p) {
  Id access(static_cast<hid_t>(p.fapl), H5Pclose);  // (closed here)
  const int count = next_checkpoint();
  h5::silence();
  const std::string tmp = path + ".tmp";
  const Writing w{path, tmp, p.root && kill_hook().during == count};
  const std::vector<uint64_t> totals = sum_hashes_over_processes(write_rows(rows, p, w), p.sum);
  if (!p.root) return;

  Id fapl = h5::file_access_without_locking();
  Id file(H5Fopen(tmp.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose);
  if (!file.ok()) w.fail("cannot reopen " + tmp);
  try {
    write_header(file.get(), h, path);
    std::map<std::string, std::string> sums;
    for (size_t k = 0; k < rows.size(); ++k) {
      const uint64_t total = totals[k];
      const std::string& name = rows[k].name;
      Id d(H5Dopen2(file.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
      if (!d.ok()) w.fail("cannot open dataset '" + name + "'");
      sums[name] = hex(total);
      string_attr(d.get(), kChecksum, sums[name], path);
      h5::write_scalar_attr<int>(d.get(), kRowsAttr, H5T_STD_I32LE, H5T_NATIVE_INT, rows[k].width, path);
    }
    write_datasets(file.get(), s, w, sums);  // (an entry of the rows is the rows': in sums)
    string_attr(file.get(), kChecksum, root_checksum(h, kVersion, sums), path);
  } catch (...) {
    H5Fclose(file.release());
    std::remove(tmp.c_str());
    throw;
  }
  if (H5Fclose(file.release()) < 0) w.fail("cannot close " + tmp + " (disk full?)");
  commit(w);
  if (kill_hook().after == count) kill_now();
}

std::vector<double> read_rows(const StateArrays& s, const std::string& name, const std::vector<int>& ids,
                              size_t count, size_t hashed, int blocks, long long whole_rows, int width,
                              uint64_t& own_hash) {
  const std::string& path = s.file;
  auto damaged = [&](const std::string& what) {
    throw InputError("restart file '" + path + "' is damaged: dataset '" + name + "' " + what + reason());
  };
  h5::silence();
  Id fapl = h5::file_access_without_locking();
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!file.ok()) throw InputError("restart file '" + path + "' cannot be opened" + reason());
  Id d(H5Dopen2(file.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) damaged("cannot be opened");
  Id fspace(H5Dget_space(d.get()), H5Sclose);
  Id type(H5Dget_type(d.get()), H5Tclose);
  const size_t w = static_cast<size_t>(width);
  const hsize_t n = static_cast<hsize_t>(blocks) * static_cast<hsize_t>(whole_rows) * w;
  if (!fspace.ok() || !type.ok() || H5Sget_simple_extent_npoints(fspace.get()) != static_cast<hssize_t>(n))
    damaged("has another size than " + std::to_string(n) + " values");
  own_hash = 0;
  if (n == 0) return {};  // an empty entry (no platens, no interfaces): written without a value
  const bool integer = H5Tget_class(type.get()) == H5T_INTEGER;
  // this process's rows in increasing order in the file, as runs
  const std::vector<size_t> order = h5::order_by(ids.data(), count);
  h5::Runs runs;
  for (int b = 0; b < blocks; ++b)
    for (size_t i : order) {
      const hsize_t row =
          static_cast<hsize_t>(b) * static_cast<hsize_t>(whole_rows) + static_cast<hsize_t>(ids[i]);
      runs.add(row * w, w);
    }
  const hsize_t m = static_cast<hsize_t>(blocks) * count * w;
  Id mspace = h5::memory_space(m);
  const bool ok = h5::select_runs(fspace.get(), runs) && mspace.ok();
  std::vector<double> f(integer ? 0 : std::max<hsize_t>(m, 1));
  std::vector<long long> l(integer ? std::max<hsize_t>(m, 1) : 0);
  if (!ok || H5Dread(d.get(), integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(),
                     H5P_DEFAULT, integer ? static_cast<void*>(l.data()) : static_cast<void*>(f.data())) < 0)
    damaged("cannot be read");
  // back into the local order; the own rows' checksum terms
  std::vector<double> out(static_cast<size_t>(m));
  own_hash = 0;
  size_t at = 0;
  for (int b = 0; b < blocks; ++b)
    for (size_t i : order) {
      const uint64_t row = static_cast<uint64_t>(b) * static_cast<uint64_t>(whole_rows) +
                           static_cast<uint64_t>(ids[i]);
      double* o = &out[(static_cast<size_t>(b) * count + i) * w];
      if (integer) {
        for (size_t c = 0; c < w; ++c) o[c] = static_cast<double>(l[at + c]);
        if (i < hashed) own_hash += rows_hash(&l[at], 1, 8 * w, row);
      } else {
        std::copy(&f[at], &f[at] + w, o);
        if (i < hashed) own_hash += rows_hash(&f[at], 1, 8 * w, row);
      }
      at += w;
    }
  return out;
}

std::vector<uint64_t> sum_hashes_over_processes(const std::vector<uint64_t>& mine,
                                                const std::function<void(double*, int)>& sum) {
  std::vector<double> halves;
  for (uint64_t x : mine) {
    halves.push_back(static_cast<double>(x >> 32));
    halves.push_back(static_cast<double>(x & 0xffffffffull));
  }
  sum(halves.data(), static_cast<int>(halves.size()));
  std::vector<uint64_t> total(mine.size());
  for (size_t k = 0; k < total.size(); ++k)
    total[k] = (static_cast<uint64_t>(halves[2 * k]) << 32) + static_cast<uint64_t>(halves[2 * k + 1]);
  return total;
}

bool rows_checksum_matches(const StateArrays& s, const std::string& name, uint64_t total) {
  const auto it = s.by_rows.find(name);
  return it != s.by_rows.end() && it->second == hex(total);
}

}  // namespace fdem
