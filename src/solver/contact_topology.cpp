#include "solver/contact_topology.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "common/error.hpp"
#include "common/union_find.hpp"
#include "kernels/contact/geometry.hpp"

namespace fdem {

bool contact_wanted(const Case& c, const HostMesh& mesh) {
  // a part of a decomposed mesh: as its whole mesh, which decompose gave a contact zone if so
  // (on explicitly without a zone: ContactSystem says what is missing)
  if (mesh.owned_nodes >= 0) return mesh.pieces >= 0 || c.contact.enabled == 1;
  if (c.contact.enabled >= 0) return c.contact.enabled == 1;
  return mesh.num_ifaces() > 0 || count_bodies(mesh) > 1;
}

namespace {

struct KeyHash {
  size_t operator()(const std::array<int, 3>& k) const {
    uint64_t h = 1469598103934665603ull;
    for (int v : k) {
      h ^= static_cast<uint64_t>(static_cast<uint32_t>(v));
      h *= 1099511628211ull;
    }
    return static_cast<size_t>(h);
  }
};

// d = 2 or 3 (the dimension). The first d entries are sorted by compare-and-swap: std::sort here
// made g++ 12, as nvcc's host compiler, report a false -Warray-bounds in its insertion sort.
std::array<int, 3> sorted_key(const int* nodes, int d) {
  std::array<int, 3> k{nodes[0], nodes[1], d == 3 ? nodes[2] : -1};
  auto order = [&k](int a, int b) {
    if (k[b] < k[a]) std::swap(k[a], k[b]);
  };
  order(0, 1);
  if (d == 3) {
    order(1, 2);
    order(0, 1);
  }
  return k;
}

// The element of each outer boundary face (-1: none found), by the faces' node sets.
template <int D>
void boundary_owners(const HostMesh& mesh, const std::vector<int>& bf, std::vector<int>& fowner) {
  const int nbf = static_cast<int>(bf.size()) / D, ne = mesh.num_elems();
  std::unordered_map<std::array<int, 3>, int, KeyHash> key_to_face;
  key_to_face.reserve(static_cast<size_t>(nbf) * 2);
  for (int f = 0; f < nbf; ++f) key_to_face[sorted_key(&bf[static_cast<size_t>(f) * D], D)] = f;
  const int npe = D + 1;
  for (int e = 0; e < ne && !key_to_face.empty(); ++e)
    for (int skip = 0; skip < npe; ++skip) {
      int nodes[3] = {-1, -1, -1}, c2 = 0;
      for (int a = 0; a < npe; ++a)
        if (a != skip) nodes[c2++] = mesh.elems[static_cast<size_t>(e) * npe + a];
      auto it = key_to_face.find(sorted_key(nodes, D));
      if (it != key_to_face.end()) fowner[it->second] = e;
    }
}

// Whether the owners given with the interfaces (mesh.iface_elems) each hold their face's nodes.
template <int D>
bool interface_owners_given(const HostMesh& mesh) {
  const int ne = mesh.num_elems(), ni = mesh.num_ifaces();
  auto holds = [&](int e, const int* nodes) {
    if (e < 0 || e >= ne) return false;
    for (int k = 0; k < D; ++k) {
      bool found = false;
      for (int a = 0; a <= D; ++a) found = found || mesh.elems[static_cast<size_t>(e) * (D + 1) + a] == nodes[k];
      if (!found) return false;
    }
    return true;
  };
  bool have_owner = static_cast<int>(mesh.iface_elems.size()) == 2 * ni;
  for (int q = 0; q < ni && have_owner; ++q) {
    const int* in = &mesh.ifaces[static_cast<size_t>(q) * 2 * D];
    have_owner = holds(mesh.iface_elems[2 * static_cast<size_t>(q)], in) &&
                 holds(mesh.iface_elems[2 * static_cast<size_t>(q) + 1], in + D);
  }
  return have_owner;
}

// The element of every face of every element, by the face's node set.
template <int D>
std::unordered_map<std::array<int, 3>, int, KeyHash> elements_of_faces(const HostMesh& mesh) {
  std::unordered_map<std::array<int, 3>, int, KeyHash> elem_of_face;
  const int npe = D + 1, ne = mesh.num_elems();
  for (int e = 0; e < ne; ++e)
    for (int skip = 0; skip < npe; ++skip) {
      int nodes[3] = {-1, -1, -1}, c2 = 0;
      for (int a = 0; a < npe; ++a)
        if (a != skip) nodes[c2++] = mesh.elems[static_cast<size_t>(e) * npe + a];
      elem_of_face[sorted_key(nodes, D)] = e;
    }
  return elem_of_face;
}

}  // namespace

template <int D>
ContactFaces contact_faces(const Case& c, const HostMesh& mesh) {
  const int ni = mesh.num_ifaces();
  // a part of a decomposed mesh: the whole mesh's outer faces that it holds (its own boundary
  // would also have the faces where its ghost layer ends)
  const std::vector<int> bf = mesh.owned_nodes >= 0 ? mesh.outer_faces : boundary_faces(mesh);
  ContactFaces F;
  const int nbf = F.nb = static_cast<int>(bf.size()) / D;
  F.nf = nbf + 2 * ni;
  F.fnode.assign(static_cast<size_t>(F.nf) * D, 0);
  F.fowner.assign(F.nf, -1);
  std::vector<int>& fnode = F.fnode;
  std::vector<int>& fowner = F.fowner;
  std::copy(bf.begin(), bf.end(), fnode.begin());
  boundary_owners<D>(mesh, bf, fowner);
  // interface faces: A side in its stored order (normal from A to B: outward of A); B side
  // reversed (outward of B); owners as given with the interfaces, else by their node sets
  const bool have_owner = interface_owners_given<D>(mesh);
  std::unordered_map<std::array<int, 3>, int, KeyHash> elem_of_face;
  if (!have_owner && ni > 0) elem_of_face = elements_of_faces<D>(mesh);
  for (int q = 0; q < ni; ++q) {
    const int* in = &mesh.ifaces[static_cast<size_t>(q) * 2 * D];
    const int fa = nbf + 2 * q, fb = fa + 1;
    for (int k = 0; k < D; ++k) fnode[static_cast<size_t>(fa) * D + k] = in[k];
    if (D == 2) {
      fnode[static_cast<size_t>(fb) * D + 0] = in[D + 1];
      fnode[static_cast<size_t>(fb) * D + 1] = in[D + 0];
    } else {
      fnode[static_cast<size_t>(fb) * D + 0] = in[D + 0];
      fnode[static_cast<size_t>(fb) * D + 1] = in[D + 2];
      fnode[static_cast<size_t>(fb) * D + 2] = in[D + 1];
    }
    if (have_owner) {
      fowner[fa] = mesh.iface_elems[2 * static_cast<size_t>(q)];
      fowner[fb] = mesh.iface_elems[2 * static_cast<size_t>(q) + 1];
    } else {
      auto ia = elem_of_face.find(sorted_key(in, D));
      auto ib = elem_of_face.find(sorted_key(in + D, D));
      if (ia == elem_of_face.end() || ib == elem_of_face.end())
        throw InputError(c.file + ": contact: interface " + std::to_string(q) + " has no element on a side");
      fowner[fa] = ia->second;
      fowner[fb] = ib->second;
    }
  }
  for (int f = 0; f < F.nf; ++f)
    if (fowner[f] < 0) throw InputError(c.file + ": contact: face " + std::to_string(f) + " has no element");
  return F;
}

template <int D>
FaceShares face_shares(const HostMesh& mesh, const ContactFaces& F, double thick) {
  const int nf = F.nf, nn = mesh.num_nodes();
  const std::vector<int>& fnode = F.fnode;
  FaceShares H;
  std::vector<int>& nfcount = H.nfoff;
  std::vector<double>& area = H.area;
  nfcount.assign(nn + 1, 0);
  area.assign(nn, 0.0);
  for (int f = 0; f < nf; ++f) {
    double xf[D][D];
    for (int a = 0; a < D; ++a)
      for (int k = 0; k < D; ++k) xf[a][k] = mesh.X[static_cast<size_t>(fnode[static_cast<size_t>(f) * D + a]) * D + k];
    const double share = face_share_of<D>(xf, thick);
    for (int a = 0; a < D; ++a) {
      const int i = fnode[static_cast<size_t>(f) * D + a];
      ++nfcount[i + 1];
      area[i] += share;
    }
  }
  for (int i = 0; i < nn; ++i) nfcount[i + 1] += nfcount[i];
  H.nface.assign(nfcount[nn], 0);
  std::vector<int>& nface = H.nface;
  {
    std::vector<int> cur(nfcount.begin(), nfcount.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int a = 0; a < D; ++a) nface[cur[fnode[static_cast<size_t>(f) * D + a]]++] = f;
  }
  return H;
}

template <int D>
HostVertexGroups vertex_groups(const HostMesh& mesh) {
  const int nn = mesh.num_nodes(), ni = mesh.num_ifaces();
  HostVertexGroups G;
  std::vector<int>& vgrp = G.vgrp;
  vgrp.assign(nn, 0);
  UnionFind uf(nn);
  for (int q = 0; q < ni; ++q)
    for (int k = 0; k < D; ++k)
      uf.join(mesh.ifaces[static_cast<size_t>(q) * 2 * D + k], mesh.ifaces[static_cast<size_t>(q) * 2 * D + D + k]);
  for (int i = 0; i < nn; ++i) vgrp[i] = uf.find(i);
  // groups that have interface pairs (numbered by first appearance): their entries (q * D + k,
  // in that order) and their copies (ascending), by counting: two passes, no list per group
  std::vector<int> gid(nn, -1);
  int ng = 0;
  G.off.assign(1, 0);
  for (int q = 0; q < ni; ++q)
    for (int k = 0; k < D; ++k) {
      const int r = vgrp[mesh.ifaces[static_cast<size_t>(q) * 2 * D + k]];
      if (gid[r] < 0) {
        gid[r] = ng++;
        G.off.push_back(0);
      }
      ++G.off[gid[r] + 1];
    }
  G.n = ng;
  G.copy_off.assign(ng + 1, 0);
  for (int i = 0; i < nn; ++i)
    if (gid[vgrp[i]] >= 0) ++G.copy_off[gid[vgrp[i]] + 1];
  for (int g = 0; g < ng; ++g) {
    G.off[g + 1] += G.off[g];
    G.copy_off[g + 1] += G.copy_off[g];
  }
  G.ent.assign(G.off[ng], 0);
  G.copy.assign(G.copy_off[ng], 0);
  {
    std::vector<int> at(G.off.begin(), G.off.end() - 1);
    for (int q = 0; q < ni; ++q)
      for (int k = 0; k < D; ++k)
        G.ent[at[gid[vgrp[mesh.ifaces[static_cast<size_t>(q) * 2 * D + k]]]]++] = q * D + k;
    at.assign(G.copy_off.begin(), G.copy_off.end() - 1);
    for (int i = 0; i < nn; ++i)
      if (gid[vgrp[i]] >= 0) G.copy[at[gid[vgrp[i]]]++] = i;
  }
  return G;
}

template ContactFaces contact_faces<2>(const Case& c, const HostMesh& mesh);
template ContactFaces contact_faces<3>(const Case& c, const HostMesh& mesh);
template FaceShares face_shares<2>(const HostMesh& mesh, const ContactFaces& F, double thick);
template FaceShares face_shares<3>(const HostMesh& mesh, const ContactFaces& F, double thick);
template HostVertexGroups vertex_groups<2>(const HostMesh& mesh);
template HostVertexGroups vertex_groups<3>(const HostMesh& mesh);

}  // namespace fdem
