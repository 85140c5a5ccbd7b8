#pragma once
// Narrow phase of contact (docs/theory.md section 6b), every step, one thread per surface node
// over its candidates: gap, normal and contact point of the node against each candidate face;
// normal and shear penalty springs (K_n A_c, K_s A_c), no tension, incremental shear force with
// Coulomb friction and cohesion (kernels/friction.hpp); the shear force of each (node, face) pair
// is kept between steps and across rebuilds. Forces go to the force kernel's scatter view.
// The law of one pair (contact_pair) is in kernels/contact/contact_pair.hpp. How the points go to
// threads is here too, since it shapes the pass: ranges of equal work on host threads
// (BalancedPoints), teams of 32 sharing the gaps of a point with many candidates on GPUs
// (ContactTeamPoints), the seeds' own kernel (PointSeeds), and the candidates' spread that
// summary.json reports. One file: the pass and its launches change together.
#include "kernels/contact/broad_phase.hpp"
#include "kernels/contact/contact_pair.hpp"
#include "kernels/contact/surfaces.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Scratch of the narrow phase, one entry per candidate pair (sized like the pair list).
template <int D>
struct PairScratch {
  Kokkos::View<double*> g, phi, depth, w, rel;
  Kokkos::View<double* [D]> n;
  // host backends with several threads: the prefix sum of the points' work (BalancedPoints), one
  // entry per surface point and one more; empty on GPUs
  Kokkos::View<int*> work;
  // the passes with seeds (Seed 2): each point's HandoverSeed (SeedRow), one row per surface point
  Kokkos::View<double* [D + 6], Kokkos::LayoutRight> seed;
};

// Node s against a free element e (all its faces are surfaces: a fragment that is one element):
// the node is in contact when it lies inside e, with the depth d = min over the faces of the
// distance to the face's plane, through the nearest face. The potential 0.5 K A d^2 is continuous
// (zero on e's boundary, the nearest face changes where two depths are equal), so contacts with
// fragments neither create nor lose energy, and a node at a corner shared by many fragments is in
// contact only with the one it has entered. Returns the depth (<= 0: outside) and the local
// index of the vertex opposite the nearest face. Uses the planes from element_planes. (It takes
// the surface, not the plane View: CUDA 13.0's cicc crashed on a device function with a
// View<double* [D + 1][D + 1]> parameter.)
struct ElementDepth {
  double depth;  // <= 0: outside
  int nearest;   // local index of the vertex opposite the nearest face (-1: outside)
};

template <int D>
KOKKOS_FORCEINLINE_FUNCTION ElementDepth element_depth(const ContactSurface<D>& S, int e, const double (&p)[D]) {
  ElementDepth r{1e300, -1};
  for (int a = 0; a <= D; ++a) {
    double d = S.eplane(e, a, D);
    for (int k = 0; k < D; ++k) d -= S.eplane(e, a, k) * p[k];
    if (d < r.depth) {
      r.depth = d;
      r.nearest = d > 0.0 ? a : -1;
    }
  }
  return r;
}

// Fade of a node against a face of a piece that is not a single free element, with least
// barycentric coordinate `score` of the projection: full on the face, fading out smoothly (C1)
// over tol beyond its edge, so that faces meeting at an edge or vertex share a node (their
// weights are then normalised, see contact_forces).
KOKKOS_FORCEINLINE_FUNCTION double contact_fade(double s, double tol) {
  if (s >= 0.0) return 1.0;
  if (s <= -tol) return 0.0;
  const double t = (s + tol) / tol;
  return t * t * (3.0 - 2.0 * t);
}

// A node is in contact with a face only if its own surface faces it: a node of the body below,
// just under the edge of a block resting on it, is behind the plane of the block's side face
// (and, once the block has sunk into the penalty by a little, within its extent), but its
// surface points up, not towards the side face, and must not be pushed sideways (it would
// plough the block). `facing` = max over the node's active faces of
// -n_node . n_face; the weight rises smoothly from 0 at facing 0.2 to 1 at 0.5.
KOKKOS_FORCEINLINE_FUNCTION double facing_fade(double facing) {
  if (facing >= 0.5) return 1.0;
  if (facing <= 0.2) return 0.0;
  const double t = (facing - 0.2) / 0.3;
  return t * t * (3.0 - 2.0 * t);
}

template <int D>
KOKKOS_FORCEINLINE_FUNCTION double node_facing(const ContactSurface<D>& S, int s, const double (&n)[D]) {
  double best = -1.0;
  for (int q = S.faces_begin(s); q < S.faces_end(s); ++q) {
    const int f2 = S.nface(q);
    if (!S.active(f2)) continue;
    double cw = 0;
    for (int k = 0; k < D; ++k) cw -= S.fgeo(S.fslot(f2), D + k) * n[k];
    best = cw > best ? cw : best;
  }
  return best;
}

// Two faces of one piece: they share a vertex whose copies are joined by intact material (same
// node, or copies in one cluster).
template <int D>
KOKKOS_FORCEINLINE_FUNCTION bool same_piece(const ContactSurface<D>& S, int fa, int fb) {
  int on_a[D], on_b[D];
  S.fnode.get(fa, on_a);
  S.fnode.get(fb, on_b);
  for (int i = 0; i < D; ++i) {
    const int va = on_a[i];
    for (int k = 0; k < D; ++k) {
      const int vb = on_b[k];
      if (S.vgrp(va) == S.vgrp(vb) && S.clus(va) == S.clus(vb)) return true;
    }
  }
  return false;
}

// The candidates of one surface node that the passes after weigh visit: the pairs that may carry
// a weight or a history (a near face, a free element, a contact at the last step or an allowance
// g0 < 0), listed by weigh (Cap at most; a node with more visits all its candidates, with the same
// sums). The others, most of the candidates (a face in front of the node by dpen or more, or
// beyond dpen and not a free element's, with nothing stored), get no weight, release nothing and
// have nothing to update, so skipping them changes no sum.
inline constexpr int kSubsetCap = 48;
template <int Cap>
struct PairSubset {
  static constexpr int kList = Cap;
  int j[kList];
  int n = 0;  // listed pairs (> kList: all of b..e are visited)
  int b = 0, e = 0;
  KOKKOS_INLINE_FUNCTION void add(int jj) {
    if (n < kList) j[n] = jj;
    ++n;
  }
  KOKKOS_INLINE_FUNCTION int count() const { return n <= kList ? n : e - b; }
  KOKKOS_INLINE_FUNCTION int operator[](int t) const { return n <= kList ? j[t] : b + t; }
};

// What the interfaces handed over at this poll (icontact kHandedNow, hand_over_failed) leave to
// one of their nodes: its share of their compressive penalty's force (fn) and energy (un) and of
// their friction springs' energy (us) and force (F, on the node). The node's contacts start from
// it (contacts, contact_pair): a new contact may start as deep as carries fn (or stores un, where
// that is less), a contact that grows takes un as budget, and each contact's shear spring starts
// with its share of F; what they do not take is dissipated. Each node of a point's pair takes
// half of the point's state (the contacts of the node against the other side's faces carry half
// the load, those of the other side's nodes the rest), but for a node that overhangs
// (seed_share): at the end of a joint whose blocks have slid past each other the interface still
// paired a node beyond the other block's end with that block's last node; the overhanging node
// finds no face under it, and its half would go to no one (the other block then settles onto the
// contacts left, docs/theory.md section 4), so its partner takes the whole point's. Each node's
// seed comes from the interfaces' state and the faces round the pair's nodes alone, which every
// process that holds the node holds alike (they lie within the search distance of it: the
// contact zone, docs/parallel.md).
template <int D>
struct HandoverSeed {
  double un = 0, us = 0, fn = 0;  // fn: its share of the compressive penalty's force (magnitude)
  double F[D] = {};
  bool any = false;
  // the values as contacts reads them (SeedRow: the same from the pass's scratch)
  KOKKOS_INLINE_FUNCTION double n_energy() const { return un; }
  KOKKOS_INLINE_FUNCTION double s_energy() const { return us; }
  KOKKOS_INLINE_FUNCTION double n_force() const { return fn; }
  KOKKOS_INLINE_FUNCTION double force(int k) const { return F[k]; }
  KOKKOS_INLINE_FUNCTION bool has() const { return any; }
  // a new contact of the node (area Anode) starts as deep as carries the seed's force share, or as
  // stores its energy share where that is less (a node whose contact area is smaller than the
  // interface points' share: the rest comes as the body settles)
  KOKKOS_INLINE_FUNCTION double limit(const ContactLaw& L, double Anode) const {
    return un > 0.0 ? kmin(kmath::sqrt(2.0 * un / (L.kn * Anode)), fn / (L.kn * Anode)) : 0.0;
  }
  // the factor on F so that the node's shear springs store at most us
  KOKKOS_INLINE_FUNCTION double cut(const ContactLaw& L, double Anode) const {
    double F2 = 0;
    for (int k = 0; k < D; ++k) F2 += F[k] * F[k];
    return F2 > 2.0 * L.ks * Anode * us ? kmath::sqrt(2.0 * L.ks * Anode * us / F2) : 1.0;
  }
};
// The shear force a pair's spring starts with (contact_pair's SeedForce): the seed's F scaled by
// the pair's share (the force read where contact_pair adds it).
template <class SeedT>
struct ScaledSeed {
  const SeedT& seed;
  double scale;
  KOKKOS_INLINE_FUNCTION bool on() const { return seed.has(); }
  KOKKOS_INLINE_FUNCTION double operator[](int k) const { return scale * seed.force(k); }
};

// A point's HandoverSeed in the pass's scratch (PairScratch::seed, row i: un, us, fn, F, any, and
// limit and cut at the node's area), read where contacts needs each value: on GPUs the seed then
// holds no registers through the contacts but the row's address (docs/cuda.md, "Kernel
// resources"). The rows are LayoutRight: one thread reads one row, in a rare pass.
template <int D>
struct SeedRow {
  using View = Kokkos::View<double* [D + 6], Kokkos::LayoutRight>;
  const double* r;
  static KOKKOS_INLINE_FUNCTION void store(const View& v, int i, const HandoverSeed<D>& s, const ContactLaw& L,
                                           double Anode) {
    v(i, 0) = s.un;
    v(i, 1) = s.us;
    v(i, 2) = s.fn;
    for (int k = 0; k < D; ++k) v(i, 3 + k) = s.F[k];
    v(i, 3 + D) = s.any ? 1.0 : 0.0;
    v(i, 4 + D) = s.limit(L, Anode);
    v(i, 5 + D) = s.cut(L, Anode);
  }
  KOKKOS_INLINE_FUNCTION double n_energy() const { return r[0]; }
  KOKKOS_INLINE_FUNCTION double s_energy() const { return r[1]; }
  KOKKOS_INLINE_FUNCTION double n_force() const { return r[2]; }
  KOKKOS_INLINE_FUNCTION double force(int k) const { return r[3 + k]; }
  KOKKOS_INLINE_FUNCTION bool has() const { return r[3 + D] != 0.0; }
  KOKKOS_INLINE_FUNCTION double limit(const ContactLaw&, double) const { return r[4 + D]; }
  KOKKOS_INLINE_FUNCTION double cut(const ContactLaw&, double) const { return r[5 + D]; }
};

// Whether node a overhangs in the direction t (a unit vector in the interface's plane, from its
// partner to it): one of the outer faces round it (the mesh's boundary, not an interface's) faces
// within 60 degrees of t, so that a beyond its partner lies outside the body its partner is on.
template <int D>
KOKKOS_INLINE_FUNCTION bool overhangs(const ContactSurface<D>& S, const Kokkos::View<double* [D]>& x, int a,
                                      const double (&t)[D]) {
  for (int j = S.faces_begin(a); j < S.faces_end(a); ++j) {
    const int f = S.nface(j);
    if (face_interface(f, S.nb) >= 0 || !S.active(f)) continue;
    double xf[D][D], n[D], d = 0;
    int v[D];
    S.fnode.get(f, v);
    for (int b = 0; b < D; ++b)
      for (int i = 0; i < D; ++i) xf[b][i] = x(v[b], i);
    face_normal<D>(xf, n);
    for (int i = 0; i < D; ++i) d += n[i] * t[i];
    if (d > 0.5) return true;
  }
  return false;
}

// The share of point k of interface q (nodes xa, xb; normal n) that its side-A node takes (side
// B's takes 1 minus it): 1/2, or 0 where the A node overhangs and the B node does not, 1 the
// other way round; 1/2 where the faces have not slid (the slip below 1e-9 of the face's size).
template <int D>
KOKKOS_INLINE_FUNCTION double seed_share(const ContactSurface<D>& S, const Kokkos::View<double* [D]>& x,
                                         const InterfaceData<D>& in, int q, const double (&xa)[D][D],
                                         const double (&xb)[D][D], const double (&n)[D], int k) {
  double t[D], tn = 0, t2 = 0, size2 = 0;
  for (int i = 0; i < D; ++i) {
    t[i] = xa[k][i] - xb[k][i];
    tn += t[i] * n[i];
    const double e = xa[(k + 1) % D][i] - xa[k][i];
    size2 += e * e;
  }
  for (int i = 0; i < D; ++i) {
    t[i] -= tn * n[i];
    t2 += t[i] * t[i];
  }
  if (!(t2 > 1e-18 * size2)) return 0.5;
  const double il = 1.0 / kmath::sqrt(t2);
  double back[D];
  for (int i = 0; i < D; ++i) {
    t[i] *= il;
    back[i] = -t[i];
  }
  const bool a_over = overhangs<D>(S, x, in.iface(q, k), t), b_over = overhangs<D>(S, x, in.iface(q, D + k), back);
  return a_over == b_over ? 0.5 : a_over ? 0.0 : 1.0;
}

template <int D>
KOKKOS_INLINE_FUNCTION HandoverSeed<D> handover_seed(const ContactSurface<D>& S, const InterfaceData<D>& in,
                                                     const Kokkos::View<double* [D]>& x, int s) {
  HandoverSeed<D> r;
  for (int t = S.faces_begin(s); t < S.faces_end(s); ++t) {
    const int q = face_interface(S.nface(t), S.nb);
    if (q < 0 || in.icontact(q) != kHandedNow) continue;
    int k = -1;
    double side = 1.0;  // the force on the node: +F on side A's, -F on side B's
    for (int a = 0; a < D; ++a) {
      if (in.iface(q, a) == s) k = a;
      if (in.iface(q, D + a) == s) {
        k = a;
        side = -1.0;
      }
    }
    if (k < 0) continue;
    double xa[D][D], xb[D][D], n[D], ap_cur, d[D], dn = 0;
    gather_interface<D>(x, in.iface, q, xa, xb);
    interface_frame<D>(xa, xb, 1.0, n, ap_cur);
    for (int i = 0; i < D; ++i) {
      d[i] = xb[k][i] - xa[k][i];
      dn += d[i] * n[i];
    }
    const double a_share = seed_share<D>(S, x, in, q, xa, xb, n, k);
    const double w = side > 0.0 ? a_share : 1.0 - a_share;  // this node's share of the point's
    if (!(w > 0.0)) continue;
    const CohesiveParams p = in.params(q);
    const double ap = in.iarea(q);
    r.any = true;
    r.un += dn < 0.0 ? w * 0.5 * ap * p.kn * dn * dn : 0.0;
    r.fn += dn < 0.0 ? -w * ap * p.kn * dn : 0.0;
    if (in.has_slip() && p.tanphir >= 0.0) {  // failed: the residual friction carries all the shear
      double e[D];
      const double e2 = elastic_slip<D>(n, d, load_slip<D>(in.islip, q, k), e);
      r.us += w * 0.5 * ap * p.ks * e2;
      for (int i = 0; i < D; ++i) r.F[i] += side * w * ap * p.ks * e[i];
    }
  }
  return r;
}

// The narrow-phase pass over one surface node's candidates (see contact_forces): the weight of
// every pair (weigh, share), what the weight changes release (release), then the contacts.
// Scratch per pair: g gap, phi fade (< 0: a free element's face), n normal, w weight, depth the
// depth at the last step, rel the energy released (written for the pairs of the node's
// PairSubset only, for all its candidates when the subset overflows).
#if defined(__GNUC__) && !defined(__CUDA_ARCH__) && !defined(__HIP_DEVICE_COMPILE__)
#define FDEM_NARROW_GAPS_FIRST 1
#else
#define FDEM_NARROW_GAPS_FIRST 0
#endif

// Seed: 0, the pass reads `seeding` (host backends); 1, no node has a seed; 2, the seeds are in
// scr.seed (PointSeeds wrote them before the pass). GPUs take 1 or 2 by `seeding` at the launch:
// the seeds' values (a rare pass: the polls with handovers) then cost the common pass no
// registers (docs/cuda.md, "Kernel resources").
template <int D, bool Fric, int Cap = kSubsetCap, int Seed = 0>
struct ContactForcesFn {
  using Subset = PairSubset<Cap>;
  Kokkos::View<double* [D]> x, v, xbuild;
  ForceScatter<D> scatter;
  Kokkos::View<int*> pts;
  PairList<D> P;
  PairScratch<D> scr;
  ContactSurface<D> S;
  ContactLaw L;
  double dt;
  int nforce;  // the points from nforce on are only followed (displacement, speed): a part's ghosts
  // the interfaces; seeding: some were handed over at this poll (their nodes' HandoverSeed)
  InterfaceData<D> in;
  bool seeding;
  KOKKOS_INLINE_FUNCTION bool seeds() const { return Seed == 0 ? seeding : Seed == 2; }

  KOKKOS_INLINE_FUNCTION void operator()(const int i, ContactSums& sums) const { point<false>(i, sums); }

  // The candidates of point i that gets its contacts (0 for a point only followed).
  KOKKOS_INLINE_FUNCTION int candidates(const int i) const {
    if (i >= nforce) return 0;
    const int s = pts(i);
    return P.off(s + 1) - P.off(s);
  }

  // The gap of point i to its candidates b <= j < e into scr.g (a team's threads take a share each:
  // ContactTeamPoints).
  KOKKOS_INLINE_FUNCTION void gap(const int i, const int j) const {
    const int s = pts(i);
    double xs[D], n[D], wv[D];
    for (int k = 0; k < D; ++k) xs[k] = x(s, k);
    scr.g(j) = face_gap_geo<D>(S.fgeo, S.fslot(P.face(j)), xs, n, wv);
  }

  // Point i's passes (weigh, share, release, contacts). Ready: the gaps of its candidates are in
  // scr.g already (ContactTeamPoints).
  template <bool Ready>
  KOKKOS_INLINE_FUNCTION void point(const int i, ContactSums& sums) const {
    auto f = scatter.access();
    const int s = pts(i);
    double xs[D], d2 = 0, v2 = 0;
    for (int k = 0; k < D; ++k) {
      xs[k] = x(s, k);
      d2 += (xs[k] - xbuild(s, k)) * (xs[k] - xbuild(s, k));
      v2 += v(s, k) * v(s, k);
    }
    sums.d2max = d2 > sums.d2max ? d2 : sums.d2max;
    sums.v2max = v2 > sums.v2max ? v2 : sums.v2max;
    if (i >= nforce) return;
    const int b = P.off(s), e = P.off(s + 1);
    if (b == e) {
      if constexpr (Seed == 2) {
        const SeedRow<D> seed{&scr.seed(i, 0)};
        sums.dissipated += seed.n_energy() + seed.s_energy();  // no contact to take it
      } else if (seeds()) {
        const HandoverSeed<D> seed = handover_seed<D>(S, in, x, s);
        sums.dissipated += seed.un + seed.us;  // no contact to take it
      }
      return;
    }
    const double Anode = S.narea(i);
    Subset sub;
    sub.b = b;
    sub.e = e;
    weigh<false, Ready>(s, b, e, xs, sub);
    if (sub.n > Cap) {  // overflow: the later passes visit every pair, so every pair gets its scratch
      sub.n = 0;
      // (host backends and Ready: every gap is in scr.g already)
      weigh<true, Ready || FDEM_NARROW_GAPS_FIRST != 0>(s, b, e, xs, sub);
    }
    share(sub);
    release(sub, Anode);
    // the seed only now (it is not used before): on GPUs the registers of the passes above stay
    // free of it (docs/cuda.md, "Kernel resources")
    if constexpr (Seed == 2) {  // (written by the pass's seed kernel: PointSeeds)
      contacts(f, s, i, sub, SeedRow<D>{&scr.seed(i, 0)}, sums);
    } else {
      contacts(f, s, i, sub, seeds() ? handover_seed<D>(S, in, x, s) : HandoverSeed<D>{}, sums);
    }
  }

  // 1. the weight of every pair (w: 0 not in contact; phi < 0 marks a free element's), with the
  //    depth of each contact at the last step (for the allowance of contacts that start).
  //    Free elements (a node's candidates are sorted by element: the depth is computed
  //    once per element): weight 1 through the nearest face when the node is inside. Other
  //    faces: gap, normal and fade at the face's edge (0: not near) here, the weight in 2.
  //    The pairs the later passes visit go to sub; All: every pair gets its scratch (the others
  //    weight 0, no fade, no depth), for a node whose subset overflows.
  template <bool All, bool Ready>
  KOKKOS_INLINE_FUNCTION void weigh(int s, int b, int e, const double (&xs)[D], Subset& sub) const {
    int last_e = -1, last_a = -1;
    double last_d = 0.0;
    // host CPUs: the gaps of all candidates first, in a loop without a branch, so that the core
    // reads their face rows (one random row each) side by side; in the loop below a branch on
    // each gap would wait for its row, and a mispredicted one (the outcome is about even) throws
    // away the reads begun after it. GPUs hide the latency with other threads instead, or take
    // the gaps of a point with many candidates from the threads of its team (Ready).
    constexpr bool from_scratch = Ready || FDEM_NARROW_GAPS_FIRST;
    if constexpr (!Ready && FDEM_NARROW_GAPS_FIRST) all_gaps(b, e, xs);
    for (int j = b; j < e; ++j) {
      const double fn = P.fn(j);
      const bool hist = fn > 0.0 || P.g0(j) < 0.0;
      const int fc = P.face(j);
      double n[D], N[D], wv[D];  // normal, barycentric coordinates, offset from the face
      double g;
      bool far;
      if constexpr (from_scratch) {
        g = scr.g(j);
        far = !hist && !(g < L.dpen);
        if (!far) face_gap_geo<D>(S.fgeo, S.fslot(fc), xs, n, wv);  // n and wv (the same g)
      } else {
        g = face_gap_geo<D>(S.fgeo, S.fslot(fc), xs, n, wv);
        far = !hist && !(g < L.dpen);
      }
      // in front of the face by dpen or more: not near, and outside the face's element (no
      // weight when that is a free element either); most candidates end here
      if (far) {
        if (All) none(j, g);
        continue;
      }
      const int own = S.fowner(fc);
      const bool near = g > -L.dpen && g < L.dpen;
      const bool fr = S.efree(own);
      if (!near && !fr && !hist) {
        if (All) none(j, g);
        continue;
      }
      double w = 0.0;
      if (fr) {  // a free element: contact through its nearest face, if inside
        if (own != last_e) {
          last_e = own;
          const ElementDepth ed = element_depth<D>(S, own, xs);
          last_d = ed.depth;
          last_a = ed.nearest;
        }
        bool mine = last_d > 0.0 && last_d < L.dpen;
        for (int k = 0; k < D && mine; ++k) mine = S.fnode(fc, k) != S.elem(own, last_a);
        if (!mine && !hist) {
          if (All) none(j, g);
          continue;
        }
        w = mine ? 1.0 : 0.0;
      }
      // a near face of another piece: its fade at the face's edge; a node beyond the edge (most
      // near faces: the fan of faces around the opposite copy of the node's vertex) with nothing
      // stored gets no weight and has nothing to update, so it stays out of the subset
      double phi = fr ? -1.0 : 0.0;
      if (!fr && near) {
        face_bary_geo<D>(S.fgeo, S.fslot(fc), wv, N);
        double score = N[0];
        for (int a = 1; a < D; ++a) score = N[a] < score ? N[a] : score;
        phi = contact_fade(score, L.tol);
        if (phi > 0.0 && g < 0.0) phi *= facing_fade(node_facing<D>(S, s, n));
        if (!(phi > 0.0) && !hist) {
          if (All) none(j, g);
          continue;
        }
      }
      sub.add(j);
      scr.depth(j) = fn > 0.0 ? fn / (L.kn * kmath::sqrt(P.ac(j))) : -1.0;
      scr.g(j) = g;
      scr.w(j) = w;
      scr.phi(j) = phi;  // a free element's (-1), no weight (0: only the history to update), or the fade
      if (phi > 0.0)
        for (int k = 0; k < D; ++k) scr.n(j, k) = n[k];
    }
  }

  // the gaps of the candidates b <= j < e into scr.g, in a loop without a branch (see weigh)
  KOKKOS_INLINE_FUNCTION void all_gaps(int b, int e, const double (&xs)[D]) const {
    for (int j = b; j < e; ++j) {
      double n[D], wv[D];
      scr.g(j) = face_gap_geo<D>(S.fgeo, S.fslot(P.face(j)), xs, n, wv);
    }
  }

  // the scratch of a pair outside the subset: no weight, no fade, no contact at the last step
  KOKKOS_INLINE_FUNCTION void none(int j, double g) const {
    scr.depth(j) = -1.0;
    scr.g(j) = g;
    scr.w(j) = 0.0;
    scr.phi(j) = 0.0;
  }

  // 2. the other faces: each penetrated near face is a contact, its weight shared among the near
  //    coplanar faces of its piece. The near faces (phi > 0, a few per node) are listed first,
  //    so that the pass is linear in the candidates and quadratic only in the near faces (kNear
  //    of them at most in the list; a node with more takes the direct loop, same sums).
  static constexpr int kNear = 32;
  KOKKOS_INLINE_FUNCTION void share(const Subset& sub) const {
    int near[kNear];
    int nnear = 0;
    const int cnt = sub.count();
    for (int t = 0; t < cnt && nnear <= kNear; ++t) {
      const int j = sub[t];
      if (scr.phi(j) > 0.0) {
        if (nnear < kNear) near[nnear] = j;
        ++nnear;
      }
    }
    const bool listed = nnear <= kNear;
    for (int t = 0; t < cnt; ++t) {
      const int j = sub[t];
      if (!(scr.g(j) < 0.0 && scr.phi(j) > 0.0)) continue;  // w stays as weigh left it
      double sum = 0;
      if (listed) {
        for (int u = 0; u < nnear; ++u) sum += share_term(j, near[u]);
      } else {
        for (int u = 0; u < cnt; ++u)
          if (scr.phi(sub[u]) > 0.0) sum += share_term(j, sub[u]);
      }
      scr.w(j) = scr.phi(j) / (sum > 1.0 ? sum : 1.0);
    }
  }
  // near face jj's part of the weight sum of penetrated face j: its fade when it is j itself, or
  // coplanar with j (normals within cos_same) on the same piece; else 0
  KOKKOS_INLINE_FUNCTION double share_term(int j, int jj) const {
    if (jj != j) {
      double d = 0;
      for (int k = 0; k < D; ++k) d += scr.n(j, k) * scr.n(jj, k);
      if (!(d > L.cos_same) || !same_piece<D>(S, P.face(j), P.face(jj))) return 0.0;
    }
    return scr.phi(jj);
  }

  // 3. what the weight changes release (the budget of rising ones, step 4)
  KOKKOS_INLINE_FUNCTION void release(const Subset& sub, double Anode) const {
    const int cnt = sub.count();
    for (int t = 0; t < cnt; ++t) {
      const int j = sub[t];
      const double ge = scr.g(j) - P.g0(j), Aw = Anode * scr.w(j);
      scr.rel(j) =
          P.fn(j) > 0.0 && Aw < P.ac(j) && ge < 0.0 ? 0.5 * L.kn * (P.ac(j) - Aw) * ge * ge : 0.0;
    }
  }

  // The largest contact energy of the node at the last step with a face related to face fc (of
  // the same piece, see same_piece), as depth(j) = depth * sqrt(effective area) = sqrt(2 U / K_n)
  // (-1: not in contact): a contact with fc of effective area A can take over the depth
  // related / sqrt(A), the one at which it stores that energy (see contact_pair). 0 when there is
  // none. Over the pairs of sub: the others had no contact.
  KOKKOS_INLINE_FUNCTION double related(const Subset& sub, int fc) const {
    double d = 0.0;
    const int cnt = sub.count();
    for (int t = 0; t < cnt; ++t) {
      const int jj = sub[t];
      if (scr.depth(jj) > d && same_piece<D>(S, fc, P.face(jj))) d = scr.depth(jj);
    }
    return d;
  }

  // 4. the contacts; the energy a contact released as its weight fell may go to a related one
  //    whose weight rises (a node moving from one face of a piece onto the next). What the
  //    node's contacts release in all is dissipated: the weights and allowances change the
  //    normal springs' energy at fixed positions, with no force doing work (a node sliding off
  //    the edge of the face it presses on: its weight fades out while compressed).
  //    A node with a HandoverSeed: its new contacts may start as deep as carries the seed's force
  //    fn over the node's area (or stores its energy un, where that is less), its growing ones
  //    take their weight's share of un as budget, and each contact's shear spring starts with
  //    its weight's share of F (cut so that the springs store at most us); the seed is released
  //    here and what the contacts take is booked back.
  template <class Force, class SeedT>
  KOKKOS_INLINE_FUNCTION void contacts(const Force& f, int s, int i, const Subset& sub, const SeedT& seed,
                                       ContactSums& sums) const {
    sums.dissipated += seed.s_energy();
    // the pairs that release energy (rel > 0: contacts whose weight fell, a few per node), listed
    // as in share so that the budgets cost the releasing pairs, not all candidates
    int relj[kNear];
    int nrel = 0;
    const int cnt = sub.count();
    for (int t = 0; t < cnt && nrel <= kNear; ++t) {
      const int j = sub[t];
      if (scr.rel(j) > 0.0) {
        if (nrel < kNear) relj[nrel] = j;
        ++nrel;
      }
    }
    const bool listed = nrel <= kNear;
    double moved = 0.0;  // energy the weight changes put into the normal springs (< 0: released)
    for (int t = 0; t < cnt; ++t) {
      const int j = sub[t];
      const int fc = P.face(j);
      const double w = scr.w(j);
      if (!(w > 0.0) && !(P.fn(j) > 0.0) && !(P.g0(j) < 0.0)) continue;  // as contact_pair: nothing to do
      const double Anode = S.narea(i);  // (read for each pair, as the position: registers)
      double lim = w > 0.0 && !(scr.depth(j) >= 0.0) ? related(sub, fc) / kmath::sqrt(Anode * w) : 0.0;
      if (w > 0.0 && !(scr.depth(j) >= 0.0)) {
        const double seed_lim = seed.limit(L, Anode);
        lim = lim > seed_lim ? lim : seed_lim;
      }
      double budget = w > 0.0 && scr.depth(j) >= 0.0 ? w * seed.n_energy() : 0.0;
      if (w > 0.0 && scr.depth(j) >= 0.0 && Anode * w > P.ac(j) && nrel > 0) {
        if (listed) {
          for (int u = 0; u < nrel; ++u) {
            const int jj = relj[u];
            if (jj != j && same_piece<D>(S, fc, P.face(jj))) budget += scr.rel(jj);
          }
        } else {
          for (int u = 0; u < cnt; ++u) {
            const int jj = sub[u];
            if (jj != j && scr.rel(jj) > 0.0 && same_piece<D>(S, fc, P.face(jj))) budget += scr.rel(jj);
          }
        }
      }
      // a contact (or one starting with a related one's energy) still within dpen of its face, not
      // a free element's (its potential is continuous: the nearest face changes where two depths
      // are equal): its spring energy at this gap with the last step's area and allowance, and
      // after the update
      const double ge_old = scr.g(j) - P.g0(j), ac_old = P.fn(j) > 0.0 ? P.ac(j) : 0.0;
      const bool counts =
          ge_old < 0.0 && scr.g(j) > -L.dpen && !(scr.phi(j) < 0.0) && (P.fn(j) > 0.0 || lim > 0.0);
      // the node's position and velocity read for each pair (not held through the loop: registers)
      double xs[D], vs[D];
      for (int k = 0; k < D; ++k) {
        xs[k] = x(s, k);
        vs[k] = v(s, k);
      }
      contact_pair<D, Fric>(S, L, v, f, P.fn, P.ac, P.g0, P.fs, j, s, fc, xs, vs, Anode * w, lim, budget, dt,
                            ScaledSeed<SeedT>{seed, seed.cut(L, Anode) * w}, sums);
      if (counts) {
        const double ge = scr.g(j) - P.g0(j);
        moved += 0.5 * L.kn * (P.ac(j) * ge * ge - ac_old * ge_old * ge_old);
      }
    }
    moved -= seed.n_energy();
    if (moved < 0.0) sums.dissipated -= moved;
  }
};

// The narrow phase by teams (GPUs: a warp each, kNarrowTeamSize threads): team t takes the
// points t T ... t T + T - 1, a thread each, as the plain kernel does; but the gaps of a point with
// more than `above` candidates (a node where a body has fragmented: its candidates run to the
// hundreds while its neighbours' are a few dozen) are shared by all the team's threads first, so
// that its thread's passes only read them (the gaps are most of a point's work: one random face
// row per candidate), and the warp does not wait on one thread's long loop. The sums are the plain
// kernel's, point by point (only the order of the threads' sums differs).
inline constexpr int kNarrowTeamSize = 32;
#ifndef FDEM_NARROW_TEAM_ABOVE
#define FDEM_NARROW_TEAM_ABOVE 16
#endif
inline constexpr int kNarrowTeamAbove = FDEM_NARROW_TEAM_ABOVE;  // 0: no teams (the plain kernel)
template <class Fn>
struct ContactTeamPoints {
  Fn fn;
  int np, above;
  using Member = typename Kokkos::TeamPolicy<ExecSpace>::member_type;
  KOKKOS_INLINE_FUNCTION void operator()(const Member& t, ContactSums& sums) const {
    const int i0 = t.league_rank() * t.team_size(), i1 = kmin(i0 + t.team_size(), np);
    // 1. the gaps of the team's heavy points, each thread a share of each one's candidates (the
    //    test on the count is the same in every thread of the team)
    bool any = false;
    for (int i = i0; i < i1; ++i) {
      const int c = fn.candidates(i);
      if (c <= above) continue;
      any = true;
      const int b = fn.P.off(fn.pts(i));
      Kokkos::parallel_for(Kokkos::TeamThreadRange(t, b, b + c), [&](const int j) { fn.gap(i, j); });
    }
    if (any) t.team_barrier();
    // 2. each thread its own point: a heavy one from its gaps
    const int i = i0 + t.team_rank();
    if (i >= i1) return;
    if (fn.candidates(i) > above) fn.template point<true>(i, sums);
    else fn.template point<false>(i, sums);
  }
};

// The narrow phase's points on a host backend with T > 1 threads: T contiguous ranges of about
// equal work (a point's work: kPointWork plus its candidates), one range item per thread, instead
// of Kokkos' T ranges of equal point counts. The contacts gather where a body fragments, so equal
// counts leave most of the candidates to one thread while the others wait at the end of the pass
// (the default 3D impact on 2 threads: the narrow phase 1.37 times faster than on one thread with
// equal counts, docs/performance-impact.md section 2). `work` holds the exclusive prefix sum of
// the points' work (np + 1 entries; ContactSystem::refresh_surfaces sizes it, contact_forces fills it
// before each pass). The ranges depend on the candidate lists
// only, and a static range of T items puts item t on thread t: each thread takes the same points
// at every step in the same order, so a run on T threads repeats itself bit for bit.
inline constexpr int kPointWork = 2;
template <class Fn>
struct BalancedPoints {
  Fn fn;
  Kokkos::View<int*> work;
  int np, nthreads;
  // the first point whose work begins at or after `bound` (np: none)
  KOKKOS_INLINE_FUNCTION int first_at(long long bound) const {
    int lo = 0, hi = np;
    while (lo < hi) {
      const int mid = lo + (hi - lo) / 2;
      if (work(mid) >= bound) hi = mid;
      else lo = mid + 1;
    }
    return lo;
  }
  KOKKOS_INLINE_FUNCTION void operator()(const int t, ContactSums& sums) const {
    const long long total = work(np);
    const int b = first_at(total * t / nthreads), e = first_at(total * (t + 1) / nthreads);
    for (int i = b; i < e; ++i) fn(i, sums);
  }
};

// The seeds of the first nforce points into scr.seed (SeedRow), for a pass with Seed 2: a kernel of
// their own, so that their computation costs the pass no registers.
template <int D>
struct PointSeeds {
  Kokkos::View<int*> pts;
  ContactSurface<D> S;
  InterfaceData<D> in;
  Kokkos::View<double* [D]> x;
  typename SeedRow<D>::View seed;
  ContactLaw L;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const {
    const int s = pts(i);
    SeedRow<D>::store(seed, i, handover_seed<D>(S, in, x, s), L, S.narea(i));
  }
};

// One narrow-phase pass of fn over the np points: one thread per point, or, above > 0, by teams
// (ContactTeamPoints; kNarrowTeamSize threads on GPUs, what the host backend allows up to that).
template <class Fn>
void narrow_pass(const Fn& fn, int np, int above, const Kokkos::View<ContactSums>& pass) {
  if (above > 0 && np > 0) {
    const ContactTeamPoints<Fn> tp{fn, np, above};
    int ts = kNarrowTeamSize;
    if constexpr (std::is_same<MemSpace, Kokkos::HostSpace>::value) {
      const Kokkos::TeamPolicy<ExecSpace> probe(1, 1);
      ts = kmin(ts, probe.team_size_max(tp, Kokkos::ParallelReduceTag()));
    }
    Kokkos::parallel_reduce("fdem::contact::forces_teams [device]",
                            Kokkos::TeamPolicy<ExecSpace, HeavyLaunchBounds>((np + ts - 1) / ts, ts), tp, pass);
    return;
  }
  Kokkos::parallel_reduce("fdem::contact::forces [device]", Kokkos::RangePolicy<ExecSpace, HeavyLaunchBounds>(0, np),
                          fn, pass);
}

// Contact forces of all surface nodes `points` against their candidate faces; adds them to m.f
// with atomics and updates the pair history. dt: the step (relative displacement increments are
// v(n-1/2) dt, as for the platens). xb: positions at the last build.
//
// Against a free element (a fragment that is one element) the node is in contact through the
// element's nearest face when it lies inside (element_depth). Against any other face, each face
// that the node penetrates (-dpen < g < 0) is a contact of its own (a node may touch several
// pieces), with the effective area A w: A the node's contact area, w the fade at the face's edge
// (contact_fade), shared among coplanar faces of one piece so that they form a partition of
// unity where they meet. Both vary continuously with the positions, so contacts begin and end
// without jumps in the stored energy. Fric: see contact_pair.
// The forces go into the scatter view sf (the force kernel's, not contributed yet: the same
// copies on host backends, so that the sums do not depend on the order the threads add in and a
// run with T threads repeats itself bit for bit; atomics on GPUs).
// The sums go to `pass` (device memory: no wait for the host; ContactSystem::update reads them
// through contact_account). Cap: the capacity of a node's PairSubset (the tests take a small one
// to check that the overflow path gives the same sums).
// nforce: only the first nforce points get their contacts (a part of a decomposed run: its own
// surface nodes); the others' displacements and speeds still count in the sums.
// On host backends with several threads the points go to the threads in ranges of equal work
// (BalancedPoints; scratch.work must then hold np + 1 entries, else the plain range runs).
// seeding: interfaces were handed over at this poll (HandoverSeed).
// team_above > 0: the points with more candidates share their gaps among a team's threads
// (ContactTeamPoints; the GPUs' default, kNarrowTeamAbove); 0: one thread per point (on host
// backends with several threads, in ranges of equal work).
template <int D, bool Fric = true, int Cap = kSubsetCap>
void contact_forces(const Model<D>& m, const Kokkos::View<int*>& points, int np, int nforce, const PairList<D>& P,
                    const PairScratch<D>& scratch, const ContactSurface<D>& surf, const ContactLaw& law,
                    double dt, const Kokkos::View<double* [D]>& xb, const ForceScatter<D>& sf,
                    const Kokkos::View<ContactSums>& pass, bool seeding, int team_above) {
  // (host backends only: `if constexpr`, so that a device build compiles no kernel for it)
  if constexpr (std::is_same<MemSpace, Kokkos::HostSpace>::value) {
    const ContactForcesFn<D, Fric, Cap> fn{m.x,  m.v, xb, sf,           points, P,      scratch,
                                           surf, law, dt, nforce, m.interfaces(), seeding};
    const int nt = ExecSpace().concurrency();
    if (team_above <= 0 && nt > 1 && np > 0 && static_cast<int>(scratch.work.extent(0)) > np) {
      auto work = scratch.work;
      auto off = P.off;
      auto pts = points;
      Kokkos::parallel_scan(
          "fdem::contact::forces_split [device]", Kokkos::RangePolicy<ExecSpace>(0, np),
          KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
            const int s = pts(i);
            const int w = i < nforce ? kPointWork + off(s + 1) - off(s) : 1;
            if (final) work(i) = upd;
            upd += w;
            if (final && i == np - 1) work(np) = upd;
          });
      const BalancedPoints<ContactForcesFn<D, Fric, Cap>> bp{fn, work, np, nt};
      Kokkos::parallel_reduce("fdem::contact::forces [device]", Kokkos::RangePolicy<ExecSpace>(0, nt), bp, pass);
      return;
    }
  }
  // (GPUs: under HeavyLaunchBounds, kernels/fdem_kokkos.hpp; the pass with seeds apart)
  if (seeding && nforce > 0)
    Kokkos::parallel_for("fdem::contact::seeds", Kokkos::RangePolicy<ExecSpace>(0, nforce),
                         PointSeeds<D>{points, surf, m.interfaces(), m.x, scratch.seed, law});
  if (seeding)
    narrow_pass(ContactForcesFn<D, Fric, Cap, 2>{m.x, m.v, xb, sf, points, P, scratch, surf, law, dt, nforce,
                                                 m.interfaces(), seeding},
                np, team_above, pass);
  else
    narrow_pass(ContactForcesFn<D, Fric, Cap, 1>{m.x, m.v, xb, sf, points, P, scratch, surf, law, dt, nforce,
                                                 m.interfaces(), seeding},
                np, team_above, pass);
}

// How the candidates spread over the first n points (ContactSystem::candidate_spread): v = points,
// pairs, then the points above each of the bounds 16, 32, 64 and 128 candidates, and their pairs;
// the largest count.
inline constexpr int kSpreadSumsBounds = 4;
struct SpreadSums {
  long v[2 + 2 * kSpreadSumsBounds] = {};
  int max = 0;
  KOKKOS_INLINE_FUNCTION SpreadSums& operator+=(const SpreadSums& o) {
    for (int k = 0; k < 2 + 2 * kSpreadSumsBounds; ++k) v[k] += o.v[k];
    max = o.max > max ? o.max : max;
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile SpreadSums& o) volatile {
    for (int k = 0; k < 2 + 2 * kSpreadSumsBounds; ++k) v[k] += o.v[k];
    max = o.max > max ? o.max : max;
  }
#endif
};
}  // namespace fdem
namespace Kokkos {
template <>
struct reduction_identity<fdem::SpreadSums> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::SpreadSums sum() { return fdem::SpreadSums(); }
};
}  // namespace Kokkos
namespace fdem {
inline SpreadSums spread_of_candidates(const Kokkos::View<int*>& off, const Kokkos::View<int*>& pts, int n) {
  SpreadSums s;
  Kokkos::parallel_reduce(
      "fdem::contact::candidate_spread", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i, SpreadSums& a) {
        const int c = off(pts(i) + 1) - off(pts(i));
        const int bounds[kSpreadSumsBounds] = {16, 32, 64, 128};
        a.v[0] += 1;
        a.v[1] += c;
        for (int k = 0; k < kSpreadSumsBounds; ++k)
          if (c > bounds[k]) {
            a.v[2 + k] += 1;
            a.v[2 + kSpreadSumsBounds + k] += c;
          }
        a.max = c > a.max ? c : a.max;
      },
      s);
  return s;
}

// Elastic energy of the contact springs (normal and shear) at the last narrow-phase pass.
template <int D>
double contact_energy(const PairList<D>& P, const Kokkos::View<int*>& points, int np, const ContactLaw& law) {
  auto off = P.off;
  auto pfn = P.fn;
  auto pac = P.ac;
  auto pfs = P.fs;
  auto pts = points;
  const double kn = law.kn, ks = law.ks;
  double e = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::energy", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const int i, double& sum) {
        const int s = pts(i);
        for (int j = off(s); j < off(s + 1); ++j) {
          if (!(pfn(j) > 0)) continue;
          double f2 = 0;
          for (int k = 0; k < D; ++k) f2 += pfs(j, k) * pfs(j, k);
          sum += 0.5 * (pfn(j) * pfn(j) / kn + f2 / ks) / pac(j);
        }
      },
      e);
  return e;
}

}  // namespace fdem
