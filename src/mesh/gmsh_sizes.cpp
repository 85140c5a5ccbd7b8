// Sizes around the Gmsh meshing (gmsh_internal.hpp): before a .geo file is meshed, its trial
// meshes (a coarse one for its area or volume, a 1D one for the sizes the file sets) and the refusal
// of a mesh that cannot fit in memory (memory_budget.hpp); after meshing, the check that Gmsh
// honoured the asked size. The trial meshes run inside the Gmsh session (gmsh_io.cpp) of the file.
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/error.hpp"
#include "mesh/gmsh_internal.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::mesh_detail {

namespace {

// Area (2D) or volume (3D) of the current mesh's elements of dimension dim (triangles,
// tetrahedra), or total length and count of its line elements (dim 1).
struct MeshMeasure {
  double measure = 0;
  std::size_t count = 0;
};

MeshMeasure measure_current_mesh(int dim) {
  std::vector<std::size_t> ntags;
  std::vector<double> xyz, uvw;
  gmsh::model::mesh::getNodes(ntags, xyz, uvw, -1, -1, false, false);
  std::unordered_map<std::size_t, std::size_t> at;
  for (std::size_t i = 0; i < ntags.size(); ++i) at[ntags[i]] = 3 * i;
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> etags, enodes;
  gmsh::model::mesh::getElements(types, etags, enodes, dim, -1);
  MeshMeasure mm;
  auto p = [&](std::size_t tag) { return &xyz.at(at.at(tag)); };
  for (std::size_t t = 0; t < types.size(); ++t) {
    const int npe = types[t] == 1 ? 2 : types[t] == 2 ? 3 : types[t] == 4 ? 4 : 0;
    if (npe == 0) continue;  // other element types: not counted
    const auto& nd = enodes[t];
    for (std::size_t e = 0; e + npe <= nd.size(); e += npe) {
      const double* a = p(nd[e]);
      double u[3][3] = {};
      for (int k = 1; k < npe; ++k) {
        const double* b = p(nd[e + k]);
        for (int c = 0; c < 3; ++c) u[k - 1][c] = b[c] - a[c];
      }
      const double cx = u[0][1] * u[1][2] - u[0][2] * u[1][1], cy = u[0][2] * u[1][0] - u[0][0] * u[1][2],
                   cz = u[0][0] * u[1][1] - u[0][1] * u[1][0];
      if (npe == 2) mm.measure += std::sqrt(u[0][0] * u[0][0] + u[0][1] * u[0][1] + u[0][2] * u[0][2]);
      if (npe == 3) mm.measure += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
      if (npe == 4) mm.measure += std::abs(cx * u[2][0] + cy * u[2][1] + cz * u[2][2]) / 6.0;
      ++mm.count;
    }
  }
  return mm;
}

// A trial meshing of dimension d with sizes clamped to [lmin, lmax]; errors do not count, the mesh
// and the log are cleared after it and the options restored. Returns count 0 if it failed.
MeshMeasure trial_mesh(int d, double lmin, double lmax) {
  const char* kMin = "Mesh.CharacteristicLengthMin";
  const char* kMax = "Mesh.CharacteristicLengthMax";
  double min0 = 0, max0 = 1e22, abort0 = 2;
  gmsh::option::getNumber(kMin, min0);
  gmsh::option::getNumber(kMax, max0);
  gmsh::option::getNumber("General.AbortOnError", abort0);
  MeshMeasure mm;
  try {
    gmsh::option::setNumber("General.AbortOnError", 0);  // an error is logged, not thrown
    gmsh::option::setNumber(kMin, lmin);
    gmsh::option::setNumber(kMax, lmax);
    gmsh::model::mesh::generate(d);
    if (GmshSession::first_error().empty()) mm = measure_current_mesh(d);
  } catch (...) {
    mm = MeshMeasure{};
  }
  try {
    gmsh::model::mesh::clear();
    gmsh::option::setNumber(kMin, min0);
    gmsh::option::setNumber(kMax, max0);
    gmsh::option::setNumber("General.AbortOnError", abort0);
  } catch (...) {
  }
  GmshSession::clear_log();
  return mm;
}

}  // namespace

// Before a .geo file is meshed: its area (2D) or volume (3D) from a coarse trial mesh (the bounding
// box if that fails), its element size (mesh.element_size, or less where the file's own sizes are
// smaller: the mean segment of a trial 1D mesh, floored at 1e-5 of the model's diagonal), and from
// them the element count; InputError if that cannot fit in memory.
void refuse_oversized_geo(const std::string& path, int dim, double element_size) {
  double lo[3], hi[3];
  gmsh::model::getBoundingBox(-1, -1, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  double ext[3], diag2 = 0;
  for (int k = 0; k < 3; ++k) {
    ext[k] = hi[k] - lo[k];
    diag2 += ext[k] * ext[k];
  }
  const double diag = std::sqrt(diag2);
  if (!(diag > 0) || !std::isfinite(diag)) return;
  const double cap = max_elements(dim);
  if (!std::isfinite(cap)) return;  // unknown memory or FDEM_MEMORY_CHECK=off
  const MeshMeasure coarse = trial_mesh(dim, diag / 20, diag / 20);
  double measure = coarse.measure;
  std::string measured = "from a coarse mesh";
  if (!(coarse.count > 0 && measure > 0)) {
    // the model's bounding box (in 2D, of the two largest extents)
    double e[3] = {ext[0], ext[1], ext[2]};
    std::sort(e, e + 3);
    measure = dim == 2 ? e[2] * e[1] : e[2] * e[1] * e[0];
    measured = "of the bounding box";
  }
  const std::string unit = dim == 2 ? " m^2" : " m^3";
  const std::string what = (dim == 2 ? "area " : "volume ") + fmt(measure) + unit + " " + measured;
  if (element_size > 0)  // at least this many: the file's own sizes can only be smaller
    check_fits_in_memory(estimate_gmsh_elements(dim, measure, element_size), dim,
                         "mesh.element_size = " + fmt(element_size) + " m for " + path + " (" + what + ")",
                         element_size, "mesh.element_size", estimate_gmsh_elements(dim, measure, 1.0));
  const double floor = diag * 1e-5;
  const MeshMeasure lines = trial_mesh(1, floor, element_size > 0 ? std::max(element_size, floor) : 1e22);
  if (lines.count == 0) return;
  const double mean = lines.measure / static_cast<double>(lines.count);
  if (element_size > 0 && mean >= element_size) return;  // checked above
  const bool floored = mean <= 1.01 * floor;             // the file's sizes may be smaller still
  check_fits_in_memory(estimate_gmsh_elements(dim, measure, mean), dim,
                       "the element sizes set in " + path + " (mean segment " + (floored ? "<= " : "") +
                           fmt(mean) + " m along its curves; " + what + ")");
}

// Gmsh does not always honour a size (4.8 counts a curve's segments in an int: above 2^31 the
// curve gets one segment); a mesh whose mean edge is over twice the asked size is refused.
void check_size_honoured(const HostMesh& m, const std::string& source, double h) {
  const int npe = m.dim + 1, ne = m.num_elems();
  double sum = 0;
  std::size_t n = 0;
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a)
      for (int b = a + 1; b < npe; ++b) {
        const int p = m.elems[static_cast<std::size_t>(e) * npe + a];
        const int q = m.elems[static_cast<std::size_t>(e) * npe + b];
        double d2 = 0;
        for (int k = 0; k < m.dim; ++k) {
          const double d =
              m.X[static_cast<std::size_t>(p) * m.dim + k] - m.X[static_cast<std::size_t>(q) * m.dim + k];
          d2 += d * d;
        }
        sum += std::sqrt(d2);
        ++n;
      }
  const double mean = n ? sum / static_cast<double>(n) : 0.0;
  if (mean > 2 * h)
    throw InputError(source + ": Gmsh did not honour mesh.element_size = " + fmt(h) + " m: its mesh has " +
                     std::to_string(ne) + " elements with a mean edge of " + fmt(mean) +
                     " m; give a larger mesh.element_size (Gmsh gives a curve one segment when it "
                     "would need more than 2^31)");
}

}  // namespace fdem::mesh_detail
