#pragma once
// Candidate lists after a handover without a full rebuild (ContactSystem::check_failures).
//
// The candidate lists are those of a search at the positions of the last build (xb, recorded for
// every node: record_all_positions). When interfaces fail, the pairs that change are those of
// "touched" nodes and faces only:
//  - a touched node is a surface node that is new (a node of a newly active face) or whose cluster
//    changed (PairFilter: the exclusion of its pairs may have changed);
//  - a touched face is an active face that is new or has a vertex whose cluster changed.
// A pair of an untouched node and an untouched face passed or failed the search before and does so
// still (the same positions xb, the same filter). So: touched nodes are searched against every
// active face, untouched nodes keep their pairs with untouched faces and are searched against the
// touched faces only (a grid of those faces), all at xb. The result is the list a full search at
// xb would give, with the history of every pair that stays; the Verlet bound of the build
// (ContactSystem::recheck) holds for it as for the list of the build.
#include "kernels/contact/broad_phase.hpp"
#include "kernels/contact/surfaces.hpp"

namespace fdem {

// xb(i) = x(i) for all n nodes (positions at the build: the local searches after a handover run
// at these positions, also for nodes that are not surface nodes yet).
template <int D>
void record_all_positions(const Kokkos::View<double* [D]>& x, const Kokkos::View<double* [D]>& xb, int n) {
  auto xx = x;
  auto xbuild = xb;
  Kokkos::parallel_for(
      "fdem::contact::record_all", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const int i) {
        for (int k = 0; k < D; ++k) xbuild(i, k) = xx(i, k);
      });
}

// Largest squared displacement since the build of the surface nodes `points` (host value).
template <int D>
double largest_displacement2(const Kokkos::View<double* [D]>& x, const Kokkos::View<double* [D]>& xb,
                             const Kokkos::View<int*>& points, int np) {
  auto xx = x;
  auto xbuild = xb;
  auto pts = points;
  double d2 = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::displacement", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const int i, double& m) {
        const int s = pts(i);
        double d = 0;
        for (int k = 0; k < D; ++k) d += (xx(s, k) - xbuild(s, k)) * (xx(s, k) - xbuild(s, k));
        m = d > m ? d : m;
      },
      Kokkos::Max<double>(d2));
  return d2;
}

// The surfaces before a handover: surface node marks and clusters (copies; which faces were
// active the interfaces' flags still tell during the poll: ContactSurface::active_before_poll).
struct SurfacesBefore {
  Kokkos::View<int*> mark, clus;
};

// Copies the current marks and clusters into `before` (device copies by a kernel).
template <int D>
void save_surfaces(const Kokkos::View<int*>& mark_in, const ContactSurface<D>& surf,
                   const SurfacesBefore& before, int nn) {
  auto mark = mark_in;
  auto clus = surf.clus;
  auto bm = before.mark, bc = before.clus;
  Kokkos::parallel_for(
      "fdem::contact::save_nodes", Kokkos::RangePolicy<ExecSpace>(0, nn), KOKKOS_LAMBDA(const int i) {
        bm(i) = mark(i);
        bc(i) = clus(i);
      });
}

// Touched nodes (tnode, nn) and faces (tface, nf) after a handover (see the file's comment), from
// the surfaces before (`before`, and the faces active before this poll) and now (mark, surf).
template <int D>
void touched(const Kokkos::View<int*>& mark_in, const ContactSurface<D>& surf, const SurfacesBefore& before,
             const Kokkos::View<int*>& tnode_in, const Kokkos::View<int*>& tface_in, int nn, int nf) {
  auto mark = mark_in;
  const ContactSurface<D> S = surf;
  auto bm = before.mark, bc = before.clus;
  auto tnode = tnode_in, tface = tface_in;
  Kokkos::parallel_for(
      "fdem::contact::touched_nodes", Kokkos::RangePolicy<ExecSpace>(0, nn),
      KOKKOS_LAMBDA(const int i) { tnode(i) = mark(i) && (!bm(i) || S.clus(i) != bc(i)) ? 1 : 0; });
  Kokkos::parallel_for(
      "fdem::contact::touched_faces", Kokkos::RangePolicy<ExecSpace>(0, nf), KOKKOS_LAMBDA(const int f) {
        const bool active = S.active(f);
        bool t = active && !S.active_before_poll(f);
        for (int k = 0; k < D && active && !t; ++k) t = S.clus(S.fnode(f, k)) != bc(S.fnode(f, k));
        tface(f) = t ? 1 : 0;
      });
}

// What the local search needs: the search set at the build positions (all active faces), the
// grid of all active faces and the grid of the touched faces (same geometry), the flags.
template <int D>
struct LocalSearch {
  SearchSet<D> S;            // x = xb, points = surface nodes, faces = active faces
  CellGrid<D> all, touched;  // the touched grid shares all.geo and all.ncell
  Kokkos::View<int*> tnode, tface;
  // the box of the touched faces (search_bounds: their centres' box and largest half extent): an
  // untouched point farther than that extent and the search radius from it along some axis passes
  // no touched face's box test, and skips its query of the touched grid (most points of a
  // handover: the touched faces are where the crack opened)
  Kokkos::View<ContactBox<D>> treach;
};

// Whether point p is out of reach of every face of box b: farther than the faces' largest half
// extent and the search radius from their centres' box along some axis (with a margin of a
// hundredth of the radius and 1e-12 of the coordinates, far above the rounding of the box test, so
// that no point that test would take is left out).
template <int D>
KOKKOS_INLINE_FUNCTION bool out_of_reach(const ContactBox<D>& b, const double (&p)[D], double radius) {
  bool out = false;
  for (int k = 0; k < D; ++k) {
    const double m =
        b.ext + 1.01 * radius + 1e-12 * (kmath::fabs(p[k]) + kmath::fabs(b.lo[k]) + kmath::fabs(b.hi[k]));
    out = out || p[k] < b.lo[k] - m || p[k] > b.hi[k] + m;
  }
  return out;
}

// Copies the history of pair `from` (index a in A) to pair b of B, or clears b's (a < 0).
template <int D>
KOKKOS_INLINE_FUNCTION void copy_pair_history(const PairList<D>& A, int a, const PairList<D>& B, int b) {
  B.fn(b) = a >= 0 ? A.fn(a) : 0.0;
  B.ac(b) = a >= 0 ? A.ac(a) : 0.0;
  B.g0(b) = a >= 0 ? A.g0(a) : 0.0;
  for (int k = 0; k < D; ++k) B.fs(b, k) = a >= 0 ? A.fs(a, k) : 0.0;
}

// The pairs of surface node s in the updated list: written to out(base..) when `out` is not empty;
// returns their number. Touched node: every active face; else its old pairs with untouched faces
// and the touched faces near it.
template <int D>
KOKKOS_INLINE_FUNCTION int local_pairs(const LocalSearch<D>& L, const PairFilter<D>& F,
                                       const PairList<D>& old, int s, const Kokkos::View<int*>& out,
                                       int base) {
  double p[D];
  for (int k = 0; k < D; ++k) p[k] = L.S.x(s, k);
  if (L.tnode(s))
    return grid_query<D>(L.all.geo, L.all, L.S.x, L.S.fnode, F, L.S.radius, s, p, out, base, L.S.tol);
  const bool write = out.extent(0) > 0;
  int cnt = 0;
  for (int j = old.off(s); j < old.off(s + 1); ++j) {
    const int f = old.face(j);
    if (L.tface(f)) continue;
    if (write) out(base + cnt) = f;
    ++cnt;
  }
  if (out_of_reach<D>(L.treach(), p, L.S.radius)) return cnt;
  // (the touched grid's cells in the geometry of the grid of all faces)
  return cnt + grid_query<D>(L.all.geo, L.touched, L.S.x, L.S.fnode, F, L.S.radius, s, p, out, base + cnt, L.S.tol);
}

// Counts the pairs of the updated list per surface node into off(node) (others 0) and turns them
// into offsets (off: nn + 1 entries). Returns the number of pairs.
template <int D>
int local_count(const LocalSearch<D>& L, const PairFilter<D>& F, const PairList<D>& old,
                const Kokkos::View<int*>& off, int nn) {
  const LocalSearch<D> Lc = L;
  const PairFilter<D> Fc = F;
  const PairList<D> A = old;
  auto o = off;
  const Kokkos::View<int*> none;
  Kokkos::parallel_for(
      "fdem::contact::local_zero", Kokkos::RangePolicy<ExecSpace>(0, nn + 1),
      KOKKOS_LAMBDA(const int i) { o(i) = 0; });
  Kokkos::parallel_for(
      "fdem::contact::local_count", Kokkos::RangePolicy<ExecSpace>(0, L.S.np), KOKKOS_LAMBDA(const int i) {
        const int s = Lc.S.points(i);
        o(s) = local_pairs<D>(Lc, Fc, A, s, none, 0);
      });
  int total = 0;
  Kokkos::parallel_scan(
      "fdem::contact::local_scan", Kokkos::RangePolicy<ExecSpace>(0, nn + 1),
      KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
        const int v = i < nn ? o(i) : 0;
        if (final) o(i) = upd;
        upd += v;
      },
      total);
  return total;
}

// Fills the updated list B (offsets from local_count): the faces of each surface node, sorted
// (pair_order), with the history of the pairs that were in `old` (both segments are sorted: one
// merge walk per node).
template <int D>
void local_fill(const LocalSearch<D>& L, const PairFilter<D>& F, const PairList<D>& old,
                const PairList<D>& B) {
  const LocalSearch<D> Lc = L;
  const PairFilter<D> Fc = F;
  const PairList<D> A = old, Bc = B;
  Kokkos::parallel_for(
      "fdem::contact::local_fill", Kokkos::RangePolicy<ExecSpace>(0, L.S.np), KOKKOS_LAMBDA(const int i) {
        const int s = Lc.S.points(i);
        const int b = Bc.off(s);
        const int cnt = local_pairs<D>(Lc, Fc, A, s, Bc.face, b);
        for (int a = b + 1; a < b + cnt; ++a) {  // insertion sort (kept pairs are in order already)
          const int val = Bc.face(a);
          int c = a - 1;
          while (c >= b && pair_order(Fc, val, Bc.face(c))) {
            Bc.face(c + 1) = Bc.face(c);
            --c;
          }
          Bc.face(c + 1) = val;
        }
        int o = A.off(s);
        const int oe = A.off(s + 1);
        for (int j = b; j < b + cnt; ++j) {
          const int f = Bc.face(j);
          while (o < oe && pair_order(Fc, A.face(o), f)) ++o;
          copy_pair_history<D>(A, o < oe && A.face(o) == f ? o : -1, Bc, j);
        }
      });
}

}  // namespace fdem
