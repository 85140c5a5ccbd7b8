#pragma once
// Broad phase of contact (docs/theory.md section 6b): candidate (node, face) pairs.
//
// A uniform cell grid of active faces (counting sort: count per cell, exclusive scan,
// permutation with atomic_fetch_add), queried by every surface node over its 3^D neighbour cells;
// the candidates of a node are the faces whose bounding box, grown by the search distance, holds
// the node. Stored as CSR by node id, each node's segment sorted (pair_order). Rebuilt only when
// a node has moved more than half the skin since the last build (ContactSystem::update); the
// contact history of the pairs that stay is carried over (transfer_history). A handover of failed
// interfaces updates the lists by a local search instead (kernels/contact/list_update.hpp).
#include "kernels/contact/geometry.hpp"

namespace fdem {

// The two faces of one interface: node s is a node of the other face of face f's interface
// (faces nb + 2q and nb + 2q + 1 belong to interface q = face_interface(f, nb)).
template <int D>
KOKKOS_INLINE_FUNCTION bool crack_pair(int nb, const FaceNodes<D>& fnode, int s, int f) {
  const int q = face_interface(f, nb);
  if (q < 0) return false;
  int v[D];
  fnode.get(nb + 2 * q + ((f - nb) % 2 == 0 ? 1 : 0), v);
  for (int k = 0; k < D; ++k)
    if (v[k] == s) return true;
  return false;
}

// Bounding box of face centres and the largest half extent of a face's box (a reduction type:
// operator+= merges; works with the volatile join of Kokkos 3.4 and the plain one of 4.x).
template <int D>
struct ContactBox {
  double lo[D], hi[D], ext;
  KOKKOS_INLINE_FUNCTION ContactBox() {
    for (int k = 0; k < D; ++k) {
      lo[k] = 1e300;
      hi[k] = -1e300;
    }
    ext = 0.0;
  }
  KOKKOS_INLINE_FUNCTION ContactBox& operator+=(const ContactBox& o) {
    for (int k = 0; k < D; ++k) {
      lo[k] = o.lo[k] < lo[k] ? o.lo[k] : lo[k];
      hi[k] = o.hi[k] > hi[k] ? o.hi[k] : hi[k];
    }
    ext = o.ext > ext ? o.ext : ext;
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile ContactBox& o) volatile {
    for (int k = 0; k < D; ++k) {
      lo[k] = o.lo[k] < lo[k] ? o.lo[k] : lo[k];
      hi[k] = o.hi[k] > hi[k] ? o.hi[k] : hi[k];
    }
    ext = o.ext > ext ? o.ext : ext;
  }
#endif
};

// What the broad phase searches: `np` query points (node ids in `points`) against `nf` faces
// (face ids in `faces`, nodes in `fnode`), positions x. A pair is a candidate when the point lies
// in the face's bounding box grown by `radius` on every side.
template <int D>
struct SearchSet {
  Kokkos::View<double* [D]> x;
  Kokkos::View<int*> points;
  int np = 0;
  FaceNodes<D> fnode;
  Kokkos::View<int*> faces;
  int nf = 0;
  double radius = 0;
  // >= 0: also the distance test of face_within (tol: the contact's edge fade, ContactLaw::tol);
  // < 0: the box test only
  double tol = -1;
};

// Topological exclusions of (node, face) pairs, applied while the candidate lists are built.
// Always excluded: a node that is a vertex of the face. With `use`: a node of the face's own
// element, and a node that shares a mesh vertex with a vertex of the face while the two copies are
// joined by intact interfaces around that vertex (same vertex group `vgrp`, same cluster `clus`):
// such a node and face are the same material, not two surfaces. Never excluded by that rule: the
// nodes of the opposite face of the face's own (failed) interface: the two faces of a crack are
// always two surfaces, also where the crack ends in intact material (without this, the faces of
// an isolated failed interface could pass through each other unresisted).
template <int D>
struct PairFilter {
  bool use = false;
  Kokkos::View<int* [D + 1]> elem;
  Kokkos::View<int*> fowner, vgrp, clus;
  int nb = 0;  // outer boundary faces (then the faces nb + 2q, nb + 2q + 1 of interface q)
};

template <int D>
KOKKOS_INLINE_FUNCTION bool pair_excluded(const PairFilter<D>& F, const FaceNodes<D>& fnode,
                                          int s, int f) {
  int v[D];
  fnode.get(f, v);
  for (int k = 0; k < D; ++k)
    if (v[k] == s) return true;
  if (!F.use) return false;
  const int e = F.fowner(f);
  for (int a = 0; a < D + 1; ++a)
    if (F.elem(e, a) == s) return true;
  if (crack_pair<D>(F.nb, fnode, s, f)) return false;
  const int gs = F.vgrp(s), cs = F.clus(s);
  for (int k = 0; k < D; ++k)
    if (F.vgrp(v[k]) == gs && F.clus(v[k]) == cs) return true;
  return false;
}

// Uniform cell grid of faces (by the centre of their bounding box). A point within `radius` of a
// face's grown box lies in the face's cell or one of its neighbours because the cell size is at
// least the largest half extent of a face box plus the radius.
template <int D>
struct GridGeo {
  double lo[D];  // corner of cell (0, ..)
  double h;      // cell size
  int n[D];      // cells per axis
};

template <int D>
struct CellGrid {
  GridGeo<D> geo{};
  int ncell = 0;
  Kokkos::View<int*> count;   // per cell (capacity >= ncell); the cursor of the permutation
  Kokkos::View<int*> offset;  // ncell + 1 (capacity)
  Kokkos::View<int*> faces;   // face ids ordered by cell (capacity >= number of faces)
  // the bounding box of each face of `faces` (the same place), centre 0..D-1 and half extent
  // D..2D-1 as face_box gives them at the binning's positions: a query tests the boxes of a cell
  // from this contiguous array instead of reading D random node rows per face
  Kokkos::View<double* [2 * D]> box;
};
// Bounding box of the face centres and the largest face half extent (search_bounds).
template <int D>
struct FaceBounds {
  using value_type = ContactBox<D>;
  SearchSet<D> S;
  KOKKOS_INLINE_FUNCTION void operator()(const int i, ContactBox<D>& b) const {
    double c[D], e[D];
    face_box<D>(S.x, S.fnode, S.faces(i), c, e);
    for (int k = 0; k < D; ++k) {
      b.lo[k] = c[k] < b.lo[k] ? c[k] : b.lo[k];
      b.hi[k] = c[k] > b.hi[k] ? c[k] : b.hi[k];
      b.ext = e[k] > b.ext ? e[k] : b.ext;
    }
  }
};
// The box of S's faces on the host (the host waits for it).
template <int D>
ContactBox<D> search_bounds(const SearchSet<D>& S) {
  ContactBox<D> out;
  Kokkos::parallel_reduce("fdem::contact::bounds", Kokkos::RangePolicy<ExecSpace>(0, S.nf), FaceBounds<D>{S}, out);
  return out;
}
// The same into device memory (no wait). No face: the empty box (lo 1e300, hi -1e300, ext 0).
template <int D>
void search_bounds(const SearchSet<D>& S, const Kokkos::View<ContactBox<D>>& out) {
  Kokkos::parallel_reduce("fdem::contact::bounds [device]", Kokkos::RangePolicy<ExecSpace>(0, S.nf), FaceBounds<D>{S},
                          out);
}

// Host: grid geometry for a box of face centres, with at most `max_cells` cells (the cell size
// grows when the box is large compared with the faces, e.g. a fragment far away). One padding
// cell on every side, so that no centre lies on the upper bound.
template <int D>
void grid_geometry(CellGrid<D>& g, const ContactBox<D>& b, double radius, long max_cells) {
  double h = b.ext + radius;
  if (!(h > 0)) h = 1.0;
  for (;;) {
    long total = 1;
    bool fits = true;
    for (int k = 0; k < D; ++k) {
      const double span = b.hi[k] - b.lo[k];
      const double nk = span / h + 3.0;
      if (!(nk < 1e9)) {
        fits = false;
        break;
      }
      g.geo.n[k] = static_cast<int>(nk);
      total *= g.geo.n[k];
      if (total > max_cells) fits = false;
    }
    if (fits) {
      g.ncell = static_cast<int>(total);
      break;
    }
    h *= 1.5;
  }
  g.geo.h = h;
  for (int k = 0; k < D; ++k) g.geo.lo[k] = b.lo[k] - h;
}

// Cell coordinates of point p (-2 and n+1 stand for "further than one cell outside"), and its
// linear cell id (clamped into the grid).
template <int D>
KOKKOS_INLINE_FUNCTION int grid_cell(const GridGeo<D>& g, const double (&p)[D], int (&ijk)[D]) {
  int id = 0;
  for (int k = D - 1; k >= 0; --k) {
    const double r = (p[k] - g.lo[k]) / g.h;
    int c;
    if (!(r >= -1.0)) c = -2;
    else if (r > static_cast<double>(g.n[k]) + 1.0) c = g.n[k] + 1;
    else c = static_cast<int>(kmath::floor(r));
    ijk[k] = c;
    id = id * g.n[k] + kclamp(c, 0, g.n[k] - 1);
  }
  return id;
}

// Counting sort of the faces into the grid's cells: count, exclusive scan, permutation.
template <int D>
void grid_bin(const CellGrid<D>& g, const SearchSet<D>& S) {
  auto count = g.count;
  auto offset = g.offset;
  auto cfaces = g.faces;
  auto cbox = g.box;
  auto x = S.x;
  auto fnode = S.fnode;
  auto faces = S.faces;
  const int ncell = g.ncell;
  const GridGeo<D> geo = g.geo;
  Kokkos::parallel_for(
      "fdem::contact::grid_zero", Kokkos::RangePolicy<ExecSpace>(0, ncell),
      KOKKOS_LAMBDA(const int c) { count(c) = 0; });
  Kokkos::parallel_for(
      "fdem::contact::grid_count", Kokkos::RangePolicy<ExecSpace>(0, S.nf), KOKKOS_LAMBDA(const int i) {
        double c[D], e[D];
        int ijk[D];
        face_box<D>(x, fnode, faces(i), c, e);
        Kokkos::atomic_add(&count(grid_cell<D>(geo, c, ijk)), 1);
      });
  Kokkos::parallel_scan(
      "fdem::contact::grid_scan [device]", Kokkos::RangePolicy<ExecSpace>(0, ncell + 1),
      KOKKOS_LAMBDA(const int c, int& upd, const bool final) {
        const int v = c < ncell ? count(c) : 0;
        if (final) offset(c) = upd;
        upd += v;
      });
  Kokkos::parallel_for(
      "fdem::contact::grid_zero2", Kokkos::RangePolicy<ExecSpace>(0, ncell),
      KOKKOS_LAMBDA(const int c) { count(c) = 0; });
  Kokkos::parallel_for(
      "fdem::contact::grid_permute", Kokkos::RangePolicy<ExecSpace>(0, S.nf), KOKKOS_LAMBDA(const int i) {
        double c[D], e[D];
        int ijk[D];
        const int f = faces(i);
        face_box<D>(x, fnode, f, c, e);
        const int id = grid_cell<D>(geo, c, ijk);
        const int pos = offset(id) + Kokkos::atomic_fetch_add(&count(id), 1);
        cfaces(pos) = f;
        for (int k = 0; k < D; ++k) {
          cbox(pos, k) = c[k];
          cbox(pos, D + k) = e[k];
        }
      });
}

// Candidate pairs as CSR by node id: the candidates of node i are face(off(i)) .. face(off(i+1)-1),
// sorted by face id. Per pair the contact history: normal force fn (> 0: in contact at the last
// step), contact area ac, shear force fs (global components) and the penetration allowance g0
// (<= 0, see contact_pair).
template <int D>
struct PairList {
  Kokkos::View<int*> off;  // nn + 1
  Kokkos::View<int*> face;
  Kokkos::View<double*> fn, ac, g0;
  Kokkos::View<double* [D]> fs;
  int size = 0, capacity = 0;
};

// The faces of the cells around point p (node s) that pass the box test and the filter: counted,
// and written to out(base + i) when `out` is not empty. Returns the count.
// The cells' faces and boxes come in their CellGrid (the geometry g apart: the touched grid shares
// the grid of all faces'), not as Views: CUDA 13.0's cicc crashed (segmentation fault) on this
// device function with a View<double* [2 * D]> parameter, as on element_depth's plane View.
template <int D>
KOKKOS_INLINE_FUNCTION int grid_query(const GridGeo<D>& g, const CellGrid<D>& cells,
                                      const Kokkos::View<double* [D]>& x,
                                      const FaceNodes<D>& fnode, const PairFilter<D>& F,
                                      double radius, int s, const double (&p)[D],
                                      const Kokkos::View<int*>& out, int base, double tol = -1) {
  int ijk[D];
  grid_cell<D>(g, p, ijk);
  int lo[D], span[D], ncells = 1;
  for (int k = 0; k < D; ++k) {
    lo[k] = ijk[k] - 1 < 0 ? 0 : ijk[k] - 1;
    const int hi = ijk[k] + 1 > g.n[k] - 1 ? g.n[k] - 1 : ijk[k] + 1;
    span[k] = hi - lo[k] + 1;
    if (span[k] <= 0) return 0;  // more than one cell outside the grid
    ncells *= span[k];
  }
  const bool write = out.extent(0) > 0;
  int cnt = 0;
  for (int t = 0; t < ncells; ++t) {
    int id = 0, r = t, c[D];
    for (int k = 0; k < D; ++k) {
      c[k] = lo[k] + r % span[k];
      r /= span[k];
    }
    for (int k = D - 1; k >= 0; --k) id = id * g.n[k] + c[k];
    for (int q = cells.offset(id); q < cells.offset(id + 1); ++q) {
      bool near = true;
      for (int k = 0; k < D; ++k) {
        const double d = p[k] - cells.box(q, k);
        near = near && (d < 0 ? -d : d) <= cells.box(q, D + k) + radius;
      }
      if (!near) continue;
      const int f = cells.faces(q);
      if (pair_excluded<D>(F, fnode, s, f)) continue;
      if (tol >= 0.0 && !face_within<D>(x, fnode, f, p, radius, tol)) continue;
      if (write) out(base + cnt) = f;
      ++cnt;
    }
  }
  return cnt;
}

// Counts the candidates of every query point into off(node) (all other nodes 0), then turns the
// counts into offsets by an exclusive scan (off has nn + 1 entries). Returns the number of pairs.
template <int D>
int candidates_count(const CellGrid<D>& g, const SearchSet<D>& S, const PairFilter<D>& F,
                     const Kokkos::View<int*>& off, int nn) {
  const CellGrid<D> grid = g;
  const SearchSet<D> set = S;
  const PairFilter<D> Fc = F;
  auto o = off;
  const Kokkos::View<int*> none;
  Kokkos::parallel_for(
      "fdem::contact::pairs_zero", Kokkos::RangePolicy<ExecSpace>(0, nn + 1),
      KOKKOS_LAMBDA(const int i) { o(i) = 0; });
  Kokkos::parallel_for(
      "fdem::contact::pairs_count", Kokkos::RangePolicy<ExecSpace>(0, S.np), KOKKOS_LAMBDA(const int i) {
        const int s = set.points(i);
        double p[D];
        for (int k = 0; k < D; ++k) p[k] = set.x(s, k);
        o(s) = grid_query<D>(grid.geo, grid, set.x, set.fnode, Fc, set.radius, s, p, none, 0, set.tol);
      });
  int total = 0;
  Kokkos::parallel_scan(
      "fdem::contact::pairs_scan", Kokkos::RangePolicy<ExecSpace>(0, nn + 1),
      KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
        const int v = i < nn ? o(i) : 0;
        if (final) o(i) = upd;
        upd += v;
      },
      total);
  return total;
}

// Order of a node's candidates: by owner element (with the topological filter: the faces of one
// element are then adjacent, see contact_forces), then by face id.
template <int D>
KOKKOS_INLINE_FUNCTION bool pair_order(const PairFilter<D>& F, int fa, int fb) {
  if (F.use) {
    const int ea = F.fowner(fa), eb = F.fowner(fb);
    if (ea != eb) return ea < eb;
  }
  return fa < fb;
}

// Fills the candidate faces (offsets from candidates_count) and sorts each node's segment
// (pair_order).
template <int D>
void candidates_fill(const CellGrid<D>& g, const SearchSet<D>& S, const PairFilter<D>& F,
                     const Kokkos::View<int*>& off, const Kokkos::View<int*>& face) {
  const CellGrid<D> grid = g;
  const SearchSet<D> set = S;
  const PairFilter<D> Fc = F;
  auto o = off;
  auto pf = face;
  Kokkos::parallel_for(
      "fdem::contact::pairs_fill", Kokkos::RangePolicy<ExecSpace>(0, S.np), KOKKOS_LAMBDA(const int i) {
        const int s = set.points(i);
        double p[D];
        for (int k = 0; k < D; ++k) p[k] = set.x(s, k);
        const int b = o(s);
        const int cnt = grid_query<D>(grid.geo, grid, set.x, set.fnode, Fc, set.radius, s, p, pf, b, set.tol);
        for (int a = b + 1; a < b + cnt; ++a) {  // insertion sort: segments are short
          const int val = pf(a);
          int c = a - 1;
          while (c >= b && pair_order(Fc, val, pf(c))) {
            pf(c + 1) = pf(c);
            --c;
          }
          pf(c + 1) = val;
        }
      });
}

// Carries the contact history of every pair of `from` that is also in `to` (same node, same
// face) over to `to`; new pairs start without history.
template <int D>
void transfer_history(const PairList<D>& from, const PairList<D>& to, const Kokkos::View<int*>& points, int np,
                      const PairFilter<D>& F) {
  const PairFilter<D> Fc = F;
  const PairList<D> a = from, b = to;  // old and new lists
  auto pts = points;
  Kokkos::parallel_for(
      "fdem::contact::transfer", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const int i) {
        const int s = pts(i);
        const int b0 = a.off(s), e0 = a.off(s + 1);
        for (int j = b.off(s); j < b.off(s + 1); ++j) {
          const int f = b.face(j);
          int lo = b0, hi = e0;  // binary search in the old (sorted) segment
          while (lo < hi) {
            const int mid = (lo + hi) / 2;
            if (pair_order(Fc, a.face(mid), f)) lo = mid + 1;
            else hi = mid;
          }
          if (lo < e0 && a.face(lo) == f) {
            b.fn(j) = a.fn(lo);
            b.ac(j) = a.ac(lo);
            b.g0(j) = a.g0(lo);
            for (int k = 0; k < D; ++k) b.fs(j, k) = a.fs(lo, k);
          } else {
            b.fn(j) = 0.0;
            b.ac(j) = 0.0;
            b.g0(j) = 0.0;
            for (int k = 0; k < D; ++k) b.fs(j, k) = 0.0;
          }
        }
      });
}

}  // namespace fdem

namespace Kokkos {
template <int D>
struct reduction_identity<fdem::ContactBox<D>> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::ContactBox<D> sum() { return fdem::ContactBox<D>(); }
};
}  // namespace Kokkos
