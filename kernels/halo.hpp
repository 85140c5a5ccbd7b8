#pragma once
// The per-step exchange of a decomposed run (src/parallel/decompose.hpp builds the lists) on the
// device: after the node update each part packs the positions of its own nodes that other parts
// hold as ghosts into one buffer, the buffers travel (in one process: exchange_in_process; over
// MPI: the same buffers handed to MPI), and each part unpacks what it received into its ghost
// nodes. Positions only without contact: the force pass reads no velocity (the node update, which
// does, covers the own nodes only). With contact (velocities = true) the velocities too (the
// friction of a contact reads the face's), and after the contact pass the forces the part's
// contacts put on ghost nodes go back the same way reversed and are added to their owners'
// (pack_forces, add_forces). The ghosts' forces are zeroed at the unpack.
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
       const std::vector<std::vector<int>>& recv, bool velocities = false)
      : neighbours(nbrs), per(velocities ? 2 * D : D) {
    send_off.assign(1, 0);
    recv_off.assign(1, 0);
    for (size_t k = 0; k < nbrs.size(); ++k) {
      send_off.push_back(send_off.back() + static_cast<int>(send[k].size()));
      recv_off.push_back(recv_off.back() + static_cast<int>(recv[k].size()));
    }
    send_idx = upload("fdem::halo::send_idx", send, send_off.back());
    recv_idx = upload("fdem::halo::recv_idx", recv, recv_off.back());
    send_buf = Kokkos::View<double*>("fdem::halo::send_buf", static_cast<size_t>(send_off.back()) * per);
    recv_buf = Kokkos::View<double*>("fdem::halo::recv_buf", static_cast<size_t>(recv_off.back()) * per);
  }

  std::vector<int> neighbours;
  int per = D;                          // doubles per node of the exchange: D, or 2 D with velocities
  std::vector<int> send_off, recv_off;  // per neighbour k: its nodes are [off[k], off[k + 1])
  Kokkos::View<int*> send_idx, recv_idx;
  Kokkos::View<double*> send_buf, recv_buf;  // `per` doubles per node (D for the forces going back)

  int send_nodes() const { return send_off.back(); }
  int recv_nodes() const { return recv_off.back(); }
  bool velocities() const { return per == 2 * D; }
  // Bytes one exchange sends (and, with contact, the forces this part sends back: D doubles per
  // ghost node).
  long send_bytes() const { return static_cast<long>(send_nodes()) * per * sizeof(double); }
  long force_bytes() const { return velocities() ? static_cast<long>(recv_nodes()) * D * sizeof(double) : 0; }
  // The doubles of neighbour k in each buffer, w per node.
  Kokkos::View<double*> send_part(int k, int w = -1) const {
    w = w < 0 ? per : w;
    return Kokkos::subview(send_buf, std::make_pair(static_cast<size_t>(send_off[k]) * w,
                                                    static_cast<size_t>(send_off[k + 1]) * w));
  }
  Kokkos::View<double*> recv_part(int k, int w = -1) const {
    w = w < 0 ? per : w;
    return Kokkos::subview(recv_buf, std::make_pair(static_cast<size_t>(recv_off[k]) * w,
                                                    static_cast<size_t>(recv_off[k + 1]) * w));
  }

  // The positions (and velocities) of the own nodes that the neighbours hold, into send_buf.
  void pack(const NodeData<D>& n) const {
    const auto idx = send_idx;
    const auto buf = send_buf;
    const auto x = n.x;
    const auto v = n.v;
    const int w = per;
    Kokkos::parallel_for(
        "fdem::halo::pack", Kokkos::RangePolicy<ExecSpace>(0, send_nodes()), KOKKOS_LAMBDA(const int j) {
          const int i = idx(j);
          for (int k = 0; k < D; ++k) buf(static_cast<size_t>(j) * w + k) = x(i, k);
          if (w > D)
            for (int k = 0; k < D; ++k) buf(static_cast<size_t>(j) * w + D + k) = v(i, k);
        });
  }
  // recv_buf into the ghosts' positions (and velocities); their forces zeroed.
  void unpack(const NodeData<D>& n) const {
    const auto idx = recv_idx;
    const auto buf = recv_buf;
    const auto x = n.x;
    const auto v = n.v;
    const auto f = n.f;
    const int w = per;
    Kokkos::parallel_for(
        "fdem::halo::unpack", Kokkos::RangePolicy<ExecSpace>(0, recv_nodes()), KOKKOS_LAMBDA(const int j) {
          const int i = idx(j);
          for (int k = 0; k < D; ++k) {
            x(i, k) = buf(static_cast<size_t>(j) * w + k);
            f(i, k) = 0.0;
          }
          if (w > D)
            for (int k = 0; k < D; ++k) v(i, k) = buf(static_cast<size_t>(j) * w + D + k);
        });
  }
  // The forces on the ghost nodes (the contact forces this part's contacts put there: the caller
  // zeroes the ghosts' forces before the contact pass), D doubles per node, into recv_buf: it goes
  // back to the owners (the exchange with send and receive swapped).
  void pack_forces(const NodeData<D>& n) const {
    const auto idx = recv_idx;
    const auto buf = recv_buf;
    const auto f = n.f;
    Kokkos::parallel_for(
        "fdem::halo::pack_forces", Kokkos::RangePolicy<ExecSpace>(0, recv_nodes()), KOKKOS_LAMBDA(const int j) {
          const int i = idx(j);
          for (int k = 0; k < D; ++k) buf(static_cast<size_t>(j) * D + k) = f(i, k);
        });
  }
  // What the neighbours sent back (send_buf, D doubles per node) added to the own nodes' forces,
  // one neighbour after the other in order (a node that several neighbours hold gets their forces
  // in that order: the same sums on every run).
  void add_forces(const NodeData<D>& n) const {
    const auto idx = send_idx;
    const auto buf = send_buf;
    const auto f = n.f;
    for (size_t q = 0; q < neighbours.size(); ++q)
      Kokkos::parallel_for(
          "fdem::halo::add_forces", Kokkos::RangePolicy<ExecSpace>(send_off[q], send_off[q + 1]),
          KOKKOS_LAMBDA(const int j) {
            const int i = idx(j);
            for (int k = 0; k < D; ++k) f(i, k) += buf(static_cast<size_t>(j) * D + k);
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

// Where part p stands in the sorted neighbour list of halo h.
template <int D>
int slot_of(const Halo<D>& h, int p) {
  return static_cast<int>(std::lower_bound(h.neighbours.begin(), h.neighbours.end(), p) - h.neighbours.begin());
}

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
      Kokkos::deep_copy(halos[q].recv_part(slot_of(halos[q], p)), halos[p].send_part(static_cast<int>(k)));
    }
  for (int p = 0; p < parts; ++p) halos[p].unpack(*nodes[p]);
}

// The forces on the ghosts back to their owners, among parts held in this process (tests; what
// the MPI exchange does reversed): each part packs its ghosts' forces, each goes to the owner's
// send part, each part adds what came back.
template <int D>
void return_forces_in_process(const std::vector<Halo<D>>& halos, const std::vector<const NodeData<D>*>& nodes) {
  const int parts = static_cast<int>(halos.size());
  for (int p = 0; p < parts; ++p) halos[p].pack_forces(*nodes[p]);
  for (int p = 0; p < parts; ++p)
    for (size_t k = 0; k < halos[p].neighbours.size(); ++k) {
      const int q = halos[p].neighbours[k];
      Kokkos::deep_copy(halos[q].send_part(slot_of(halos[q], p), D), halos[p].recv_part(static_cast<int>(k), D));
    }
  for (int p = 0; p < parts; ++p) halos[p].add_forces(*nodes[p]);
}

}  // namespace fdem
