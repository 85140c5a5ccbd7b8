#pragma once
// The processes of a run over MPI as the solver sees them (docs/parallel.md). The solver library
// does not see MPI: an MPI build (-DFDEM_ENABLE_MPI=ON) implements this interface in
// src/parallel/mpi/comm_mpi.cpp, and fdem's main hands it to run_case (RunOptions::comm) when it
// runs under mpirun on more than one process. Host only; called between kernels, never inside.
#include <algorithm>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "kernels/fdem_kokkos.hpp"

namespace fdem {

class Comm {
 public:
  virtual ~Comm() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // In place, over all processes, in the same order on every process (so that every process gets
  // the same bits).
  virtual void sum(double* v, int n) const = 0;
  virtual void min(double* v, int n) const = 0;
  // One halo exchange (kernels/halo.hpp): for each k, the doubles
  // send[send_off[k] * per .. send_off[k + 1] * per) go to process neighbours[k], and what it
  // sends back lands in recv[recv_off[k] * per .. recv_off[k + 1] * per). The buffers are in the
  // run's device memory: a GPU-aware MPI takes them as they are, others through host copies.
  virtual void exchange(const std::vector<int>& neighbours, const Kokkos::View<double*>& send,
                        const std::vector<int>& send_off, const Kokkos::View<double*>& recv,
                        const std::vector<int>& recv_off, int per) const = 0;
  // Every process's `mine`, one after the other in process order, into `all` on process 0 (the
  // others' `all` is left as it is).
  virtual void gather(const std::vector<double>& mine, std::vector<double>& all) const = 0;
  // From process 0 (parts: one buffer per process, consumed) to each process its own, into
  // `mine` (process 0's own too).
  virtual void scatter_bytes(std::vector<std::vector<char>>& parts, std::vector<char>& mine) const = 0;
  // The same with each process's buffer made by process 0 when it is its turn (make(r), called
  // there only, for every process r, its own last) and freed once sent, so that process 0 holds one
  // at a time. (This default makes them all first.)
  virtual void scatter_each(const std::function<std::vector<char>(int)>& make, std::vector<char>& mine) const {
    std::vector<std::vector<char>> parts;
    if (rank() == 0) {
      parts.resize(static_cast<size_t>(size()));
      for (int r = 1; r < size(); ++r) parts[static_cast<size_t>(r)] = make(r);
      parts[0] = make(0);
    }
    scatter_bytes(parts, mine);
  }
  // Process 0's `bytes` to every process (the others' replaced by them).
  virtual void broadcast_bytes(std::vector<char>& bytes) const = 0;
  // An HDF5 file access property list (hid_t) for opening one file on every process with MPI-IO,
  // which the caller closes; -1 when the build's HDF5 is not parallel (the frames are then gathered
  // on process 0: src/solver/run_output.cpp). Collective: every process calls it.
  virtual long long h5_parallel_access() const { return -1; }
  // Whether the MPI passes device buffers without host copies (CUDA-aware); "" when unknown.
  virtual std::string gpu_aware() const = 0;
  // Ends every process of the run now (after an error on one of them: the others would wait for it).
  [[noreturn]] virtual void abort(int code) const = 0;
};

// The one process of a run that is not decomposed: the trivial case of a Comm. Its sums and minima
// leave the values as they are, it has no neighbours to exchange with, and its gather and scatter
// hand the process its own (ExaMiniMD's serial communicator has this shape).
class OneProcess final : public Comm {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void sum(double*, int) const override {}
  void min(double*, int) const override {}
  void exchange(const std::vector<int>&, const Kokkos::View<double*>&, const std::vector<int>&,
                const Kokkos::View<double*>&, const std::vector<int>&, int) const override {}
  void gather(const std::vector<double>& mine, std::vector<double>& all) const override { all = mine; }
  void scatter_bytes(std::vector<std::vector<char>>& parts, std::vector<char>& mine) const override {
    mine = parts.empty() ? std::vector<char>{} : std::move(parts[0]);
  }
  void broadcast_bytes(std::vector<char>&) const override {}
  std::string gpu_aware() const override { return ""; }
  [[noreturn]] void abort(int code) const override { std::exit(code); }
};

// Rows of `width` values of a process's own items (row i at local[i * width], i < own) gathered on
// process 0 into the whole mesh's order (row ids[i] of whole_n rows; whole_n is read on process 0
// only); an empty vector on the other processes.
inline std::vector<double> gather_rows(const Comm& comm, const double* local, size_t own, size_t width,
                                       const std::vector<int>& ids, size_t whole_n) {
  std::vector<double> mine, all;
  mine.reserve(own * (1 + width));
  for (size_t i = 0; i < own; ++i) {
    mine.push_back(ids[i]);
    mine.insert(mine.end(), local + i * width, local + (i + 1) * width);
  }
  comm.gather(mine, all);
  if (comm.rank() != 0) return {};
  std::vector<double> out(whole_n * width, 0.0);
  for (size_t j = 0; j + 1 + width <= all.size(); j += 1 + width)
    std::copy(all.begin() + j + 1, all.begin() + j + 1 + width, out.begin() + static_cast<size_t>(all[j]) * width);
  return out;
}

}  // namespace fdem
