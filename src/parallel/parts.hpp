#pragma once
// The decomposition of a run as the time step sees it (docs/parallel.md): which process this is,
// the sums and minima over the processes, the exchange of the ghost nodes' state after each node
// update, the return of the contact forces put on ghost nodes, and the whole mesh's index of each
// local node, element and interface. A run on one process holds the trivial decomposition: one
// part, no ghosts, the OneProcess comm (src/parallel/comm.hpp). Its exchanges do nothing and its
// sums leave the values as they are, so the step and the ledger call them always, with no branch
// on the number of processes (the shape of ExaMiniMD's serial communicator and of CabanaPD's
// always-called halo gather). Host only; the device loops are kernels/halo.hpp and kernels/parts.hpp.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kernels/halo.hpp"
#include "kernels/model.hpp"
#include "kernels/parts.hpp"
#include "parallel/comm.hpp"
#include "parallel/decompose.hpp"

namespace fdem {

template <int D>
class Parts {
 public:
  Parts() : comm_(std::make_shared<OneProcess>()) {}

  // One part of a run over several processes (the model built from part.mesh): the comm, the
  // exchange lists (velocities: the ghosts' velocities travel too, for contact's friction) and the
  // whole mesh's numbering.
  void decompose(std::shared_ptr<const Comm> comm, const SubMesh& part, bool velocities) {
    comm_ = std::move(comm);
    halo_ = std::make_unique<Halo<D>>(part.neighbours, part.send, part.recv, velocities);
    node_global_ = part.node_global;
    elem_global_ = part.elem_global;
    iface_global_ = part.iface_global;
    whole_nn_ = part.whole_nodes;
    whole_ne_ = part.whole_elems;
    whole_ni_ = part.whole_ifaces;
    send_ = part.send;
    recv_ = part.recv;
  }

  // Whether the run is decomposed over several processes (what is written where and how a
  // checkpoint is gathered depend on it; the step does not ask).
  bool many() const { return halo_ != nullptr; }
  const Comm& comm() const { return *comm_; }
  const std::shared_ptr<const Comm>& comm_ptr() const { return comm_; }
  int rank() const { return comm_->rank(); }
  int size() const { return comm_->size(); }
  // Process 0: the one that writes the outputs gathered from all.
  bool root() const { return comm_->rank() == 0; }

  // In place over the processes, the same bits on each (one process: the values as they are).
  void sum(double* v, int n) const { comm_->sum(v, n); }
  void min(double* v, int n) const { comm_->min(v, n); }

  // After the node update: the ghosts take their owners' positions (and velocities) and their
  // forces are zeroed. `seconds` gets the time of the pack, the MPI and the unpack's launch.
  void exchange_ghosts(const Model<D>& m, double& seconds) const {
    if (!halo_) return;  // one part: no ghosts
    Kokkos::Timer clock;
    halo_->pack(m);
    fence("fdem::halo: packed");  // MPI reads the buffer
    comm_->exchange(halo_->neighbours, halo_->send_buf, halo_->send_off, halo_->recv_buf, halo_->recv_off,
                    halo_->per);
    halo_->unpack(m);  // runs before the next force pass on the same execution space: no fence
    seconds += clock.seconds();
  }

  // Whether the force pass adds its forces to m.f before contact's pass (`contact`: the run has
  // contact). Over several processes it must: contact's pass then starts from zero forces on the
  // ghosts (open_ghost_forces), to send back what its contacts put there. On one process the
  // force pass and contact share one scatter view and one contribute.
  bool force_pass_contributes(bool contact) const { return !contact || halo_ != nullptr; }
  // Before contact's pass over several processes: the ghosts' forces zeroed and the scatter view
  // emptied (the force pass contributed it already).
  template <class Scatter>
  void open_ghost_forces(const Model<D>& m, Scatter& scatter) const {
    if (!halo_) return;
    zero_ghost_forces(m);
    scatter.reset();
  }
  // After contact's pass: the forces on the ghosts go to their owners, which add them (in the order
  // of their neighbours). Every contact is computed once, by its node's owner.
  void return_ghost_forces(const Model<D>& m, double& seconds) const {
    if (!halo_) return;
    Kokkos::Timer clock;
    halo_->pack_forces(m);
    fence("fdem::halo: ghost forces packed");  // MPI reads the buffer
    comm_->exchange(halo_->neighbours, halo_->recv_buf, halo_->recv_off, halo_->send_buf, halo_->send_off, D);
    halo_->add_forces(m);
    seconds += clock.seconds();
  }

  // The own rows (the first `own`, `width` values each) of a per-node, per-element or
  // per-interface field gathered into the whole mesh's order on process 0; the others' left empty
  // (`ids`, `whole`: node_global() and whole_nodes(), or the elements' or interfaces'). One
  // process: the field as it is (its rows are the whole mesh's, in order).
  void gather_to_root(std::vector<double>& v, size_t own, size_t width, const std::vector<int>& ids,
                      long whole) const {
    if (!halo_) return;
    v = gather_rows(*comm_, v.data(), own, width, ids, static_cast<size_t>(whole));
  }

  // Bytes of ghost positions this process sends per step (0 on one process).
  long exchange_bytes() const { return halo_ ? halo_->send_bytes() : 0; }

  // The whole mesh's index of each local node, element and interface (own ones first; empty on one
  // process, where the local numbering is the whole mesh's) and the whole mesh's counts.
  const std::vector<int>& node_global() const { return node_global_; }
  const std::vector<int>& elem_global() const { return elem_global_; }
  const std::vector<int>& iface_global() const { return iface_global_; }
  long whole_nodes() const { return whole_nn_; }
  long whole_elems() const { return whole_ne_; }
  long whole_ifaces() const { return whole_ni_; }
  // The exchange's lists on the host (the Halo's neighbours; SubMesh::send, recv: local node
  // indices), for exchanges of other values than the step's (solver/fragment_parts.hpp).
  const std::vector<int>& neighbours() const {
    static const std::vector<int> none;
    return halo_ ? halo_->neighbours : none;
  }
  const std::vector<std::vector<int>>& send_lists() const { return send_; }
  const std::vector<std::vector<int>>& recv_lists() const { return recv_; }

 private:
  std::shared_ptr<const Comm> comm_;
  std::unique_ptr<Halo<D>> halo_;  // null: one part
  std::vector<int> node_global_, elem_global_, iface_global_;
  std::vector<std::vector<int>> send_, recv_;
  long whole_nn_ = 0, whole_ne_ = 0, whole_ni_ = 0;
};

}  // namespace fdem
