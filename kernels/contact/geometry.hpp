#pragma once
// Contact geometry (docs/theory.md section 6b): the normal, measure and projection of one face
// (2D: an edge, 3D: a triangle), its stored per-step geometry (FaceGeo), its bounding box and
// the distance test of the broad phase (closest point of a segment or triangle).
#include "kernels/model.hpp"

namespace fdem {

// The interface of contact face f (-1: an outer boundary face): the faces come as the nb outer
// boundary faces, then the two faces nb + 2q (side A) and nb + 2q + 1 (side B) of each interface q
// (src/solver/contact_topology.hpp), so it is a number, not a stored one.
KOKKOS_INLINE_FUNCTION int face_interface(int f, int nb) { return f < nb ? -1 : (f - nb) >> 1; }

// The nodes of contact face f: fnode(f, a), a < D. The outer boundary faces' are stored (`outer`,
// nb rows); an interface's two faces take theirs from the interface (Model::iface: side A's D
// nodes, then side B's): side A in its stored order, side B reversed (2D: its nodes 1, 0; 3D: 0, 2,
// 1), so that both normals point out of their element (src/solver/contact_topology.cpp). Holding
// only the outer faces' rows, not one per face that may become a surface, saves D ints for every
// face of every interface.
// (side_b_shift: where side B's a-th face node sits in the interface's row, a + side_b_shift(a);
// face_node_of: the rule on any two such arrays, host mirrors included.)
template <int D>
KOKKOS_INLINE_FUNCTION constexpr int side_b_shift(const int a) {
  return D == 2 ? (a == 0 ? 3 : 1) : (a == 0 ? 3 : (a == 1 ? 4 : 2));
}

template <int D, class Outer, class Iface>
KOKKOS_INLINE_FUNCTION int face_node_of(const Outer& outer, const Iface& iface, const int nb, const int f,
                                        const int a) {
  if (f < nb) return outer(f, a);
  const int r = f - nb, q = r >> 1, s = r & 1;  // (no branch on the side: either is as likely)
  return iface(q, a + s * side_b_shift<D>(a));
}

template <int D>
struct FaceNodes {
  Kokkos::View<int* [D]> outer;
  Kokkos::View<int* [2 * D]> iface;
  int nb = 0, nf = 0;
  KOKKOS_INLINE_FUNCTION int operator()(const int f, const int a) const {
    return face_node_of<D>(outer, iface, nb, f, a);
  }
  // All D nodes of face f at once (one test of its kind, one row read: the loops that visit every
  // node of a face).
  KOKKOS_INLINE_FUNCTION void get(const int f, int (&v)[D]) const {
    if (f < nb) {
      for (int a = 0; a < D; ++a) v[a] = outer(f, a);
      return;
    }
    const int r = f - nb, q = r >> 1, s = r & 1;
    for (int a = 0; a < D; ++a) v[a] = iface(q, a + s * side_b_shift<D>(a));
  }
};


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

// A face's share of each of its D nodes' areas: its measure (thickness included: 2D) over D. One
// definition for the set-up's potential areas (solver/contact_topology.cpp, face_shares) and the
// surface nodes' areas during the run (surfaces.hpp, face_share): the same bits in both.
template <int D>
KOKKOS_INLINE_FUNCTION double face_share_of(const double (&xf)[D][D], double thick) {
  double n[D];
  const double meas = face_normal<D>(xf, n) * thick;
  return meas / D;
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

// The two halves of face_project_geo: the signed gap g along the face's unit normal n (and the
// offset w of p from the face's first vertex), from the first 2 D values of the face's geometry
// row; then the barycentric coordinates N of p's projection from w. The narrow phase takes the
// second only for faces near enough to matter.
template <int D, class G>
KOKKOS_FORCEINLINE_FUNCTION double face_gap_geo(const G& geo, int f, const double (&p)[D], double (&n)[D],
                                           double (&w)[D]) {
  double g = 0;
  for (int k = 0; k < D; ++k) {
    n[k] = geo(f, D + k);
    w[k] = p[k] - geo(f, k);
    g += w[k] * n[k];
  }
  return g;
}
template <int D, class G>
KOKKOS_FORCEINLINE_FUNCTION void face_bary_geo(const G& geo, int f, const double (&w)[D], double (&N)[D]) {
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
}

// face_project from the stored geometry of face f (same arithmetic).
template <int D, class G>
KOKKOS_FORCEINLINE_FUNCTION double face_project_geo(const G& geo, int f, const double (&p)[D], double (&n)[D],
                                               double (&N)[D]) {
  double w[D];
  const double g = face_gap_geo<D>(geo, f, p, n, w);
  face_bary_geo<D>(geo, f, w, N);
  return g;
}

// Centre c and half extent e of the bounding box of face f at positions x.
template <int D>
KOKKOS_INLINE_FUNCTION void face_box(const Kokkos::View<double* [D]>& x, const FaceNodes<D>& fnode,
                                     int f, double (&c)[D], double (&e)[D]) {
  double lo[D], hi[D];
  int v[D];
  fnode.get(f, v);
  for (int k = 0; k < D; ++k) lo[k] = hi[k] = x(v[0], k);
  for (int a = 1; a < D; ++a)
    for (int k = 0; k < D; ++k) {
      const double y = x(v[a], k);
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
KOKKOS_INLINE_FUNCTION bool face_within(const Kokkos::View<double* [D]>& x, const FaceNodes<D>& fnode,
                                        int f, const double (&p)[D], double radius, double tol) {
  double a[D], ab[D], ap[D], L2 = 0, d2 = 0;
  int v[D];
  fnode.get(f, v);
  for (int k = 0; k < D; ++k) {
    a[k] = x(v[0], k);
    ab[k] = x(v[1], k) - a[k];
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
      ac[k] = x(v[2], k) - a[k];
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

}  // namespace fdem
