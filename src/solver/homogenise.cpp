#include "solver/homogenise.hpp"

// Eigen runs on the host only here: without EIGEN_NO_CUDA, nvcc (CUDA builds) makes Eigen mark its
// functions __host__ __device__, which CUDA 13 warns about (#20012-D, #20015-D) in Eigen 3.4.
#define EIGEN_NO_CUDA
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/error.hpp"
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
        A[j][b] = mesh.X[static_cast<std::size_t>(nd[b + 1]) * D + j] - mesh.X[static_cast<std::size_t>(nd[0]) * D + j];
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

// Interface springs at the reference positions: each node pair, with its tributary area, kn
// across and ks along the interface; frictional joints (failed from the start) carry nothing.
template <int D>
void interface_stiffness(const Case& c, const HostMesh& mesh, Triplets& t) {
  if (mesh.num_ifaces() == 0) return;
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
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
          const double s = ap * ((im.kn - im.ks) * n[i] * n[j] + (i == j ? im.ks : 0.0));
          t.emplace_back(a * D + i, a * D + j, s);
          t.emplace_back(b * D + i, b * D + j, s);
          t.emplace_back(a * D + i, b * D + j, -s);
          t.emplace_back(b * D + i, a * D + j, -s);
        }
    }
  }
}

template <int D>
EffectiveModuli solve(const Case& c, const HostMesh& mesh) {
  constexpr int NV = D == 2 ? 3 : 6;
  const long ndof = static_cast<long>(mesh.num_nodes()) * D;
  Triplets t;
  const double volume = bulk_stiffness<D>(c, mesh, t);
  interface_stiffness<D>(c, mesh, t);
  Eigen::SparseMatrix<double> K(ndof, ndof);
  K.setFromTriplets(t.begin(), t.end());
  t.clear();
  t.shrink_to_fit();
  // outer boundary faces with their outward normals (area-weighted) and measures
  const std::vector<int> faces = boundary_faces(mesh);
  const double thick = D == 2 ? c.thickness : 1.0;
  const std::size_t nf = faces.size() / D;
  std::vector<double> nA(nf * D);  // outward normal times the face's measure
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
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-10);
  cg.setMaxIterations(static_cast<int>(std::min<long>(20 * ndof + 1000, 2000000000L)));
  cg.compute(K);
  EffectiveModuli r;
  r.dim = D;
  r.compliance.assign(NV, std::vector<double>(NV, 0.0));
  for (int J = 0; J < NV; ++J) {
    double sig[D][D] = {};
    sig[voigt<D>(J)[0]][voigt<D>(J)[1]] = sig[voigt<D>(J)[1]][voigt<D>(J)[0]] = 1.0;
    Eigen::VectorXd f = Eigen::VectorXd::Zero(ndof);
    for (std::size_t q = 0; q < nf; ++q)
      for (int i = 0; i < D; ++i) {
        double ti = 0;  // traction times measure, shared equally by the face's nodes
        for (int j = 0; j < D; ++j) ti += sig[i][j] * nA[q * D + j];
        for (int a = 0; a < D; ++a) f[static_cast<long>(faces[q * D + a]) * D + i] += ti / D;
      }
    std::fprintf(stderr, "fdem: effective moduli: stress state %d of %d (%ld unknowns)\n", J + 1, NV, ndof);
    const Eigen::VectorXd u = cg.solve(f);
    r.iterations = std::max(r.iterations, static_cast<int>(cg.iterations()));
    r.residual = std::max(r.residual, cg.error());
    if (cg.info() != Eigen::Success || !(cg.error() <= 1e-8))
      throw InputError(c.file + ": effective moduli: the solver did not converge (relative residual " +
                       std::to_string(cg.error()) + " after " + std::to_string(cg.iterations()) +
                       " iterations; a mesh with a piece held by nothing but contact has no stiffness)");
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

}  // namespace

EffectiveModuli effective_moduli(const Case& c, const HostMesh& mesh) {
  return mesh.dim == 2 ? solve<2>(c, mesh) : solve<3>(c, mesh);
}

nlohmann::json effective_moduli_report(const Case& c, const EffectiveModuli& m) {
  const auto& S = m.compliance;
  const char* ax = "xyz";
  nlohmann::json j;
  j["method"] = "uniform stress on the outer boundary; linear elastic bulk and intact interface springs";
  j["compliance_per_Pa"] = S;
  j["solver"] = {{"iterations", m.iterations}, {"relative_residual", m.residual}};
  nlohmann::json app;
  for (int i = 0; i < m.dim; ++i) app[std::string("E_") + ax[i] + "_Pa"] = 1.0 / S[i][i];
  for (int i = 0; i < m.dim; ++i)
    for (int k = i + 1; k < m.dim; ++k) app[std::string("nu_") + ax[i] + ax[k]] = -S[i][k] / S[i][i];
  const int nv = static_cast<int>(S.size());
  const char* shear2[] = {"G_xy_Pa"};
  const char* shear3[] = {"G_yz_Pa", "G_xz_Pa", "G_xy_Pa"};
  for (int I = m.dim; I < nv; ++I) app[m.dim == 2 ? shear2[I - 2] : shear3[I - 3]] = 1.0 / S[I][I];
  j["apparent"] = app;
  // isotropic fit from the mean axial (a) and lateral (b) compliances
  double a = 0, b = 0;
  int nb = 0;
  for (int i = 0; i < m.dim; ++i) {
    a += S[i][i] / m.dim;
    for (int k = i + 1; k < m.dim; ++k, ++nb) b += S[i][k];
  }
  b /= nb;
  double E, nu;
  if (m.dim == 2 && !c.plane_stress) {  // plane strain: a = (1 - nu^2) / E, b = -nu (1 + nu) / E
    nu = -b / (a - b);
    E = (1 - nu * nu) / a;
  } else {
    nu = -b / a;
    E = 1.0 / a;
  }
  j["isotropic_fit"] = {{"E_Pa", E}, {"nu", nu}};
  if (c.materials.size() == 1) {
    j["bulk"] = {{"E_Pa", c.materials[0].E}, {"nu", c.materials[0].nu}};
    j["E_over_bulk_E"] = E / c.materials[0].E;
  }
  return j;
}

}  // namespace fdem
