#pragma once
// Contact surfaces (docs/theory.md section 6b): which faces are surfaces, the vertex clusters
// that tell one piece from two, the surface nodes and their contact areas, the per-step geometry
// of the active faces and of the free elements, and the handover of failed interfaces to contact.
//
// Surfaces are faces (2D: edges, 3D: triangles) with their outward normal: the outer boundary of
// every body, and both faces of every failed interface once it is handed over. Every node of an
// active face is a "surface node".
#include <algorithm>

#include "kernels/contact/geometry.hpp"
#include "kernels/interface.hpp"

namespace fdem {

// Vertex groups that have interface node pairs (CSR, from the mesh): the entries q * D + k of
// group g's interface node pairs are ent(off(g)) .. ent(off(g + 1) - 1), its copies (node ids)
// copy(copy_off(g)) .. copy(copy_off(g + 1) - 1).
struct VertexGroups {
  Kokkos::View<int*> off, ent, copy_off, copy;
  int n = 0;
};

// Surface data the narrow phase needs: face nodes, the reference positions X and the 2D
// thickness (a face's share of its nodes' areas, face_share), which faces are active, the faces
// around each node, each surface node's contact area (half its share of its active faces:
// both sides of a contact carry half; one row per place in the list of surface nodes), the
// number of outer boundary faces nb (faces nb + 2q and nb + 2q + 1 are the two faces of
// interface q: face_interface) and the vertex groups/clusters (see PairFilter).
template <int D>
struct ContactSurface {
  Kokkos::View<int* [D + 1]> elem;  // the model's elements
  Kokkos::View<int*> fowner;         // element of each face
  Kokkos::View<int*> efree;          // 1: every face of the element is active (a free piece)
  // planes of the faces of free elements at the current positions (element_planes): for the
  // face opposite vertex a, the outward unit normal (0..D-1) and its offset n . x (D)
  Kokkos::View<double* [D + 1][D + 1]> eplane;
  FaceNodes<D> fnode;
  Kokkos::View<double* [D]> X;  // the model's reference positions (Model::X)
  double thick = 1.0;           // 2D: the thickness; 3D: 1
  // the model's interface handover flags (Model::icontact): which faces are surfaces (active)
  Kokkos::View<int*> icontact;
  // the faces around each node: nface(faces_begin(i)) .. nface(faces_end(i) - 1), ascending; the
  // offsets nfoff, or none where every node is on face_stride faces (a mesh with interfaces on every
  // face: each node is one element's corner, on D of its faces)
  Kokkos::View<int*> nfoff, nface;
  int face_stride = 0;
  KOKKOS_INLINE_FUNCTION int faces_begin(int i) const { return face_stride > 0 ? face_stride * i : nfoff(i); }
  KOKKOS_INLINE_FUNCTION int faces_end(int i) const { return face_stride > 0 ? face_stride * (i + 1) : nfoff(i + 1); }
  // Whether face f is a surface: an outer face, or a face of an interface handed over (computed
  // where needed rather than stored for every face).
  KOKKOS_INLINE_FUNCTION bool active(int f) const {
    const int q = face_interface(f, nb);
    return q < 0 || icontact(q) != 0;
  }
  // Whether it was one before the handovers of this poll (hand_over_failed marks those kHandedNow
  // or kApartNow until ContactSystem::check_failures has updated the lists: clear_apart_marks).
  KOKKOS_INLINE_FUNCTION bool active_before_poll(int f) const {
    const int q = face_interface(f, nb);
    return q < 0 || icontact(q) == 1;
  }
  Kokkos::View<double*> narea;  // by place in the list of surface nodes (node_areas)
  // friction coefficient of each face (nf) when some interface is a frictional joint
  // (Model::ifric): the joint's for the faces of its interfaces, -1 (the contact law's) for the
  // others; empty otherwise
  Kokkos::View<double*> fmu;
  int nb = 0;
  Kokkos::View<int*> vgrp, clus;
  // geometry of the active faces at the current positions (face_geometry): row fslot(f) for an
  // active face f (its place in the list of active faces), FaceGeo<D>::size values each
  Kokkos::View<int*> fslot;
  Kokkos::View<double**> fgeo;
};

// The geometry of every active face at the current positions (see FaceGeo), once per step.
template <int D>
void face_geometry(const Kokkos::View<double* [D]>& x, const ContactSurface<D>& surf,
                   const Kokkos::View<int*>& afaces, int na) {
  auto xx = x;
  auto fnode = surf.fnode;
  auto geo = surf.fgeo;
  auto af = afaces;
  Kokkos::parallel_for(
      "fdem::contact::face_geometry", Kokkos::RangePolicy<ExecSpace>(0, na), KOKKOS_LAMBDA(const int i) {
        const int f = af(i);
        double xf[D][D];
        int v[D];
        fnode.get(f, v);
        for (int a = 0; a < D; ++a)
          for (int k = 0; k < D; ++k) xf[a][k] = xx(v[a], k);
        face_geometry_of<D>(xf, geo, i);
      });
}

// Planes of the faces of the free elements at the current positions (see element_depth).
template <int D>
void element_planes(const Kokkos::View<double* [D]>& x, const ContactSurface<D>& surf, int ne) {
  auto xx = x;
  auto elem = surf.elem;
  auto efree = surf.efree;
  auto eplane = surf.eplane;
  Kokkos::parallel_for(
      "fdem::contact::element_planes", Kokkos::RangePolicy<ExecSpace>(0, ne), KOKKOS_LAMBDA(const int e) {
        if (!efree(e)) return;
        double xe[D + 1][D];
        for (int a = 0; a <= D; ++a)
          for (int k = 0; k < D; ++k) xe[a][k] = xx(elem(e, a), k);
        for (int a = 0; a <= D; ++a) {
          double xf[D][D], n[D];
          int c = 0;
          for (int b = 0; b <= D; ++b)
            if (b != a) {
              for (int k = 0; k < D; ++k) xf[c][k] = xe[b][k];
              ++c;
            }
          face_normal<D>(xf, n);
          double side = 0;
          for (int k = 0; k < D; ++k) side += (xe[a][k] - xf[0][k]) * n[k];
          const double sg = side < 0 ? 1.0 : -1.0;  // outward: away from vertex a
          double off = 0;
          for (int k = 0; k < D; ++k) {
            eplane(e, a, k) = sg * n[k];
            off += sg * n[k] * xf[0][k];
          }
          eplane(e, a, D) = off;
        }
      });
}

// Per-face friction (surf.fmu, allocated) from the per-interface friction of frictional joints
// (ifric, Model::ifric): the interface's for its two faces, -1 for the outer boundary. Returns the
// largest.
template <int D>
double joint_face_friction(const ContactSurface<D>& surf, const Kokkos::View<double*>& ifric_in, int nf) {
  auto fmu = surf.fmu;
  const int nb = surf.nb;
  auto ifric = ifric_in;
  double mu_max = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::joint_friction", Kokkos::RangePolicy<ExecSpace>(0, nf),
      KOKKOS_LAMBDA(const int f, double& mx) {
        const int q = face_interface(f, nb);
        fmu(f) = q < 0 ? -1.0 : ifric(q);
        mx = fmu(f) > mx ? fmu(f) : mx;
      },
      Kokkos::Max<double>(mu_max));
  return mu_max;
}

// Clusters: within each vertex group, copies joined by intact interface pairs share the smallest
// node id (surf.clus).
// (IfaceView: Model::iface, View<int* [2 * D]>. A template parameter, not that type: nvcc 13's
// front end crashed on a parameter whose extent is an expression of D, docs/cuda.md.)
template <int D, class IfaceView>
void update_clusters(const VertexGroups& G, const ContactSurface<D>& surf, const IfaceView& iface_in,
                     const Kokkos::View<int*>& icontact_in) {
  if (G.n == 0) return;
  auto goff = G.off;
  auto gent = G.ent;
  auto gcoff = G.copy_off;
  auto gcopy = G.copy;
  auto clus = surf.clus;
  auto iface = iface_in;
  auto icontact = icontact_in;
  Kokkos::parallel_for(
      "fdem::contact::clusters", Kokkos::RangePolicy<ExecSpace>(0, G.n), KOKKOS_LAMBDA(const int g) {
        for (int c = gcoff(g); c < gcoff(g + 1); ++c) clus(gcopy(c)) = gcopy(c);
        bool changed = true;
        while (changed) {
          changed = false;
          for (int t = goff(g); t < goff(g + 1); ++t) {
            const int q = gent(t) / D, k = gent(t) % D;
            if (icontact(q)) continue;
            const int a = iface(q, k), b = iface(q, D + k);
            const int ca = clus(a), cb = clus(b);
            if (ca != cb) {
              const int lo = ca < cb ? ca : cb;
              clus(a) = lo;
              clus(b) = lo;
              changed = true;
            }
          }
        }
      });
}

// The indices i < n with keep(i), in order, into out (a compact list); returns their number.
// Keep: a device-callable predicate (Flagged: flag(i) != 0; ActiveFaces: ContactSurface::active).
template <class Keep>
int compact_where(const char* label, const Keep& keep, const Kokkos::View<int*>& out_in, int n) {
  auto out = out_in;
  int count = 0;
  Kokkos::parallel_scan(
      label, Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
        if (keep(i)) {
          if (final) out(upd) = i;
          ++upd;
        }
      },
      count);
  return count;
}

// compact_where into `out` grown to hold the kept entries (counted first; grown by half again
// when it grows, up to n, so that a list of the surfaces is sized by the surfaces that exist, not
// by every node or face that may become one).
template <class Keep>
int compact_where_grown(const char* label, const Keep& keep, Kokkos::View<int*>& out, int n) {
  int count = 0;
  Kokkos::parallel_reduce(
      label, Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const int i, int& c) { c += keep(i) ? 1 : 0; },
      count);
  if (static_cast<int>(out.extent(0)) < count) {
    const long cap = std::min<long>(n, count + count / 2 + 64L);
    out = Kokkos::View<int*>(Kokkos::view_alloc(Kokkos::WithoutInitializing, out.label()), cap);
  }
  return compact_where(label, keep, out, n);
}

struct Flagged {
  Kokkos::View<int*> flag;
  KOKKOS_INLINE_FUNCTION bool operator()(const int i) const { return flag(i) != 0; }
};
template <int D>
struct ActiveFaces {
  ContactSurface<D> S;
  KOKKOS_INLINE_FUNCTION bool operator()(const int f) const { return S.active(f); }
};

// The indices i < n with flag(i) != 0, into `out` grown to hold them (compact_where_grown).
inline int compact_flagged_grown(const char* label, const Kokkos::View<int*>& flag, Kokkos::View<int*>& out, int n) {
  return compact_where_grown(label, Flagged{flag}, out, n);
}

// How many of the first n entries of an ascending list are below `bound`.
inline int count_below(const Kokkos::View<int*>& list_in, int n, int bound) {
  auto list = list_in;
  int count = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::count_below", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i, int& c) { c += list(i) < bound ? 1 : 0; }, count);
  return count;
}

// The row of each active face in surf.fgeo (its place in the list of active faces).
template <int D>
void face_slots(const ContactSurface<D>& surf, const Kokkos::View<int*>& afaces_in, int na) {
  auto fslot = surf.fslot;
  auto afaces = afaces_in;
  Kokkos::parallel_for(
      "fdem::contact::face_slots", Kokkos::RangePolicy<ExecSpace>(0, na),
      KOKKOS_LAMBDA(const int i) { fslot(afaces(i)) = i; });
}

// mark(i) = 1 for the nodes of the active faces, 0 for all others.
template <int D>
void mark_surface_nodes(const ContactSurface<D>& surf, const Kokkos::View<int*>& afaces_in, int na,
                        const Kokkos::View<int*>& mark_in) {
  auto mark = mark_in;
  auto afaces = afaces_in;
  auto fnode = surf.fnode;
  Kokkos::deep_copy(mark, 0);
  Kokkos::parallel_for(
      "fdem::contact::mark_nodes", Kokkos::RangePolicy<ExecSpace>(0, na), KOKKOS_LAMBDA(const int i) {
        for (int a = 0; a < D; ++a) Kokkos::atomic_exchange(&mark(fnode(afaces(i), a)), 1);
      });
}

// mark(list(b)) = b + 1 for the n nodes of `list` (after compact_flagged_grown: the surface nodes, so
// that mark, still non-zero exactly on them, also gives each node's place in the list;
// ContactSystem::surface_places).
inline void number_listed(const Kokkos::View<int*>& mark_in, const Kokkos::View<int*>& list_in, int n) {
  auto mark = mark_in;
  auto list = list_in;
  Kokkos::parallel_for(
      "fdem::contact::number_surface_nodes", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int b) { mark(list(b)) = b + 1; });
}

// Free elements (all D + 1 faces active: a fragment that is one element) into surf.efree;
// returns their number.
template <int D>
int flag_free_elements(const ContactSurface<D>& surf, const Kokkos::View<int*>& afaces_in, int na, int ne) {
  auto efree = surf.efree;
  auto fowner = surf.fowner;
  auto afaces = afaces_in;
  Kokkos::deep_copy(efree, 0);
  Kokkos::parallel_for(
      "fdem::contact::free_count", Kokkos::RangePolicy<ExecSpace>(0, na), KOKKOS_LAMBDA(const int i) {
        Kokkos::atomic_add(&efree(fowner(afaces(i))), 1);
      });
  int nfree = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::free_flag", Kokkos::RangePolicy<ExecSpace>(0, ne),
      KOKKOS_LAMBDA(const int e, int& cnt) {
        efree(e) = efree(e) == D + 1 ? 1 : 0;
        cnt += efree(e);
      },
      nfree);
  return nfree;
}

// Face f's share of each of its nodes' areas at the reference positions (face_share_of),
// computed where needed rather than stored for every face.
template <int D>
KOKKOS_INLINE_FUNCTION double face_share(const ContactSurface<D>& S, int f) {
  double xf[D][D];
  int v[D];
  S.fnode.get(f, v);
  for (int a = 0; a < D; ++a)
    for (int k = 0; k < D; ++k) xf[a][k] = S.X(v[a], k);
  return face_share_of<D>(xf, S.thick);
}

// Contact area of each of the ns surface nodes `nodes` (surf.narea, by place in the list): half
// its share of its active faces, summed per node over its faces in a fixed order (the same sums
// whatever the threads).
template <int D>
void node_areas(const ContactSurface<D>& surf, const Kokkos::View<int*>& nodes_in, int ns) {
  const ContactSurface<D> S = surf;
  auto nodes = nodes_in;
  Kokkos::parallel_for(
      "fdem::contact::node_area", Kokkos::RangePolicy<ExecSpace>(0, ns), KOKKOS_LAMBDA(const int p) {
        const int i = nodes(p);
        double a = 0.0;
        for (int j = S.faces_begin(i); j < S.faces_end(i); ++j)
          if (S.active(S.nface(j))) a += 0.5 * face_share<D>(S, S.nface(j));
        S.narea(p) = a;
      });
}

// Model::icontact of an interface handed over at this poll whose state passes to the contacts of
// its nodes (the narrow phase's HandoverSeed, kernels/contact/narrow_phase.hpp); after that pass
// it becomes 1 like every handed-over interface (clear_handover_marks). kApartNow: one handed over
// at this poll that carried nothing (1 once the poll has updated the lists: clear_apart_marks).
// Both tell the faces that become surfaces at this poll (ContactSurface::active_before_poll).
inline constexpr int kHandedNow = 2;
inline constexpr int kApartNow = 3;

// Hands every failed interface (damage 1 at all its points) that has parted or come apart over
// to contact; ni: the number of interfaces. One that has parted gets m.icontact(q) = kHandedNow:
// it still carried its compression and friction, which its nodes' contacts take over. One that
// has come apart (interface_apart) carried nothing already: kApartNow. Returns how many. Clears the
// force kernel's flag m.icontact_pending (by a kernel: no copy to the device).
template <int D>
int hand_over_failed(const Model<D>& m, int ni) {
  auto icontact = m.icontact;
  auto ihist = m.ihist;
  auto iface = m.iface;
  auto x = m.x;
  const double slip = m.handover_slip;
  int n = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::handover", Kokkos::RangePolicy<ExecSpace>(0, ni),
      KOKKOS_LAMBDA(const int q, int& cnt) {
        if (icontact(q)) return;
        bool all = true;
        for (int k = 0; k < D; ++k)
          all = all && cohesive_damage(load_point(ihist, q, k)) >= 1.0;
        if (!all) return;
        double xa[D][D], xb[D][D];
        for (int k = 0; k < D; ++k)
          for (int i = 0; i < D; ++i) {
            xa[k][i] = x(iface(q, k), i);
            xb[k][i] = x(iface(q, D + k), i);
          }
        CohesivePoint h[D];
        for (int k = 0; k < D; ++k) h[k] = load_point(ihist, q, k);
        const bool apart = interface_apart<D>(xa, xb, h);
        if (apart || interface_parted<D>(xa, xb, slip)) {
          icontact(q) = apart ? kApartNow : kHandedNow;
          ++cnt;
        }
      },
      n);
  auto pending = m.icontact_pending;
  if (pending.data() != nullptr)
    Kokkos::parallel_for(
        "fdem::contact::pending_clear", Kokkos::RangePolicy<ExecSpace>(0, 1),
        KOKKOS_LAMBDA(const int) { pending() = 0; });
  return n;
}

// The interfaces handed over at this poll that carried nothing (kApartNow) handed over like any
// other (icontact 1), once the poll has updated the lists.
inline void clear_apart_marks(const Kokkos::View<int*>& icontact_in, int ni) {
  auto icontact = icontact_in;
  Kokkos::parallel_for(
      "fdem::contact::apart_marks", Kokkos::RangePolicy<ExecSpace>(0, ni), KOKKOS_LAMBDA(const int q) {
        if (icontact(q) == kApartNow) icontact(q) = 1;
      });
}

// After the narrow pass that took their state over: the interfaces handed over at this poll are
// handed over like any other (icontact 1).
inline void clear_handover_marks(const Kokkos::View<int*>& icontact_in, int ni) {
  auto icontact = icontact_in;
  Kokkos::parallel_for(
      "fdem::contact::handover_marks", Kokkos::RangePolicy<ExecSpace>(0, ni), KOKKOS_LAMBDA(const int q) {
        if (icontact(q) == kHandedNow) icontact(q) = 1;
      });
}

}  // namespace fdem
