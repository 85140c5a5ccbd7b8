#include "parallel/mpi/comm_mpi.hpp"

#include <mpi.h>
#if __has_include(<mpi-ext.h>)
#include <mpi-ext.h>  // Open MPI's MPIX_Query_cuda_support
#endif
#ifdef FDEM_PARALLEL_HDF5
#include <hdf5.h>  // H5Pset_fapl_mpio
#endif

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <iostream>
#include <thread>
#include <vector>

namespace fdem {

namespace {

using HostBuffer = Kokkos::View<double*>::HostMirror;

// Whether device buffers may go to MPI as they are: host backends always; CUDA when the MPI says
// it is CUDA-aware (Open MPI's query; other MPIs: no, the buffers go through the host).
bool pass_device_buffers() {
  if (Kokkos::SpaceAccessibility<Kokkos::HostSpace, Kokkos::View<double*>::memory_space>::accessible)
    return true;
#if defined(KOKKOS_ENABLE_CUDA) && defined(MPIX_CUDA_AWARE_SUPPORT) && MPIX_CUDA_AWARE_SUPPORT
  return MPIX_Query_cuda_support() == 1;
#else
  return false;
#endif
}

class MpiComm final : public Comm {
 public:
  MpiComm() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    direct_ = pass_device_buffers();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  // Reduced on process 0 and broadcast: every process gets the same bits (MPI_Allreduce is only
  // recommended, not required, to give them).
  void sum(double* v, int n) const override {
    if (n <= 0) return;
    std::vector<double> r(static_cast<size_t>(n));
    MPI_Reduce(v, r.data(), n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank_ == 0) std::copy(r.begin(), r.end(), v);
    MPI_Bcast(v, n, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  void min(double* v, int n) const override {
    if (n > 0) MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  }
  void exchange(const std::vector<int>& neighbours, const Kokkos::View<double*>& send,
                const std::vector<int>& send_off, const Kokkos::View<double*>& recv,
                const std::vector<int>& recv_off, int per) const override {
    double* sp = send.data();
    double* rp = recv.data();
    if (!direct_) {  // through host copies
      if (hs_.extent(0) != send.extent(0)) hs_ = Kokkos::create_mirror_view(send);
      if (hr_.extent(0) != recv.extent(0)) hr_ = Kokkos::create_mirror_view(recv);
      Kokkos::deep_copy(hs_, send);
      sp = hs_.data();
      rp = hr_.data();
    }
    const int nb = static_cast<int>(neighbours.size());
    req_.assign(2 * static_cast<size_t>(nb), MPI_REQUEST_NULL);
    for (int k = 0; k < nb; ++k)
      MPI_Irecv(rp + static_cast<size_t>(recv_off[k]) * per, (recv_off[k + 1] - recv_off[k]) * per,
                MPI_DOUBLE, neighbours[k], kTag, MPI_COMM_WORLD, &req_[k]);
    for (int k = 0; k < nb; ++k)
      MPI_Isend(sp + static_cast<size_t>(send_off[k]) * per, (send_off[k + 1] - send_off[k]) * per,
                MPI_DOUBLE, neighbours[k], kTag, MPI_COMM_WORLD, &req_[nb + k]);
    MPI_Waitall(2 * nb, req_.data(), MPI_STATUSES_IGNORE);
    if (!direct_) Kokkos::deep_copy(recv, hr_);
  }
  void gather(const std::vector<double>& mine, std::vector<double>& all) const override {
    const int n = static_cast<int>(mine.size());
    std::vector<int> counts(static_cast<size_t>(size_)), displs(static_cast<size_t>(size_), 0);
    MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (rank_ == 0) {
      for (int r = 1; r < size_; ++r) displs[r] = displs[r - 1] + counts[r - 1];
      all.resize(static_cast<size_t>(displs[size_ - 1]) + counts[size_ - 1]);
    }
    MPI_Gatherv(mine.data(), n, MPI_DOUBLE, rank_ == 0 ? all.data() : nullptr, counts.data(), displs.data(),
                MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  // Process 0 sends parts[r] to process r (send_bytes).
  void scatter_bytes(std::vector<std::vector<char>>& parts, std::vector<char>& mine) const override {
    if (rank_ == 0) {
      for (int r = 1; r < size_; ++r) {
        send_bytes(parts[static_cast<size_t>(r)], r);
        std::vector<char>().swap(parts[static_cast<size_t>(r)]);  // sent: freed
      }
      mine = std::move(parts[0]);
      return;
    }
    receive_bytes(mine);
  }
  void scatter_each(const std::function<std::vector<char>(int)>& make, std::vector<char>& mine) const override {
    if (rank_ == 0) {
      for (int r = 1; r < size_; ++r) send_bytes(make(r), r);  // (freed once sent)
      mine = make(0);
      return;
    }
    receive_bytes(mine);
  }
  void broadcast_bytes(std::vector<char>& bytes) const override {
    long long n = static_cast<long long>(bytes.size());
    MPI_Bcast(&n, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
    if (rank_ != 0) bytes.resize(static_cast<size_t>(n));
    for (long long at = 0; at < n; at += kPiece)
      MPI_Bcast(bytes.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_CHAR, 0, MPI_COMM_WORLD);
  }
  long long h5_parallel_access() const override {
#ifdef FDEM_PARALLEL_HDF5
    const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0) return -1;
    if (H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL) < 0) {
      H5Pclose(fapl);
      return -1;
    }
    return fapl;
#else
    return -1;
#endif
  }
  std::string gpu_aware() const override {
    if (Kokkos::SpaceAccessibility<Kokkos::HostSpace, Kokkos::View<double*>::memory_space>::accessible)
      return "not needed (host backend)";
    return direct_ ? "yes" : "no (device buffers go through host copies)";
  }
  [[noreturn]] void abort(int code) const override {
    // mpirun forwards each process's output on its own time, and MPI_Abort ends the job at once: a
    // message just written can be lost (seen in CI under load: exit 2 and no error line). The
    // streams are flushed and mpirun is given a second to forward them first.
    std::cout.flush();
    std::cerr.flush();
    std::fflush(stdout);
    std::fflush(stderr);
    std::this_thread::sleep_for(std::chrono::seconds(1));
    MPI_Abort(MPI_COMM_WORLD, code);
    std::abort();  // MPI_Abort does not return; if it did, this process ends anyway
  }

 private:
  static constexpr long long kPiece = 1LL << 30;
  // Process 0: b to process r, its size first, in pieces of at most 1 GiB (MPI counts are ints).
  void send_bytes(const std::vector<char>& b, int r) const {
    long long n = static_cast<long long>(b.size());
    MPI_Send(&n, 1, MPI_LONG_LONG, r, kTag + 1, MPI_COMM_WORLD);
    for (long long at = 0; at < n; at += kPiece)
      MPI_Send(b.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_CHAR, r, kTag + 1, MPI_COMM_WORLD);
  }
  // The others: what process 0 sends. It may mesh for minutes first: wait without spinning on a
  // core (MPI's own wait polls, which takes the core from process 0 where processes share cores).
  void receive_bytes(std::vector<char>& mine) const {
    for (int flag = 0;;) {
      MPI_Iprobe(0, kTag + 1, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
      if (flag) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    long long n = 0;
    MPI_Recv(&n, 1, MPI_LONG_LONG, 0, kTag + 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    mine.resize(static_cast<size_t>(n));
    for (long long at = 0; at < n; at += kPiece)
      MPI_Recv(mine.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_CHAR, 0, kTag + 1, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
  }
  static constexpr int kTag = 7301;
  int rank_ = 0, size_ = 1;
  bool direct_ = true;
  mutable HostBuffer hs_, hr_;
  mutable std::vector<MPI_Request> req_;
};

}  // namespace

std::shared_ptr<Comm> mpi_start(int* argc, char*** argv) {
  int started = 0;
  MPI_Initialized(&started);
  if (!started) MPI_Init(argc, argv);
  return std::make_shared<MpiComm>();
}

void mpi_finish() {
  int started = 0, finished = 0;
  MPI_Initialized(&started);
  MPI_Finalized(&finished);
  if (started && !finished) MPI_Finalize();
}

std::string mpi_description(const Comm& comm) {
  char version[MPI_MAX_LIBRARY_VERSION_STRING] = {0};
  int len = 0;
  MPI_Get_library_version(version, &len);
  (void)len;
  std::string v(version);  // up to its terminating zero
  if (const auto nl = v.find_first_of("\r\n"); nl != std::string::npos) v.resize(nl);
  while (!v.empty() && (v.back() == ',' || v.back() == ' ')) v.pop_back();
#ifdef FDEM_PARALLEL_HDF5
  const char* snapshots = "every process writes its rows (parallel HDF5)";
#else
  const char* snapshots = "gathered on process 0 (serial HDF5)";
#endif
  return v + "; processes: " + std::to_string(comm.size()) + "; GPU-aware: " + comm.gpu_aware() +
         "; snapshots and checkpoints: " + snapshots;
}

}  // namespace fdem
