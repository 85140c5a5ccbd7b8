#pragma once
// Contact between deformable bodies (METHOD.md section 6): device data and kernels.
//
// Surfaces are faces (2D: edges, 3D: triangles) with their outward normal: the outer boundary of
// every body, and both faces of every failed interface. Every node of an active face is a
// "surface node" and is checked against the active faces near it (node-to-face, applied to both
// surfaces of a touching pair: symmetric two-pass, each node with half its contact area).
//
// Broad phase: a uniform cell grid of active faces (counting sort: count per cell, exclusive scan,
// permutation with atomic_fetch_add), queried by every surface node over its 3^D neighbour cells;
// the candidates of a node are the faces whose bounding box, grown by the search distance, holds
// the node. Stored as CSR by node id, each node's segment sorted by face id. Rebuilt only when a
// node has moved more than half the skin since the last build (see src/solver/contact_system.cpp).
//
// Narrow phase (every step, one thread per surface node over its candidates): gap, normal and
// contact point of the node against each candidate face; normal and shear penalty springs
// (K_n A_c, K_s A_c), no tension, incremental shear force with Coulomb friction and cohesion; the
// shear force of each (node, face) pair is kept between steps and across rebuilds. Forces are
// added to m.f with atomics (contacts are sparse).
//
// Free functions copy the Views they need into locals before each KOKKOS_LAMBDA (CUDA-safe); no
// std containers, exceptions or virtual calls in kernels; (i, k) indexing only.
#include "kernels/model.hpp"

namespace fdem {

// ---------------------------------------------------------------------------------------------
// Geometry of one face

// Unit outward normal of a face (nodes in the boundary-face order of mesh.hpp: 2D n = (t_y, -t_x)
// with t = x1 - x0; 3D n = (x1 - x0) x (x2 - x0)), and its measure (length or area).
template <int D>
KOKKOS_INLINE_FUNCTION double face_normal(const double (&xf)[D][D], double (&n)[D]) {
  if constexpr (D == 2) {
    const double tx = xf[1][0] - xf[0][0], ty = xf[1][1] - xf[0][1];
    const double L = kmath::sqrt(tx * tx + ty * ty);
    const double il = L > 0 ? 1.0 / L : 0.0;
    n[0] = ty * il;
    n[1] = -tx * il;
    return L;
  } else {
    const double a[3] = {xf[1][0] - xf[0][0], xf[1][1] - xf[0][1], xf[1][2] - xf[0][2]};
    const double b[3] = {xf[2][0] - xf[0][0], xf[2][1] - xf[0][1], xf[2][2] - xf[0][2]};
    const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double len = kmath::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    const double il = len > 0 ? 1.0 / len : 0.0;
    for (int k = 0; k < 3; ++k) n[k] = c[k] * il;
    return 0.5 * len;
  }
}

// Signed distance g of point p from the plane of a face along its outward normal n (g < 0: p is
// behind the face, i.e. inside its element's side) and the barycentric coordinates N of p's
// orthogonal projection on that plane (all in [0, 1]: the projection lies on the face). For a flat
// face, dg/dp = n and dg/dx_k = -N_k n exactly, so the penalty force -K A g n on p and
// +K A g N_k n on the face nodes is the gradient of 0.5 K A g^2.
template <int D>
KOKKOS_INLINE_FUNCTION double face_project(const double (&xf)[D][D], const double (&p)[D],
                                           double (&n)[D], double (&N)[D]) {
  face_normal<D>(xf, n);
  double w[D], g = 0;
  for (int k = 0; k < D; ++k) {
    w[k] = p[k] - xf[0][k];
    g += w[k] * n[k];
  }
  if constexpr (D == 2) {
    const double tx = xf[1][0] - xf[0][0], ty = xf[1][1] - xf[0][1];
    const double L2 = tx * tx + ty * ty;
    const double xi = L2 > 0 ? (w[0] * tx + w[1] * ty) / L2 : 0.0;
    N[0] = 1.0 - xi;
    N[1] = xi;
  } else {
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = xf[1][k] - xf[0][k];
      e2[k] = xf[2][k] - xf[0][k];
    }
    const double d00 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    const double d01 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    const double d11 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    const double d20 = w[0] * e1[0] + w[1] * e1[1] + w[2] * e1[2];
    const double d21 = w[0] * e2[0] + w[1] * e2[1] + w[2] * e2[2];
    const double den = d00 * d11 - d01 * d01;
    const double id = den > 0 ? 1.0 / den : 0.0;
    N[1] = (d11 * d20 - d01 * d21) * id;
    N[2] = (d00 * d21 - d01 * d20) * id;
    N[0] = 1.0 - N[1] - N[2];
  }
  return g;
}

// The geometry of a face that face_project needs, computed once per step for every active face
// (face_geometry) instead of once per candidate pair (a node has tens of candidates in a
// fragmented 3D mesh): 2D x0, n, t = x1 - x0, 1 / |t|^2; 3D x0, n,
// e1 = x1 - x0, e2 = x2 - x0, d00, d01, d11 (their dot products) and 1 / (d00 d11 - d01^2).
template <int D>
struct FaceGeo {
  static constexpr int size = D == 2 ? 7 : 16;
};

template <int D, class G>
KOKKOS_INLINE_FUNCTION void face_geometry_of(const double (&xf)[D][D], const G& geo, int f) {
  double n[D];
  face_normal<D>(xf, n);
  for (int k = 0; k < D; ++k) {
    geo(f, k) = xf[0][k];
    geo(f, D + k) = n[k];
  }
  if constexpr (D == 2) {
    const double tx = xf[1][0] - xf[0][0], ty = xf[1][1] - xf[0][1];
    const double L2 = tx * tx + ty * ty;
    geo(f, 4) = tx;
    geo(f, 5) = ty;
    geo(f, 6) = L2 > 0 ? 1.0 / L2 : 0.0;
  } else {
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = xf[1][k] - xf[0][k];
      e2[k] = xf[2][k] - xf[0][k];
      geo(f, 6 + k) = e1[k];
      geo(f, 9 + k) = e2[k];
    }
    const double d00 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    const double d01 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    const double d11 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    const double den = d00 * d11 - d01 * d01;
    geo(f, 12) = d00;
    geo(f, 13) = d01;
    geo(f, 14) = d11;
    geo(f, 15) = den > 0 ? 1.0 / den : 0.0;
  }
}

// face_project from the stored geometry of face f (same arithmetic).
template <int D, class G>
KOKKOS_INLINE_FUNCTION double face_project_geo(const G& geo, int f, const double (&p)[D], double (&n)[D],
                                               double (&N)[D]) {
  double w[D], g = 0;
  for (int k = 0; k < D; ++k) {
    n[k] = geo(f, D + k);
    w[k] = p[k] - geo(f, k);
    g += w[k] * n[k];
  }
  if constexpr (D == 2) {
    const double xi = (w[0] * geo(f, 4) + w[1] * geo(f, 5)) * geo(f, 6);
    N[0] = 1.0 - xi;
    N[1] = xi;
  } else {
    double d20 = 0, d21 = 0;
    for (int k = 0; k < 3; ++k) {
      d20 += w[k] * geo(f, 6 + k);
      d21 += w[k] * geo(f, 9 + k);
    }
    const double d00 = geo(f, 12), d01 = geo(f, 13), d11 = geo(f, 14), id = geo(f, 15);
    N[1] = (d11 * d20 - d01 * d21) * id;
    N[2] = (d00 * d21 - d01 * d20) * id;
    N[0] = 1.0 - N[1] - N[2];
  }
  return g;
}

// The two faces of one interface: node s is a node of the other face of face f's interface
// (faces nb + 2q and nb + 2q + 1 belong to interface q = fiface(f); -1: outer boundary).
template <int D>
KOKKOS_INLINE_FUNCTION bool crack_pair(const Kokkos::View<int*>& fiface, int nb, const Kokkos::View<int* [D]>& fnode,
                                       int s, int f) {
  const int q = fiface(f);
  if (q < 0) return false;
  const int other = nb + 2 * q + ((f - nb) % 2 == 0 ? 1 : 0);
  for (int k = 0; k < D; ++k)
    if (fnode(other, k) == s) return true;
  return false;
}

// ---------------------------------------------------------------------------------------------
// Broad phase: bounding box reduction, cell grid, candidate lists

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
  Kokkos::View<int* [D]> fnode;
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
  Kokkos::View<int*> fiface;  // interface of each face (-1: outer boundary); faces nb + 2q, nb + 2q + 1
  int nb = 0;
};

template <int D>
KOKKOS_INLINE_FUNCTION bool pair_excluded(const PairFilter<D>& F, const Kokkos::View<int* [D]>& fnode,
                                          int s, int f) {
  for (int k = 0; k < D; ++k)
    if (fnode(f, k) == s) return true;
  if (!F.use) return false;
  const int e = F.fowner(f);
  for (int a = 0; a < D + 1; ++a)
    if (F.elem(e, a) == s) return true;
  if (crack_pair<D>(F.fiface, F.nb, fnode, s, f)) return false;
  const int gs = F.vgrp(s), cs = F.clus(s);
  for (int k = 0; k < D; ++k) {
    const int v = fnode(f, k);
    if (F.vgrp(v) == gs && F.clus(v) == cs) return true;
  }
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
};

template <int D>
KOKKOS_INLINE_FUNCTION void face_box(const Kokkos::View<double* [D]>& x, const Kokkos::View<int* [D]>& fnode,
                                     int f, double (&c)[D], double (&e)[D]) {
  double lo[D], hi[D];
  for (int k = 0; k < D; ++k) lo[k] = hi[k] = x(fnode(f, 0), k);
  for (int a = 1; a < D; ++a)
    for (int k = 0; k < D; ++k) {
      const double y = x(fnode(f, a), k);
      lo[k] = y < lo[k] ? y : lo[k];
      hi[k] = y > hi[k] ? y : hi[k];
    }
  for (int k = 0; k < D; ++k) {
    c[k] = 0.5 * (lo[k] + hi[k]);
    e[k] = 0.5 * (hi[k] - lo[k]);
  }
}

// Whether point p is within radius + 2 tol (L + radius) of face f (the triangle or segment, not
// its plane; L: its longest edge). A node that comes into contact with the face before the
// candidate lists are rebuilt (each surface node moves less than half the skin, radius = dpen +
// skin) is within that distance now: in contact it is within dpen of the face's plane with its
// barycentric coordinates above -tol (contact_fade), i.e. within dpen + 2 tol L' of the face, and
// the distance changes by at most the skin while the nodes move. Degenerate faces pass.
template <int D>
KOKKOS_INLINE_FUNCTION bool face_within(const Kokkos::View<double* [D]>& x, const Kokkos::View<int* [D]>& fnode,
                                        int f, const double (&p)[D], double radius, double tol) {
  double a[D], ab[D], ap[D], L2 = 0, d2 = 0;
  for (int k = 0; k < D; ++k) {
    a[k] = x(fnode(f, 0), k);
    ab[k] = x(fnode(f, 1), k) - a[k];
    ap[k] = p[k] - a[k];
    L2 += ab[k] * ab[k];
  }
  if constexpr (D == 2) {
    double t = (ap[0] * ab[0] + ap[1] * ab[1]) / L2;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    for (int k = 0; k < D; ++k) d2 += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
  } else {
    // closest point of a triangle (Ericson, Real-Time Collision Detection, 5.1.5)
    double ac[D], bc2 = 0, ac2 = 0;
    for (int k = 0; k < D; ++k) {
      ac[k] = x(fnode(f, 2), k) - a[k];
      ac2 += ac[k] * ac[k];
      const double bc = ac[k] - ab[k];
      bc2 += bc * bc;
    }
    L2 = L2 > ac2 ? L2 : ac2;
    L2 = L2 > bc2 ? L2 : bc2;
    auto dot = [](const double (&u)[D], const double (&v)[D]) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
    double bp[D], cp[D];
    for (int k = 0; k < D; ++k) {
      bp[k] = ap[k] - ab[k];
      cp[k] = ap[k] - ac[k];
    }
    const double d1 = dot(ab, ap), d2a = dot(ac, ap), d3 = dot(ab, bp), d4 = dot(ac, bp), d5 = dot(ab, cp),
                 d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2a, vb = d5 * d2a - d1 * d6, va = d3 * d6 - d5 * d4;
    double u = 0, v = 0;  // closest point a + u ab + v ac
    if (d1 <= 0.0 && d2a <= 0.0) {
    } else if (d3 >= 0.0 && d4 <= d3) {
      u = 1.0;
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
      u = d1 / (d1 - d3);
    } else if (d6 >= 0.0 && d5 <= d6) {
      v = 1.0;
    } else if (vb <= 0.0 && d2a >= 0.0 && d6 <= 0.0) {
      v = d2a / (d2a - d6);
    } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      u = 1.0 - w;
      v = w;
    } else {
      const double den = 1.0 / (va + vb + vc);
      u = vb * den;
      v = vc * den;
    }
    for (int k = 0; k < D; ++k) d2 += (ap[k] - u * ab[k] - v * ac[k]) * (ap[k] - u * ab[k] - v * ac[k]);
  }
  const double r = radius + 2.0 * tol * (kmath::sqrt(L2) + radius);
  return !(d2 > r * r);  // NaN (a degenerate face): in
}

// Bounding box of the face centres and the largest face half extent.
template <int D>
ContactBox<D> search_bounds(const SearchSet<D>& S) {
  auto x = S.x;
  auto fnode = S.fnode;
  auto faces = S.faces;
  ContactBox<D> out;
  Kokkos::parallel_reduce(
      "fdem::contact::bounds", Kokkos::RangePolicy<ExecSpace>(0, S.nf),
      KOKKOS_LAMBDA(const int i, ContactBox<D>& b) {
        double c[D], e[D];
        face_box<D>(x, fnode, faces(i), c, e);
        for (int k = 0; k < D; ++k) {
          b.lo[k] = c[k] < b.lo[k] ? c[k] : b.lo[k];
          b.hi[k] = c[k] > b.hi[k] ? c[k] : b.hi[k];
          b.ext = e[k] > b.ext ? e[k] : b.ext;
        }
      },
      out);
  return out;
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
      "fdem::contact::grid_scan", Kokkos::RangePolicy<ExecSpace>(0, ncell + 1),
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
        const int pos = Kokkos::atomic_fetch_add(&count(id), 1);
        cfaces(offset(id) + pos) = f;
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
template <int D>
KOKKOS_INLINE_FUNCTION int grid_query(const GridGeo<D>& g, const Kokkos::View<int*>& offset,
                                      const Kokkos::View<int*>& cfaces, const Kokkos::View<double* [D]>& x,
                                      const Kokkos::View<int* [D]>& fnode, const PairFilter<D>& F,
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
    for (int q = offset(id); q < offset(id + 1); ++q) {
      const int f = cfaces(q);
      double fc[D], fe[D];
      face_box<D>(x, fnode, f, fc, fe);
      bool near = true;
      for (int k = 0; k < D; ++k) {
        const double d = p[k] - fc[k];
        near = near && (d < 0 ? -d : d) <= fe[k] + radius;
      }
      if (!near || pair_excluded<D>(F, fnode, s, f)) continue;
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
  const GridGeo<D> geo = g.geo;
  auto offset = g.offset;
  auto cfaces = g.faces;
  auto x = S.x;
  auto fnode = S.fnode;
  auto points = S.points;
  const double radius = S.radius, tol = S.tol;
  const PairFilter<D> Fc = F;
  auto o = off;
  const Kokkos::View<int*> none;
  Kokkos::parallel_for(
      "fdem::contact::pairs_zero", Kokkos::RangePolicy<ExecSpace>(0, nn + 1),
      KOKKOS_LAMBDA(const int i) { o(i) = 0; });
  Kokkos::parallel_for(
      "fdem::contact::pairs_count", Kokkos::RangePolicy<ExecSpace>(0, S.np), KOKKOS_LAMBDA(const int i) {
        const int s = points(i);
        double p[D];
        for (int k = 0; k < D; ++k) p[k] = x(s, k);
        o(s) = grid_query<D>(geo, offset, cfaces, x, fnode, Fc, radius, s, p, none, 0, tol);
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
  const GridGeo<D> geo = g.geo;
  auto offset = g.offset;
  auto cfaces = g.faces;
  auto x = S.x;
  auto fnode = S.fnode;
  auto points = S.points;
  const double radius = S.radius, tol = S.tol;
  const PairFilter<D> Fc = F;
  auto o = off;
  auto pf = face;
  Kokkos::parallel_for(
      "fdem::contact::pairs_fill", Kokkos::RangePolicy<ExecSpace>(0, S.np), KOKKOS_LAMBDA(const int i) {
        const int s = points(i);
        double p[D];
        for (int k = 0; k < D; ++k) p[k] = x(s, k);
        const int b = o(s);
        const int cnt = grid_query<D>(geo, offset, cfaces, x, fnode, Fc, radius, s, p, pf, b, tol);
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
  auto fo = from.off;
  auto ff = from.face;
  auto ffn = from.fn;
  auto fac = from.ac;
  auto fg0 = from.g0;
  auto ffs = from.fs;
  auto to_off = to.off;
  auto tf = to.face;
  auto tfn = to.fn;
  auto tac = to.ac;
  auto tg0 = to.g0;
  auto tfs = to.fs;
  auto pts = points;
  Kokkos::parallel_for(
      "fdem::contact::transfer", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const int i) {
        const int s = pts(i);
        const int b0 = fo(s), e0 = fo(s + 1);
        for (int j = to_off(s); j < to_off(s + 1); ++j) {
          const int f = tf(j);
          int lo = b0, hi = e0;  // binary search in the old (sorted) segment
          while (lo < hi) {
            const int mid = (lo + hi) / 2;
            if (pair_order(Fc, ff(mid), f)) lo = mid + 1;
            else hi = mid;
          }
          if (lo < e0 && ff(lo) == f) {
            tfn(j) = ffn(lo);
            tac(j) = fac(lo);
            tg0(j) = fg0(lo);
            for (int k = 0; k < D; ++k) tfs(j, k) = ffs(lo, k);
          } else {
            tfn(j) = 0.0;
            tac(j) = 0.0;
            tg0(j) = 0.0;
            for (int k = 0; k < D; ++k) tfs(j, k) = 0.0;
          }
        }
      });
}

// ---------------------------------------------------------------------------------------------
// Narrow phase

// Penalty and friction parameters of the contact law, and the geometric tolerances.
struct ContactLaw {
  double kn, ks;     // Pa/m, times the contact area
  double mu, coh;    // friction coefficient, cohesion (Pa)
  double dpen;       // deepest penetration recognised (m); deeper nodes are not in contact
  double tol;        // a contact fades out as its projection leaves the face by this much (barycentric)
  double cos_same;   // coplanar test: faces of one piece with normals closer than this share a contact
};

// Surface data the narrow phase needs: face nodes and each node's share of the reference face
// measure (thickness included), which faces are active, the faces around each node (CSR), each
// node's contact area (half its share of its active faces: both sides of a contact carry half),
// the interface of each face (-1: outer boundary; faces nb + 2q and nb + 2q + 1 are the two
// faces of interface q) and the vertex groups/clusters (see PairFilter).
template <int D>
struct ContactSurface {
  Kokkos::View<int* [D + 1]> elem;  // the model's elements
  Kokkos::View<int*> fowner;         // element of each face
  Kokkos::View<int*> efree;          // 1: every face of the element is active (a free piece)
  // planes of the faces of free elements at the current positions (element_planes): for the
  // face opposite vertex a, the outward unit normal (0..D-1) and its offset n . x (D)
  Kokkos::View<double* [D + 1][D + 1]> eplane;
  Kokkos::View<int* [D]> fnode;
  Kokkos::View<double*> fshare;  // measure / D
  Kokkos::View<int*> factive;
  Kokkos::View<int*> nfoff, nface;
  Kokkos::View<double*> narea;
  Kokkos::View<int*> fiface;
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
        for (int a = 0; a < D; ++a)
          for (int k = 0; k < D; ++k) xf[a][k] = xx(fnode(f, a), k);
        face_geometry_of<D>(xf, geo, i);
      });
}

// Scratch of the narrow phase, one entry per candidate pair (sized like the pair list).
template <int D>
struct PairScratch {
  Kokkos::View<double*> g, phi, depth, w, rel;
  Kokkos::View<double* [D]> n;
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
KOKKOS_INLINE_FUNCTION ElementDepth element_depth(const ContactSurface<D>& S, int e, const double (&p)[D]) {
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

// Fade of a node against a face of a piece that is not a single free element, with least
// barycentric coordinate `score` of the projection: full on the face, fading out smoothly (C1)
// over tol beyond its edge, so that faces meeting at an edge or vertex share a node (their
// weights are then normalised, see contact_forces).
KOKKOS_INLINE_FUNCTION double contact_fade(double s, double tol) {
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
KOKKOS_INLINE_FUNCTION double facing_fade(double facing) {
  if (facing >= 0.5) return 1.0;
  if (facing <= 0.2) return 0.0;
  const double t = (facing - 0.2) / 0.3;
  return t * t * (3.0 - 2.0 * t);
}

template <int D>
KOKKOS_INLINE_FUNCTION double node_facing(const ContactSurface<D>& S, int s, const double (&n)[D]) {
  double best = -1.0;
  for (int q = S.nfoff(s); q < S.nfoff(s + 1); ++q) {
    const int f2 = S.nface(q);
    if (!S.factive(f2)) continue;
    double cw = 0;
    for (int k = 0; k < D; ++k) cw -= S.fgeo(S.fslot(f2), D + k) * n[k];
    best = cw > best ? cw : best;
  }
  return best;
}

// Two faces of one piece: they share a vertex whose copies are joined by intact material (same
// node, or copies in one cluster).
template <int D>
KOKKOS_INLINE_FUNCTION bool same_piece(const ContactSurface<D>& S, int fa, int fb) {
  for (int i = 0; i < D; ++i) {
    const int va = S.fnode(fa, i);
    for (int k = 0; k < D; ++k) {
      const int vb = S.fnode(fb, k);
      if (S.vgrp(va) == S.vgrp(vb) && S.clus(va) == S.clus(vb)) return true;
    }
  }
  return false;
}

// The largest contact energy of node s at the last step with a face related to face fc (of the
// same piece, see same_piece), as depth(j) = depth * sqrt(effective area) = sqrt(2 U / K_n) (-1:
// not in contact): a contact with fc of effective area A can take over the depth
// related_depth / sqrt(A), the one at which it stores that energy (see contact_pair). 0 when there
// is none.
template <int D>
KOKKOS_INLINE_FUNCTION double related_depth(const ContactSurface<D>& S, const Kokkos::View<int*>& pface,
                                            const Kokkos::View<double*>& depth, int b, int e, int fc) {
  double d = 0.0;
  for (int jj = b; jj < e; ++jj)
    if (depth(jj) > d && same_piece<D>(S, fc, pface(jj))) d = depth(jj);
  return d;
}

// Results of one narrow-phase pass (a reduction type): energy dissipated by the slip of the shear
// springs and released when a contact opens, number of active contacts (sums); largest squared
// displacement of a surface node since the last build and largest squared speed (maxima), for the
// rebuild test of the next step.
struct ContactSums {
  double dissipated, active, d2max, v2max;
  KOKKOS_INLINE_FUNCTION ContactSums() : dissipated(0), active(0), d2max(0), v2max(0) {}
  KOKKOS_INLINE_FUNCTION ContactSums& operator+=(const ContactSums& o) {
    dissipated += o.dissipated;
    active += o.active;
    d2max = o.d2max > d2max ? o.d2max : d2max;
    v2max = o.v2max > v2max ? o.v2max : v2max;
    return *this;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile ContactSums& o) volatile {
    dissipated += o.dissipated;
    active += o.active;
    d2max = o.d2max > d2max ? o.d2max : d2max;
    v2max = o.v2max > v2max ? o.v2max : v2max;
  }
#endif
};

// One (node, face) pair with effective contact area A (0: not in contact): normal penalty (no
// tension), incremental shear spring with Coulomb friction and cohesion; forces added with
// atomics to the node and, through the contact point's barycentric weights, to the face's nodes;
// history updated.
//
// No energy from nowhere. A node's contacts begin, end and change weight as it moves over faces
// and the surfaces change, which a penalty force that is not the gradient of its stored energy
// turns into energy gained or lost. Three rules keep a contact from gaining energy without work:
// - Penetration allowance g0 (<= 0): the gap is measured from it, g - g0. A contact that starts
//   can have entered the face only by the node's approach over the last step (twice its relative
//   displacement) beyond the depth `limit` at which it stores the energy of the node's contacts
//   with related faces at the last step (a node sliding from one face of a piece onto the next,
//   or inside a free element from one nearest face to another, carries its energy over). Deeper,
//   the node did not make its penetration: it became a contact pair, or its weight rose, while it
//   was behind the face (a crack has just separated two pieces that overlapped while they were
//   one: copies of a vertex drift apart along failed interfaces before those are handed over, and
//   an interface parted by sliding can leave a node behind the other face's plane; or the node's
//   own surface changed; or it came back within d_max). The extra depth becomes the allowance, so
//   the contact starts with the energy its approach explains (without it, a node 0.23 mm behind
//   such a face started with 3.4 kJ in the 2D impact at 15 m/s, h = 8 mm, more than the particle's
//   kinetic energy). While the node is shallower than g0 there is no contact, and the allowance
//   follows the node out (g0 = min(g, 0)), so it fades as the overlap it stands for goes away.
// - A contact whose effective area grows (its face's weight rises as the node moves onto it, or
//   the node's area grows at a handover) may gain no more normal energy than the node's related
//   contacts released as their weights fell (`budget`); beyond that g0 absorbs it.
// - The shear spring, a spring per contact area, shrinks with a shrinking area (the elastic slip
//   is kept) and keeps its force when the area grows; what it loses by that, by the rotation of
//   the tangent plane, by slip and when the contact ends is dissipated. Slip dissipation is
//   booked as the spring's energy before, minus after, plus the work of the relative
//   displacement du against the mean of the old and new shear forces: zero while sticking, and
//   the work the leap-frog sees (without the mean, the books were first order in dt: -14 % of
//   the energy in a rattle of free fragments with friction 1).
// Fric = false: frictionless contact (mu = 0 and no cohesion): the shear force is zero, so the
// shear spring is neither computed nor stored (its history stays zero; see ContactSystem::update
// for the switch from friction to none).
template <int D, bool Fric = true, class Force>
KOKKOS_INLINE_FUNCTION void contact_pair(const ContactSurface<D>& S, const ContactLaw& L,
                                         const Kokkos::View<double* [D]>& v,
                                         const Force& f, const Kokkos::View<double*>& pfn,
                                         const Kokkos::View<double*>& pac, const Kokkos::View<double*>& pg0,
                                         const Kokkos::View<double* [D]>& pfs, int j, int s, int fc,
                                         const double (&xs)[D], const double (&vs)[D], double A, double limit,
                                         double budget, double dt, ContactSums& sums) {
  const bool was = pfn(j) > 0.0;
  double g0 = pg0(j);
  if (!(A > 0.0) && !(was || g0 < 0.0)) return;  // not in contact, nothing to update
  double n[D], N[D];
  const double g = face_project_geo<D>(S.fgeo, S.fslot(fc), xs, n, N);
  double Nc[D], nsum = 0;
  for (int q = 0; q < D; ++q) {
    Nc[q] = kclamp(N[q], 0.0, 1.0);
    nsum += Nc[q];
  }
  // relative displacement of the node against the contact point over the last step
  double du[D], du2 = 0;
  for (int k = 0; k < D; ++k) {
    double vf = 0;
    for (int q = 0; q < D; ++q) vf += Nc[q] / nsum * v(S.fnode(fc, q), k);
    du[k] = (vs[k] - vf) * dt;
    du2 += du[k] * du[k];
  }
  for (int q = 0; q < D; ++q) Nc[q] /= nsum;
  if (A > 0.0 && !was) {  // a contact starts: depth beyond what the approach explains is allowed
    const double allowed = limit + 2.0 * kmath::sqrt(du2);
    if (g - g0 < -allowed) g0 = g + allowed;
  }
  if (A > pac(j) && was && g - g0 < 0.0) {  // the area grew: energy only from the budget
    const double ge = g - g0;
    const double Aok = pac(j) + 2.0 * budget / (L.kn * ge * ge);
    if (A > Aok) g0 = g - ge * kmath::sqrt(Aok / A);
  }
  if (!(A > 0.0) || !(g - g0 < 0.0)) {  // no contact (any more): the allowance follows the node
    pg0(j) = g >= g0 ? (g < 0.0 ? g : 0.0) : g0;
    if (was) {  // the contact ended: its shear spring's energy and last half step are dissipated
      if constexpr (Fric) {
        double f2 = 0, w = 0;
        for (int k = 0; k < D; ++k) {
          f2 += pfs(j, k) * pfs(j, k);
          w += pfs(j, k) * du[k];
          pfs(j, k) = 0.0;
        }
        sums.dissipated += 0.5 * f2 / (L.ks * pac(j)) - 0.5 * w;
      }
      pfn(j) = 0.0;
      pac(j) = 0.0;
    }
    return;
  }
  pg0(j) = g0;
  const double Fn = -L.kn * A * (g - g0);
  double Fs[D];
  for (int k = 0; k < D; ++k) Fs[k] = 0.0;
  if constexpr (Fric) {
    // the last step's shear spring in this step's tangent plane, scaled to this step's area
    const double scale = was && A < pac(j) ? A / pac(j) : 1.0;
    double fs0[D], dun = 0, fsn = 0, f2old = 0;
    for (int k = 0; k < D; ++k) {
      dun += du[k] * n[k];
      fs0[k] = was ? pfs(j, k) * scale : 0.0;
      f2old += was ? pfs(j, k) * pfs(j, k) : 0.0;
      fsn += fs0[k] * n[k];
    }
    double Fs2 = 0, f2new = 0;
    for (int k = 0; k < D; ++k) {
      fs0[k] -= fsn * n[k];
      f2new += fs0[k] * fs0[k];
      Fs[k] = fs0[k] - L.ks * A * (du[k] - dun * n[k]);
      Fs2 += Fs[k] * Fs[k];
    }
    if (was) sums.dissipated += 0.5 * (f2old / pac(j) - f2new / A) / L.ks;
    const double lim = L.mu * Fn + L.coh * A;
    const double Fsm = kmath::sqrt(Fs2);
    if (Fsm > lim) {  // slip
      const double r = Fsm > 0 ? lim / Fsm : 0.0;
      double w = 0;
      for (int k = 0; k < D; ++k) {
        Fs[k] *= r;
        w += (fs0[k] + Fs[k]) * du[k];
      }
      sums.dissipated += 0.5 * (f2new - lim * lim) / (L.ks * A) - 0.5 * w;
    }
  }
  for (int k = 0; k < D; ++k) {
    const double Fk = Fn * n[k] + Fs[k];
    f(s, k) += Fk;
    for (int q = 0; q < D; ++q) f(S.fnode(fc, q), k) += -Nc[q] * Fk;
    if constexpr (Fric) pfs(j, k) = Fs[k];
  }
  pfn(j) = Fn;
  pac(j) = A;
  sums.active += 1.0;
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
template <int D, bool Fric = true>
ContactSums contact_forces(const Model<D>& m, const Kokkos::View<int*>& points, int np,
                           const PairList<D>& P, const PairScratch<D>& scratch,
                           const ContactSurface<D>& surf, const ContactLaw& law, double dt,
                           const Kokkos::View<double* [D]>& xb,
                           const ForceScatter<D>& sf) {
  auto xbuild = xb;
  auto x = m.x;
  auto v = m.v;
  auto scatter = sf;
  auto pts = points;
  auto off = P.off;
  auto pface = P.face;
  auto pfn = P.fn;
  auto pac = P.ac;
  auto pg0 = P.g0;
  auto pfs = P.fs;
  auto sg = scratch.g;
  auto sphi = scratch.phi;
  auto sdep = scratch.depth;
  auto sw = scratch.w;
  auto srel = scratch.rel;
  auto sn = scratch.n;
  const ContactSurface<D> S = surf;
  const ContactLaw L = law;
  ContactSums out;
  Kokkos::parallel_reduce(
      "fdem::contact::forces", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const int i, ContactSums& sums) {
        auto f = scatter.access();
        const int s = pts(i);
        double xs[D], vs[D], d2 = 0, v2 = 0;
        for (int k = 0; k < D; ++k) {
          xs[k] = x(s, k);
          vs[k] = v(s, k);
          d2 += (xs[k] - xbuild(s, k)) * (xs[k] - xbuild(s, k));
          v2 += vs[k] * vs[k];
        }
        sums.d2max = d2 > sums.d2max ? d2 : sums.d2max;
        sums.v2max = v2 > sums.v2max ? v2 : sums.v2max;
        const int b = off(s), e = off(s + 1);
        if (b == e) return;
        const double Anode = S.narea(s);
        // 0. the depth of each contact at the last step (for the allowance of contacts that start)
        for (int j = b; j < e; ++j) sdep(j) = pfn(j) > 0.0 ? pfn(j) / (L.kn * kmath::sqrt(pac(j))) : -1.0;
        // 1. the weight of every pair (sw: 0 not in contact; sphi < 0 marks a free element's).
        //    Free elements (a node's candidates are sorted by element: the depth is computed
        //    once per element): weight 1 through the nearest face when the node is inside. Other
        //    faces: gap, normal and fade at the face's edge (0: not near) here, the weight in 2.
        int last_e = -1, last_a = -1;
        double last_d = 0.0;
        for (int j = b; j < e; ++j) {
          const int fc = pface(j);
          const int own = S.fowner(fc);
          double n[D], N[D];
          const double g = face_project_geo<D>(S.fgeo, S.fslot(fc), xs, n, N);
          sg(j) = g;
          if (S.efree(own)) {  // a free element: contact through its nearest face, if inside
            if (own != last_e) {
              last_e = own;
              const ElementDepth ed = element_depth<D>(S, own, xs);
              last_d = ed.depth;
              last_a = ed.nearest;
            }
            bool mine = last_d > 0.0 && last_d < L.dpen;
            for (int k = 0; k < D && mine; ++k) mine = S.fnode(fc, k) != S.elem(own, last_a);
            sw(j) = mine ? 1.0 : 0.0;
            sphi(j) = -1.0;
            continue;
          }
          double score = N[0];
          for (int a = 1; a < D; ++a) score = N[a] < score ? N[a] : score;
          const bool near = g > -L.dpen && g < L.dpen;
          double phi = near ? contact_fade(score, L.tol) : 0.0;
          if (phi > 0.0 && g < 0.0) phi *= facing_fade(node_facing<D>(S, s, n));
          sphi(j) = phi;
          for (int k = 0; k < D; ++k) sn(j, k) = n[k];
        }
        // 2. the other faces: each penetrated near face is a contact, its weight shared among
        //    the near coplanar faces of its piece
        for (int j = b; j < e; ++j) {
          if (sphi(j) < 0.0) continue;
          const int fc = pface(j);
          double w = 0.0;
          if (sg(j) < 0.0 && sphi(j) > 0.0) {
            double sum = 0;
            for (int jj = b; jj < e; ++jj) {
              if (!(sphi(jj) > 0.0)) continue;
              if (jj != j) {
                double d = 0;
                for (int k = 0; k < D; ++k) d += sn(j, k) * sn(jj, k);
                if (!(d > L.cos_same) || !same_piece<D>(S, fc, pface(jj))) continue;
              }
              sum += sphi(jj);
            }
            w = sphi(j) / (sum > 1.0 ? sum : 1.0);
          }
          sw(j) = w;
        }
        // 3. what the weight changes release (the budget of rising ones, step 4)
        for (int j = b; j < e; ++j) {
          const double ge = sg(j) - pg0(j), Aw = Anode * sw(j);
          srel(j) = pfn(j) > 0.0 && Aw < pac(j) && ge < 0.0 ? 0.5 * L.kn * (pac(j) - Aw) * ge * ge : 0.0;
        }
        // 4. the contacts; the energy a contact released as its weight fell may go to a related
        //    one whose weight rises (a node moving from one face of a piece onto the next)
        for (int j = b; j < e; ++j) {
          const int fc = pface(j);
          const double w = sw(j);
          const double lim =
              w > 0.0 && !(sdep(j) >= 0.0) ? related_depth<D>(S, pface, sdep, b, e, fc) / kmath::sqrt(Anode * w) : 0.0;
          double budget = 0.0;
          if (w > 0.0 && sdep(j) >= 0.0 && Anode * w > pac(j))
            for (int jj = b; jj < e; ++jj)
              if (jj != j && srel(jj) > 0.0 && same_piece<D>(S, fc, pface(jj))) budget += srel(jj);
          contact_pair<D, Fric>(S, L, v, f, pfn, pac, pg0, pfs, j, s, fc, xs, vs, Anode * w, lim, budget, dt,
                                sums);
        }
      },
      out);
  return out;
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

namespace Kokkos {
template <int D>
struct reduction_identity<fdem::ContactBox<D>> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::ContactBox<D> sum() { return fdem::ContactBox<D>(); }
};
template <>
struct reduction_identity<fdem::ContactSums> {
  KOKKOS_FORCEINLINE_FUNCTION static fdem::ContactSums sum() { return fdem::ContactSums(); }
};
}  // namespace Kokkos
