#pragma once
// The per-step exchange of a decomposed run (src/parallel/decompose.hpp builds the lists) on the
// device: after the node update each part packs the positions of its own nodes that other parts
// hold as ghosts into one buffer, the buffers travel (in one process: exchange_in_process; over
// MPI: the same buffers handed to MPI), and each part unpacks what it received into its ghost
// nodes. Positions only: the force pass reads no velocity (the node update, which does, covers
// the own nodes only). The ghosts' forces are zeroed at the unpack (they are never used).
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "kernels/model.hpp"

namespace fdem {

template <int D>
class Halo {
 public:
  Halo() = default;
  // Per neighbouring part k (sorted): neighbours[k], the own nodes it needs (send[k]) and the ghost
  // nodes it sends (recv[k]), as SubMesh lists them.
  Halo(const std::vector<int>& nbrs, const std::vector<std::vector<int>>& send,
       const std::vector<std::vector<int>>& recv)
      : neighbours(nbrs) {
    send_off.assign(1, 0);
    recv_off.assign(1, 0);
    for (size_t k = 0; k < nbrs.size(); ++k) {
      send_off.push_back(send_off.back() + static_cast<int>(send[k].size()));
      recv_off.push_back(recv_off.back() + static_cast<int>(recv[k].size()));
    }
    send_idx = upload("fdem::halo::send_idx", send, send_off.back());
    recv_idx = upload("fdem::halo::recv_idx", recv, recv_off.back());
    send_buf = Kokkos::View<double*>("fdem::halo::send_buf", static_cast<size_t>(send_off.back()) * D);
    recv_buf = Kokkos::View<double*>("fdem::halo::recv_buf", static_cast<size_t>(recv_off.back()) * D);
  }

  std::vector<int> neighbours;
  std::vector<int> send_off, recv_off;  // per neighbour k: its nodes are [off[k], off[k + 1])
  Kokkos::View<int*> send_idx, recv_idx;
  Kokkos::View<double*> send_buf, recv_buf;  // D doubles per node

  int send_nodes() const { return send_off.back(); }
  int recv_nodes() const { return recv_off.back(); }
  // Bytes one exchange sends.
  long send_bytes() const { return static_cast<long>(send_nodes()) * D * sizeof(double); }
  // The doubles of neighbour k in each buffer.
  Kokkos::View<double*> send_part(int k) const {
    return Kokkos::subview(send_buf, std::make_pair(static_cast<size_t>(send_off[k]) * D,
                                                    static_cast<size_t>(send_off[k + 1]) * D));
  }
  Kokkos::View<double*> recv_part(int k) const {
    return Kokkos::subview(recv_buf, std::make_pair(static_cast<size_t>(recv_off[k]) * D,
                                                    static_cast<size_t>(recv_off[k + 1]) * D));
  }

  // The positions of the own nodes that the neighbours hold, into send_buf.
  void pack(const NodeData<D>& n) const {
    const auto idx = send_idx;
    const auto buf = send_buf;
    const auto x = n.x;
    Kokkos::parallel_for(
        "fdem::halo::pack", Kokkos::RangePolicy<ExecSpace>(0, send_nodes()), KOKKOS_LAMBDA(const int j) {
          const int i = idx(j);
          for (int k = 0; k < D; ++k) buf(static_cast<size_t>(j) * D + k) = x(i, k);
        });
  }
  // recv_buf into the ghosts' positions; their forces zeroed.
  void unpack(const NodeData<D>& n) const {
    const auto idx = recv_idx;
    const auto buf = recv_buf;
    const auto x = n.x;
    const auto f = n.f;
    Kokkos::parallel_for(
        "fdem::halo::unpack", Kokkos::RangePolicy<ExecSpace>(0, recv_nodes()), KOKKOS_LAMBDA(const int j) {
          const int i = idx(j);
          for (int k = 0; k < D; ++k) {
            x(i, k) = buf(static_cast<size_t>(j) * D + k);
            f(i, k) = 0.0;
          }
        });
  }

 private:
  static Kokkos::View<int*> upload(const char* name, const std::vector<std::vector<int>>& lists, int count) {
    Kokkos::View<int*> v(std::string(name), static_cast<size_t>(count));
    auto h = Kokkos::create_mirror_view(v);
    int j = 0;
    for (const auto& l : lists)
      for (int i : l) h(j++) = i;
    Kokkos::deep_copy(v, h);
    return v;
  }
};

// One exchange among all the parts of a decomposed run held in this process (tests; and what the
// MPI exchange does between processes): each part packs, each send part is copied into the
// receive part of its neighbour, each part unpacks. `halos[p]` and `nodes[p]` belong to part p.
template <int D>
void exchange_in_process(const std::vector<Halo<D>>& halos, const std::vector<const NodeData<D>*>& nodes) {
  const int parts = static_cast<int>(halos.size());
  for (int p = 0; p < parts; ++p) halos[p].pack(*nodes[p]);
  for (int p = 0; p < parts; ++p)
    for (size_t k = 0; k < halos[p].neighbours.size(); ++k) {
      const int q = halos[p].neighbours[k];
      const auto& hq = halos[q].neighbours;
      const size_t kq = static_cast<size_t>(std::lower_bound(hq.begin(), hq.end(), p) - hq.begin());
      Kokkos::deep_copy(halos[q].recv_part(static_cast<int>(kq)), halos[p].send_part(static_cast<int>(k)));
    }
  for (int p = 0; p < parts; ++p) halos[p].unpack(*nodes[p]);
}

}  // namespace fdem
