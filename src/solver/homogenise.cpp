// Effective moduli of a mesh with its interfaces (homogenise.hpp), one concern in one file: the
// stiffness matrix of the bulk and the interface springs, its solve by conjugate gradients (the
// block preconditioner, the rigid motions kept out, springs beyond double precision capped) and
// the report.
#include "solver/homogenise.hpp"

// Eigen runs on the host only here: without EIGEN_NO_CUDA, nvcc (CUDA builds) makes Eigen mark its
// functions __host__ __device__, which CUDA 13 warns about (#20012-D, #20015-D) in Eigen 3.4.
#define EIGEN_NO_CUDA
#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/QR>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "common/union_find.hpp"
#include "kernels/interface.hpp"
#include "solver/elastic_host.hpp"
#include "solver/interface_materials.hpp"

namespace fdem {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// Voigt index pairs: 2D xx, yy, xy; 3D xx, yy, zz, yz, xz, xy.
constexpr int kVoigt2[3][2] = {{0, 0}, {1, 1}, {0, 1}};
constexpr int kVoigt3[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};

template <int D>
const int (&voigt(int J))[2] {
  if constexpr (D == 2)
    return kVoigt2[J];
  else
    return kVoigt3[J];
}

// Linear elastic stiffness of each element (small strain, Lame constants of its material; plane
// stress through the reduced lambda, as the force kernel's material table). Returns the volume.
template <int D>
double bulk_stiffness(const Case& c, const HostMesh& mesh, Triplets& t) {
  const int npe = D + 1;
  const double thick = D == 2 ? c.thickness : 1.0;
  double volume = 0;
  for (int e = 0; e < mesh.num_elems(); ++e) {
    const auto it = c.region_material.find(mesh.region_names[mesh.elem_region[e]]);
    if (it == c.region_material.end())
      throw InputError(c.file + ": regions: an element's region has no material");
    const BulkMaterial& bm = c.materials[it->second];
    const Lame L = lame(bm.E, bm.nu, D == 2 && c.plane_stress);
    const double lam = L.lambda, mu = L.mu;
    const int* nd = &mesh.elems[static_cast<std::size_t>(e) * npe];
    // shape gradients: g[a][j] = dN_a / dX_j from the inverse of the edge matrix
    double A[D][D], inv[D][D], g[D + 1][D];
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j)
        A[j][b] = mesh.X[static_cast<std::size_t>(nd[b + 1]) * D + j] -
                  mesh.X[static_cast<std::size_t>(nd[0]) * D + j];
    const double d = det<D>(A);
    inverse<D>(A, inv);
    // inv = A^-1: row b of inv holds dN_{b+1} / dX
    for (int j = 0; j < D; ++j) {
      g[0][j] = 0;
      for (int b = 0; b < D; ++b) {
        g[b + 1][j] = inv[b][j];
        g[0][j] -= inv[b][j];
      }
    }
    const double vol = std::abs(d) / (D == 2 ? 2.0 : 6.0) * thick;
    volume += vol;
    for (int a = 0; a < npe; ++a)
      for (int b = 0; b < npe; ++b)
        for (int i = 0; i < D; ++i)
          for (int k = 0; k < D; ++k) {
            // sum_jl g_aj C_ijkl g_bl, C = lam d_ij d_kl + mu (d_ik d_jl + d_il d_jk)
            double s = lam * g[a][i] * g[b][k] + mu * g[a][k] * g[b][i];
            if (i == k)
              for (int j = 0; j < D; ++j) s += mu * g[a][j] * g[b][j];
            t.emplace_back(nd[a] * D + i, nd[b] * D + k, vol * s);
          }
  }
  return volume;
}

// Springs at most this many times stiffer than the bulk at their nodes (the ratio of a spring's
// stiffness, tributary area times max(kn, ks), to its nodes' mean diagonal bulk stiffness: 1.3
// k h / E on the crossed mesh): a stiffer one is solved at this ratio, its kn / ks kept. Double
// precision resolves no more: a spring's force is kn times an opening far below the last digit of
// the displacements around it, and its rounding disturbs the solution by about eps times the
// ratio. The capped springs soften the mesh by less than about 1e-6 of the bulk compliance
// (measured on the crossed mesh, kn = 1e25: E = (1 - 2.2e-7) of the bulk's, not the exact
// 1 - 2e-13); the report says how many were capped.
constexpr double kMaxSpringRatio = 1e7;
// Springs over this ratio join their nodes into one block of the preconditioner; below it one
// block per node does as well for less (grain_crushing_3d, stiffest spring 150: 841 iterations
// per state, 971 with a scalar diagonal, 341 with the groups, whose dense blocks took longer to
// apply than the iterations they saved).
constexpr double kStiffSpringRatio = 1e3;
// A larger group of joined nodes falls back to one block per node (the dense block's cost).
constexpr int kMaxGroupDofs = 600;
// The solve's tolerance on the recursive residual, and the relative residual ||f - K u|| / ||f||
// it must reach, or else be at most kRounding times what rounding in K u gives (stiff springs:
// measured 1.1 to 2.2 times eps || |K| |u| ||, about 3e-14 times the stiffest spring's ratio:
// 1e-8 at 4.6e5, 3.6e-7 at 1e7).
constexpr double kTolerance = 1e-10, kMaxResidual = 1e-8, kRounding = 16;
// A fitted E above the one bulk material's by more than this fraction is refused.
constexpr double kAboveBulk = 1e-6;

// What the interface springs were: the largest stiffness ratio (as given), how many were capped
// at kMaxSpringRatio, the node pairs they join, and those joined by springs over
// kStiffSpringRatio (as solved).
struct Springs {
  double max_ratio = 0;
  long capped = 0;
  std::vector<std::pair<int, int>> pairs, stiff;
};

// Mean diagonal bulk stiffness of each node (from the bulk's triplets).
std::vector<double> node_bulk_scale(const Triplets& t, int nodes, int D) {
  std::vector<double> s(static_cast<std::size_t>(nodes), 0.0);
  for (const auto& e : t)
    if (e.row() == e.col()) s[static_cast<std::size_t>(e.row() / D)] += e.value() / D;
  return s;
}

// Interface springs at the reference positions: each node pair, with its tributary area, kn
// across and ks along the interface, capped at kMaxSpringRatio times the bulk at its nodes
// (`scale`); frictional joints (failed from the start) carry nothing.
template <int D>
Springs interface_stiffness(const Case& c, const HostMesh& mesh, const std::vector<double>& scale,
                            Triplets& t) {
  Springs sp;
  if (mesh.num_ifaces() == 0) return sp;
  const InterfaceMaterialMap map = interface_material_map(c, mesh);
  const double thick = D == 2 ? c.thickness : 1.0;
  for (int q = 0; q < mesh.num_ifaces(); ++q) {
    const InterfaceMaterial& im =
        c.interface_materials[map.material.empty() ? c.fracture_material : map.material[q]];
    if (im.frictional()) continue;
    const int* nd = &mesh.ifaces[static_cast<std::size_t>(q) * 2 * D];
    double xa[D][D], xb[D][D], n[D], ap;
    for (int k = 0; k < D; ++k)
      for (int i = 0; i < D; ++i) xa[k][i] = xb[k][i] = mesh.X[static_cast<std::size_t>(nd[k]) * D + i];
    interface_frame<D>(xa, xb, thick, n, ap);
    for (int k = 0; k < D; ++k) {
      const int a = nd[k], b = nd[D + k];
      if (a == b) continue;  // a crack tip: one node on both sides
      const double bulk = std::min(scale[a], scale[b]);
      const double ratio = bulk > 0 ? ap * std::max(im.kn, im.ks) / bulk : 0.0;
      sp.max_ratio = std::max(sp.max_ratio, ratio);
      const double cap = ratio > kMaxSpringRatio ? kMaxSpringRatio / ratio : 1.0;
      sp.capped += cap < 1.0;
      sp.pairs.emplace_back(a, b);
      if (ratio * cap > kStiffSpringRatio) sp.stiff.emplace_back(a, b);
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
          const double s = cap * ap * ((im.kn - im.ks) * n[i] * n[j] + (i == j ? im.ks : 0.0));
          t.emplace_back(a * D + i, a * D + j, s);
          t.emplace_back(b * D + i, b * D + j, s);
          t.emplace_back(a * D + i, b * D + j, -s);
          t.emplace_back(b * D + i, a * D + j, -s);
        }
    }
  }
  return sp;
}

using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// Block Jacobi: the inverses of K's diagonal blocks over groups of nodes, a node alone or the
// nodes that stiff springs join (the copies of one mesh vertex on the sides of stiff interfaces).
// Each block solves its group's relative motion exactly, so the springs' stiffness does not slow
// the conjugate gradients (with a scalar diagonal they stalled from a spring ratio of 4.6e5 on,
// converging at 4.6e4).
class GroupPreconditioner {
 public:
  GroupPreconditioner(const SpMat& K, int nodes, int D, const std::vector<std::pair<int, int>>& stiff) {
    UnionFind uf(nodes);
    for (const auto& [a, b] : stiff) uf.join(a, b);
    std::vector<std::vector<int>> members(static_cast<std::size_t>(nodes));
    for (int v = 0; v < nodes; ++v) members[static_cast<std::size_t>(uf.find(v))].push_back(v);
    start_.push_back(0);
    for (const auto& g : members) {
      if (g.empty()) continue;
      const bool split = static_cast<int>(g.size()) * D > kMaxGroupDofs;
      for (std::size_t i = 0; i < g.size(); ++i) {
        for (int k = 0; k < D; ++k) dofs_.push_back(g[i] * D + k);
        if (split || i + 1 == g.size()) start_.push_back(static_cast<int>(dofs_.size()));
      }
    }
    invert_blocks(K);
  }

  Eigen::VectorXd apply(const Eigen::VectorXd& r) const {
    Eigen::VectorXd z(r.size());
    for (std::size_t g = 0; g + 1 < start_.size(); ++g) {
      const int n = start_[g + 1] - start_[g];
      const int* d = &dofs_[static_cast<std::size_t>(start_[g])];
      const double* inv = &inv_[at_[g]];
      for (int j = 0; j < n; ++j) rg_[j] = r[d[j]];  // gathered: the row products vectorize
      for (int i = 0; i < n; ++i) {
        double s = 0;
        for (int j = 0; j < n; ++j) s += inv[static_cast<std::size_t>(i) * n + j] * rg_[j];
        z[d[i]] = s;
      }
    }
    return z;
  }

 private:
  // Each group's block of K, inverted through its Cholesky factor (symmetric positive definite:
  // its nodes' bulk blocks plus springs); a block that is not falls back to its diagonal.
  void invert_blocks(const SpMat& K) {
    std::vector<int> local(static_cast<std::size_t>(K.rows()), -1);
    for (std::size_t g = 0; g + 1 < start_.size(); ++g) {
      const int n = start_[g + 1] - start_[g];
      const int* d = &dofs_[static_cast<std::size_t>(start_[g])];
      for (int i = 0; i < n; ++i) local[d[i]] = i;
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n, n);
      for (int i = 0; i < n; ++i)
        for (SpMat::InnerIterator it(K, d[i]); it; ++it)
          if (local[it.col()] >= 0) B(i, local[it.col()]) = it.value();
      for (int i = 0; i < n; ++i) local[d[i]] = -1;
      const Eigen::LLT<Eigen::MatrixXd> llt(B);
      Eigen::MatrixXd inv = Eigen::MatrixXd::Zero(n, n);
      if (llt.info() == Eigen::Success)
        inv = llt.solve(Eigen::MatrixXd::Identity(n, n));
      else
        for (int i = 0; i < n; ++i) inv(i, i) = B(i, i) > 0 ? 1.0 / B(i, i) : 0.0;
      at_.push_back(inv_.size());
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) inv_.push_back(inv(i, j));
    }
  }

  std::vector<int> start_;  // group g's dofs: dofs_[start_[g] .. start_[g + 1])
  std::vector<int> dofs_;
  std::vector<std::size_t> at_;  // group g's inverse (row-major) from inv_[at_[g]]
  std::vector<double> inv_;
  mutable std::vector<double> rg_ = std::vector<double>(kMaxGroupDofs);  // apply's work space
};

// The rigid motions of each piece of the mesh (nodes joined by elements and springs): the null
// space of K, as the mesh floats free. The conjugate gradients run orthogonal to it: rounding in
// the stiff springs' forces otherwise feeds a rigid drift that grows until the solve breaks down
// (a spring ratio of 4.6e5: the residual fell to 1e-8, then rose again).
template <int D>
class RigidModes {
 public:
  static constexpr int NM = D == 2 ? 3 : 6;  // translations, then rotations about the centroid

  RigidModes(const HostMesh& mesh, const std::vector<std::pair<int, int>>& springs) : X_(mesh.X) {
    const int nn = mesh.num_nodes(), npe = D + 1;
    UnionFind uf(nn);
    for (int e = 0; e < mesh.num_elems(); ++e)
      for (int a = 1; a < npe; ++a)
        uf.join(mesh.elems[static_cast<std::size_t>(e) * npe],
                mesh.elems[static_cast<std::size_t>(e) * npe + a]);
    for (const auto& [a, b] : springs) uf.join(a, b);
    piece_.assign(static_cast<std::size_t>(nn), -1);
    std::vector<int> id(static_cast<std::size_t>(nn), -1), count;
    for (int v = 0; v < nn; ++v) {
      int& p = id[static_cast<std::size_t>(uf.find(v))];
      if (p < 0) {
        p = static_cast<int>(count.size());
        count.push_back(0);
        centre_.push_back({});
      }
      piece_[v] = p;
      ++count[p];
      for (int i = 0; i < D; ++i) centre_[p][i] += X_[static_cast<std::size_t>(v) * D + i];
    }
    for (std::size_t p = 0; p < centre_.size(); ++p)
      for (int i = 0; i < D; ++i) centre_[p][i] /= count[p];
    std::vector<Mat> gram(centre_.size(), Mat::Zero());
    for (int v = 0; v < nn; ++v)
      for (int k = 0; k < NM; ++k) {  // column k of the modes' Gram matrix: N^T (N e_k) at v
        double e[NM] = {}, u[D], col[NM];
        e[k] = 1;
        expand(v, e, u);
        project(v, u, col);
        for (int l = 0; l < NM; ++l) gram[piece_[v]](l, k) += col[l];
      }
    for (const Mat& g : gram) ginv_.push_back(g.completeOrthogonalDecomposition().pseudoInverse());
  }

  // v less its projection on the rigid motions.
  void remove(Eigen::VectorXd& v) const {
    const int nn = static_cast<int>(piece_.size());
    coef_.assign(centre_.size() * NM, 0.0);
    for (int n = 0; n < nn; ++n) {
      double c[NM];
      project(n, &v[static_cast<long>(n) * D], c);
      for (int k = 0; k < NM; ++k) coef_[static_cast<std::size_t>(piece_[n]) * NM + k] += c[k];
    }
    for (std::size_t p = 0; p < centre_.size(); ++p) {
      Eigen::Map<Vec> c(&coef_[p * NM]);
      c = (ginv_[p] * c).eval();
    }
    for (int n = 0; n < nn; ++n) {
      double u[D];
      expand(n, &coef_[static_cast<std::size_t>(piece_[n]) * NM], u);
      for (int i = 0; i < D; ++i) v[static_cast<long>(n) * D + i] -= u[i];
    }
  }

 private:
  using Mat = Eigen::Matrix<double, NM, NM>;
  using Vec = Eigen::Matrix<double, NM, 1>;

  // N^T v at node n (N: the modes' displacements there): the force, then the moment about the
  // centroid (2D: its z component).
  void project(int n, const double* v, double* c) const {
    double x[D];
    for (int i = 0; i < D; ++i) {
      x[i] = X_[static_cast<std::size_t>(n) * D + i] - centre_[piece_[n]][i];
      c[i] = v[i];
    }
    if constexpr (D == 2) {
      c[2] = x[0] * v[1] - x[1] * v[0];
    } else {
      c[3] = x[1] * v[2] - x[2] * v[1];
      c[4] = x[2] * v[0] - x[0] * v[2];
      c[5] = x[0] * v[1] - x[1] * v[0];
    }
  }

  // N c at node n: the translation plus the rotation (c's last components) about the centroid.
  void expand(int n, const double* c, double* u) const {
    double x[D];
    for (int i = 0; i < D; ++i) x[i] = X_[static_cast<std::size_t>(n) * D + i] - centre_[piece_[n]][i];
    if constexpr (D == 2) {
      u[0] = c[0] - c[2] * x[1];
      u[1] = c[1] + c[2] * x[0];
    } else {
      u[0] = c[0] + c[4] * x[2] - c[5] * x[1];
      u[1] = c[1] + c[5] * x[0] - c[3] * x[2];
      u[2] = c[2] + c[3] * x[1] - c[4] * x[0];
    }
  }

  const std::vector<double>& X_;
  std::vector<int> piece_;  // each node's piece
  std::vector<std::array<double, D>> centre_;
  std::vector<Mat> ginv_;             // each piece's inverse Gram matrix of its modes
  mutable std::vector<double> coef_;  // remove's work space: each piece's NM coefficients
};

struct CgResult {
  int iterations = 0;
  double residual = 0;  // ||f - K u|| / ||f||, recomputed at the end
  double rounding = 0;  // the part of it rounding in K u can give: eps || |K| |u| || / ||f||
};

// Preconditioned conjugate gradients for K u = f from u = 0 (f balanced on every piece), the
// residuals kept orthogonal to the rigid motions, until the recursive residual is kTolerance of
// ||f||.
template <int D>
CgResult conjugate_gradients(const SpMat& K, const GroupPreconditioner& M, const RigidModes<D>& rigid,
                             const Eigen::VectorXd& f, Eigen::VectorXd& u) {
  const long n = f.size(), max_it = std::min<long>(20 * n + 1000, 2000000000L);
  const double fn = f.norm();
  u = Eigen::VectorXd::Zero(n);
  CgResult out;
  if (!(fn > 0)) return out;
  Eigen::VectorXd r = f, z = M.apply(r), p = z, Kp(n);
  double rz = r.dot(z);
  while (out.iterations < max_it && r.norm() > kTolerance * fn) {
    Kp.noalias() = K * p;
    const double pKp = p.dot(Kp);
    if (!(pKp > 0)) break;
    const double alpha = rz / pKp;
    u += alpha * p;
    r -= alpha * Kp;
    rigid.remove(r);
    z = M.apply(r);
    const double rz1 = r.dot(z);
    p = z + (rz1 / rz) * p;
    rz = rz1;
    ++out.iterations;
  }
  rigid.remove(u);  // the rigid motions z brought in: they strain nothing; r . z, p . K p miss them
  out.residual = (f - K * u).norm() / fn;
  const Eigen::VectorXd Ku_abs = K.cwiseAbs() * u.cwiseAbs();
  out.rounding = std::numeric_limits<double>::epsilon() * Ku_abs.norm() / fn;
  return out;
}

// Outer boundary faces with their outward normals times their measures (area-weighted).
template <int D>
std::vector<double> face_normals(const Case& c, const HostMesh& mesh, const std::vector<int>& faces) {
  const double thick = D == 2 ? c.thickness : 1.0;
  const std::size_t nf = faces.size() / D;
  std::vector<double> nA(nf * D);
  for (std::size_t f = 0; f < nf; ++f) {
    const double* x0 = &mesh.X[static_cast<std::size_t>(faces[f * D]) * D];
    const double* x1 = &mesh.X[static_cast<std::size_t>(faces[f * D + 1]) * D];
    if constexpr (D == 2) {
      nA[f * 2] = (x1[1] - x0[1]) * thick;
      nA[f * 2 + 1] = -(x1[0] - x0[0]) * thick;
    } else {
      const double* x2 = &mesh.X[static_cast<std::size_t>(faces[f * 3 + 2]) * 3];
      const double a[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
      const double b[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
      nA[f * 3] = 0.5 * (a[1] * b[2] - a[2] * b[1]);
      nA[f * 3 + 1] = 0.5 * (a[2] * b[0] - a[0] * b[2]);
      nA[f * 3 + 2] = 0.5 * (a[0] * b[1] - a[1] * b[0]);
    }
  }
  return nA;
}

std::string fmt_g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

// InputError when the load on a piece of the mesh is not balanced: it has no static equilibrium.
template <int D>
void check_balanced(const Case& c, const RigidModes<D>& rigid, const Eigen::VectorXd& f) {
  Eigen::VectorXd g = f;
  rigid.remove(g);
  const double out = (f - g).norm() / f.norm();
  if (out > kMaxResidual)
    throw InputError(
        c.file + ": effective moduli: a piece of the mesh held by nothing but contact (frictional " +
        "joints around it, or bodies that only touch) carries an unbalanced load (" + fmt_g(out) +
        " of the boundary load): it has no static equilibrium; the moduli need each piece closed " +
        "by the outer boundary or bonded to the rest");
}

// InputError when a state's solve did not reach kMaxResidual.
void check_converged(const Case& c, const CgResult& cg, const Springs& sp) {
  if (cg.residual <= std::max(kMaxResidual, kRounding * cg.rounding)) return;
  std::string why = "the stiffest interface spring is " + fmt_g(sp.max_ratio) +
                    " times the bulk at its nodes" +
                    (sp.capped ? " (solved at " + fmt_g(kMaxSpringRatio) + ")" : std::string());
  throw InputError(c.file + ": effective moduli: the solver did not converge (relative residual " +
                   fmt_g(cg.residual) + " after " + std::to_string(cg.iterations) + " iterations, " +
                   fmt_g(std::max(kMaxResidual, kRounding * cg.rounding)) + " needed; " + why + ")");
}

template <int D>
EffectiveModuli solve(const Case& c, const HostMesh& mesh) {
  constexpr int NV = D == 2 ? 3 : 6;
  const long ndof = static_cast<long>(mesh.num_nodes()) * D;
  Triplets t;
  const double volume = bulk_stiffness<D>(c, mesh, t);
  const Springs sp = interface_stiffness<D>(c, mesh, node_bulk_scale(t, mesh.num_nodes(), D), t);
  SpMat K(ndof, ndof);
  K.setFromTriplets(t.begin(), t.end());
  t.clear();
  t.shrink_to_fit();
  const GroupPreconditioner M(K, mesh.num_nodes(), D, sp.stiff);
  const RigidModes<D> rigid(mesh, sp.pairs);
  const std::vector<int> faces = boundary_faces(mesh);
  const std::vector<double> nA = face_normals<D>(c, mesh, faces);
  const std::size_t nf = faces.size() / D;
  EffectiveModuli r;
  r.dim = D;
  r.max_spring_ratio = sp.max_ratio;
  r.capped_springs = sp.capped;
  r.compliance.assign(NV, std::vector<double>(NV, 0.0));
  for (int J = 0; J < NV; ++J) {
    double sig[D][D] = {};
    sig[voigt<D>(J)[0]][voigt<D>(J)[1]] = sig[voigt<D>(J)[1]][voigt<D>(J)[0]] = 1.0;
    Eigen::VectorXd f = Eigen::VectorXd::Zero(ndof), u;
    for (std::size_t q = 0; q < nf; ++q)
      for (int i = 0; i < D; ++i) {
        double ti = 0;  // traction times measure, shared equally by the face's nodes
        for (int j = 0; j < D; ++j) ti += sig[i][j] * nA[q * D + j];
        for (int a = 0; a < D; ++a) f[static_cast<long>(faces[q * D + a]) * D + i] += ti / D;
      }
    std::fprintf(stderr, "fdem: effective moduli: stress state %d of %d (%ld unknowns)\n", J + 1, NV, ndof);
    check_balanced(c, rigid, f);
    const CgResult cg = conjugate_gradients(K, M, rigid, f, u);
    r.iterations = std::max(r.iterations, cg.iterations);
    r.residual = std::max(r.residual, cg.residual);
    r.rounding = std::max(r.rounding, cg.rounding);
    check_converged(c, cg, sp);
    // mean strain: (1/V) sum over the boundary of sym(u (x) n) dA, u linear on each face
    double eps[D][D] = {};
    for (std::size_t q = 0; q < nf; ++q) {
      double um[D] = {};
      for (int a = 0; a < D; ++a)
        for (int i = 0; i < D; ++i) um[i] += u[static_cast<long>(faces[q * D + a]) * D + i] / D;
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
          eps[i][j] += 0.5 * (um[i] * nA[q * D + j] + um[j] * nA[q * D + i]) / volume;
    }
    for (int I = 0; I < NV; ++I) {
      const int i = voigt<D>(I)[0], j = voigt<D>(I)[1];
      r.compliance[I][J] = (i == j ? 1.0 : 2.0) * eps[i][j];
    }
  }
  return r;
}

// The isotropic fit from the mean axial (a) and lateral (b) compliances: {E, nu}.
std::pair<double, double> isotropic_fit(const Case& c, const std::vector<std::vector<double>>& S, int dim) {
  double a = 0, b = 0;
  int nb = 0;
  for (int i = 0; i < dim; ++i) {
    a += S[i][i] / dim;
    for (int k = i + 1; k < dim; ++k, ++nb) b += S[i][k];
  }
  b /= nb;
  if (dim == 2 && !c.plane_stress) {  // plane strain: a = (1 - nu^2) / E, b = -nu (1 + nu) / E
    const double nu = -b / (a - b);
    return {(1 - nu * nu) / a, nu};
  }
  return {1.0 / a, -b / a};
}

}  // namespace

EffectiveModuli effective_moduli(const Case& c, const HostMesh& mesh) {
  EffectiveModuli m = mesh.dim == 2 ? solve<2>(c, mesh) : solve<3>(c, mesh);
  // interfaces only soften: a fitted E above the one bulk material's is a solve that failed
  if (c.materials.size() == 1) {
    const double E = isotropic_fit(c, m.compliance, m.dim).first, Eb = c.materials[0].E;
    if (!(E <= Eb * (1 + kAboveBulk)))
      throw NumericalError(c.file + ": effective moduli: the fitted E = " + fmt_g(E) +
                           " Pa is above the bulk's " + fmt_g(Eb) + " Pa (by " + fmt_g(E / Eb - 1) +
                           "), which interfaces cannot give: the solve is not accurate (relative "
                           "residual " +
                           fmt_g(m.residual) + ", the stiffest interface spring " +
                           fmt_g(m.max_spring_ratio) + " times the bulk at its nodes); report it");
  }
  return m;
}

nlohmann::json effective_moduli_report(const Case& c, const EffectiveModuli& m) {
  const auto& S = m.compliance;
  const char* ax = "xyz";
  nlohmann::json j;
  j["method"] = "uniform stress on the outer boundary; linear elastic bulk and intact interface springs";
  j["compliance_per_Pa"] = S;
  j["solver"] = {{"iterations", m.iterations},
                 {"relative_residual", m.residual},
                 {"rounding_residual", m.rounding},
                 {"stiffest_spring_over_bulk", m.max_spring_ratio}};
  if (m.capped_springs > 0) {
    j["solver"]["capped_springs"] = m.capped_springs;
    j["solver"]["note"] = std::to_string(m.capped_springs) + " interface springs stiffer than " +
                          fmt_g(kMaxSpringRatio) +
                          " times the bulk at their nodes were solved at that ratio: double precision "
                          "resolves no more; their softening is below about 1e-6 of the bulk compliance";
  }
  nlohmann::json app;
  for (int i = 0; i < m.dim; ++i) app[std::string("E_") + ax[i] + "_Pa"] = 1.0 / S[i][i];
  for (int i = 0; i < m.dim; ++i)
    for (int k = i + 1; k < m.dim; ++k) app[std::string("nu_") + ax[i] + ax[k]] = -S[i][k] / S[i][i];
  const int nv = static_cast<int>(S.size());
  const char* shear2[] = {"G_xy_Pa"};
  const char* shear3[] = {"G_yz_Pa", "G_xz_Pa", "G_xy_Pa"};
  for (int I = m.dim; I < nv; ++I) app[m.dim == 2 ? shear2[I - 2] : shear3[I - 3]] = 1.0 / S[I][I];
  j["apparent"] = app;
  const auto [E, nu] = isotropic_fit(c, S, m.dim);
  j["isotropic_fit"] = {{"E_Pa", E}, {"nu", nu}};
  if (c.materials.size() == 1) {
    j["bulk"] = {{"E_Pa", c.materials[0].E}, {"nu", c.materials[0].nu}};
    j["E_over_bulk_E"] = E / c.materials[0].E;
  }
  return j;
}

}  // namespace fdem
