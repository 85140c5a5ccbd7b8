#pragma once
// Domain decomposition of a host mesh after interface insertion (issue 20, docs/parallel.md): from
// a part id per element (partition.hpp), each part's own share of the mesh with the ghost layer it
// needs to compute its nodes' forces alone, and the lists of the per-step exchange of ghost node
// states between parts. Host only; the device side of the exchange is kernels/halo.hpp.
//
// Ownership. An element belongs to its part. A node belongs to the part of the first (lowest
// index) element that holds it: after insertion a node of a fracturable region has one element, so
// it goes with it; a node that elements of several parts share (a continuous region cut by the
// partition) goes to one of them. An interface is counted (energies, damage counts) by the owner
// of its first side-A node.
//
// What a part holds (its "local" items), so that the force on each of its own nodes is complete
// without any exchange of forces:
//   interfaces: those with at least one own node;
//   elements:   its own; those holding an own node; the sides of its interfaces (E1); and every
//               element holding a node of E1 (so that the masses of the nodes its interfaces join,
//               which set their springs' stable step, are complete);
//   nodes:      the nodes of those elements: its own, then the ghosts.
// Of the ghost elements only those at an own node need their bulk force (HostMesh::bulk_elems:
// they come right after the own ones); the others carry an interface's other side or a mass.
// Likewise only the ghost nodes a step reads (of the elements with a bulk force and of the
// interfaces) are exchanged; the rest (SubMesh::inert_ghosts, last) keep their first positions.
// A cut interface is thus computed by every part that owns one of its nodes, from the same
// positions (the ghosts' are the owners' to the bit after each exchange) and the same history, so
// its forces and its damage history are the same on each of them bit for bit: each part keeps the
// forces on its own nodes, and no force or history is ever sent. Ghost elements are computed too
// (their forces on shared own nodes count); the forces on ghost nodes are dropped.
//
// Order of the local items: own elements, ghost elements with a bulk force, the other ghost
// elements (each group in the whole mesh's order); own nodes, exchanged ghosts, inert ghosts;
// counted interfaces, then the others (each group in order of its side-A element's local index:
// the force pass's chunks, where every node has one element). The reductions of a step (energies, counts) run over the first
// owned_* items (HostMesh::owned_*), so that every item is summed by exactly one part.
#include <cstdio>
#include <memory>
#include <vector>

#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"

namespace fdem {

struct SubMesh {
  int part = 0, parts = 1;
  long whole_nodes = 0, whole_elems = 0, whole_ifaces = 0;  // the whole mesh's counts
  // The local mesh: node sets hold the own nodes only (velocity BCs, reactions, monitors: each
  // node is counted once over the parts); iface_sets the counted interfaces only; owned_* set.
  HostMesh mesh;
  std::vector<int> node_global, elem_global, iface_global;  // local index -> whole mesh's index
  // The exchange, per neighbouring part (neighbours sorted): `send[k]` are own local nodes whose
  // state part neighbours[k] needs, `recv[k]` the local ghost nodes it sends, both in order of the
  // whole mesh's node index, so that position j of part p's send list to q is position j of q's
  // receive list from p.
  std::vector<int> neighbours;
  std::vector<std::vector<int>> send, recv;
  // The last inert_ghosts nodes: ghosts that no step reads (nodes only of ghost elements without
  // a bulk force, in no local interface): never exchanged, they stay where they start.
  int inert_ghosts = 0;
  // Contact (decompose's contact_reach > 0): the part also holds, as ghosts, every element that
  // comes within this distance of one of its own nodes (at the reference positions) and the
  // interfaces at their nodes, and every ghost is exchanged; 0: no contact zone.
  double contact_reach = 0;
  // The positions the contact zones were taken at (decompose's `at`: a run's parts cut anew during
  // the run), D per local node; empty: the reference positions (mesh.X).
  std::vector<double> cut_x;
  int ghost_nodes() const { return mesh.num_nodes() - mesh.owned_nodes; }
  int ghost_elems() const { return mesh.num_elems() - mesh.owned_elems; }
};

// Every part's share of `whole` (after insert_interfaces), for part ids `elem_part` in
// [0, parts). InputError when elem_part does not have one valid id per element. Deterministic.
// contact_reach > 0 (a run with contact): each part also holds its contact zone (SubMesh::
// contact_reach), the whole mesh's outer faces it holds (HostMesh::outer_faces) and the whole
// mesh's piece count (HostMesh::pieces). at: the positions (as whole.X) to take the contact zones
// at (null: whole.X), kept in SubMesh::cut_x.
std::vector<SubMesh> decompose(const HostMesh& whole, const std::vector<int>& elem_part, int parts,
                               double contact_reach = 0, const std::vector<double>* at = nullptr);

// decompose() one part at a time, so that process 0 need not hold every part at once (it sends
// each as soon as it is built: solver/run_processes.cpp). part(p) builds part p (each once, in any
// order) with the lists of what it receives (SubMesh::neighbours and recv: the parts it receives
// from; send empty); what each part sends is known once every part is built: lists(p), which
// complete_lists adds. The same parts as decompose(), which is built on it. The mesh, the part ids
// and the positions `at` must outlive the builder. only >= 0: a builder of that part alone (its
// contact zone alone is searched; the mesh's pieces and smallest element size are left unset for
// the caller to fill: local_part.hpp); its lists() are not the part's (the send lists then come
// from the other parts' requests: lists_from_requests).
struct PartLists {
  std::vector<int> neighbours;             // sorted: the parts it receives from or sends to
  std::vector<std::vector<int>> send;      // per neighbour (SubMesh::send)
};
class PartBuilder {
 public:
  PartBuilder(const HostMesh& whole, const std::vector<int>& elem_part, int parts, double contact_reach = 0,
              const std::vector<double>* at = nullptr, int only = -1);
  ~PartBuilder();
  PartBuilder(const PartBuilder&) = delete;
  PartBuilder& operator=(const PartBuilder&) = delete;
  SubMesh part(int p);
  PartLists lists(int p);  // after every part is built; each once

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};
// Part s with its neighbours and send lists (its recv lists reordered to the neighbours').
void complete_lists(SubMesh& s, PartLists lists);

// A part as bytes (for sending it to its process) and back; unpack_submesh throws InputError on
// data that does not unpack exactly (damaged or cut short).
std::vector<char> pack_submesh(const SubMesh& s);
SubMesh unpack_submesh(const std::vector<char>& bytes);
std::vector<char> pack_lists(const PartLists& l);
PartLists unpack_lists(const std::vector<char>& bytes);
// A whole mesh as bytes and back (process 0 keeps the mesh it cuts the parts from in a file
// between the cuts: solver/run_processes.cpp).
std::vector<char> pack_mesh(const HostMesh& m);
HostMesh unpack_mesh(const std::vector<char>& bytes);
// pack_mesh's bytes written to the open file f at its position, without them in memory (a mesh
// kept aside in a temporary file: solver/kept_mesh.hpp); returns how many, -1 when the file
// refused them. read_mesh_file reads that many back from f's position (InputError: damaged).
long write_mesh_file(std::FILE* f, const HostMesh& m);
HostMesh read_mesh_file(std::FILE* f, long bytes);
// The same for a run's state (a re-cut sends the whole state to every process).
std::vector<char> pack_state(const StateArrays& s);
StateArrays unpack_state(const std::vector<char>& bytes);

}  // namespace fdem
