#pragma once
// Effective elastic moduli of a mesh with its interfaces (`fdem check --moduli`,
// docs/case-format.md "Effective moduli"): the static, linear response of the whole mesh, bulk
// elements and intact interface springs, to a uniform stress on its outer boundary.
#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "mesh/mesh.hpp"

namespace fdem {

// For each unit stress state (Voigt order xx, yy, xy in 2D; xx, yy, zz, yz, xz, xy in 3D) the
// outer boundary carries the tractions sigma n; the equilibrium K u = f of the linear elastic
// bulk (small strain, the run's plane strain or stress) and the interface springs (kn across,
// ks along, each node pair with its tributary area; frictional joints carry nothing) is solved
// by preconditioned conjugate gradients, and the mean strain (1/V) sum over the boundary of
// sym(u (x) n) dA (which includes the openings of the interfaces) is that state's column of the
// effective compliance. Springs stiffer than double precision resolves against the bulk are
// solved at the largest ratio it does (counted in capped_springs). Throws InputError when a piece
// of the mesh carries an unbalanced load (held by nothing but contact) or the solver does not
// converge (a residual above 1e-8 and above what rounding in K u gives), NumericalError when the
// fitted E of a one-material mesh comes out above its bulk E.
struct EffectiveModuli {
  int dim = 2;
  std::vector<std::vector<double>> compliance;  // Voigt, engineering shear strains (1/Pa)
  int iterations = 0;                           // conjugate-gradient iterations, largest of the states
  double residual = 0;                          // ||f - K u|| / ||f||, largest of the states
  double rounding = 0;                          // what rounding in K u gives: eps || |K| |u| || / ||f||
  double max_spring_ratio = 0;                  // stiffest interface spring over the bulk at its nodes
  long capped_springs = 0;                      // springs solved at a lower ratio (kMaxSpringRatio)
};
EffectiveModuli effective_moduli(const Case& c, const HostMesh& mesh);

// Report: the compliance, the apparent moduli along the axes (E_x = 1 / S_xx, nu_xy = -S_xy / S_xx,
// G_xy = 1 / S_xyxy, ...), the isotropic fit (E, nu from the mean axial and lateral compliances,
// through the plane strain relations in a plane strain run) and, with one bulk material, its E and
// the ratio.
nlohmann::json effective_moduli_report(const Case& c, const EffectiveModuli& m);

}  // namespace fdem
