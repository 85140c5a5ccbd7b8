// The unstructured generators (disc, sphere) through the Gmsh C++ API; the session (a child
// process, Gmsh's errors as InputError, the size check, orientation) is generate_with_gmsh in
// gmsh_io.cpp.
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

using mesh_detail::fmt;
using mesh_detail::generate_with_gmsh;

namespace {

void check_generator_args(const std::string& who, double R, double h) {
  if (!(R > 0) || !std::isfinite(R)) throw InputError(who + ": radius must be positive (got " + fmt(R) + ")");
  if (!(h > 0) || !std::isfinite(h))
    throw InputError(who + ": element_size must be positive (got " + fmt(h) + ")");
  if (h > R) throw InputError(who + ": element_size " + fmt(h) + " is larger than the radius " + fmt(R));
}

// The half disc meshed by Gmsh, reflected across its diameter (through c along the unit vector u):
// every node off the diameter gets its mirror image, each triangle its mirror with two nodes
// swapped (positively oriented), each set its mirror images (face set segments reversed: the
// outer arc keeps its sense). Nodes within 1e-9 R of the diameter are their own images.
HostMesh mirror_across_diameter(HostMesh half, double cx, double cy, double ux, double uy, double R) {
  const int nn = half.num_nodes(), ne = half.num_elems();
  const double nx = -uy, ny = ux;  // normal of the diameter
  std::vector<int> image(nn);
  std::vector<double> X = half.X;
  for (int i = 0; i < nn; ++i) {
    const double x = half.X[2 * static_cast<size_t>(i)], y = half.X[2 * static_cast<size_t>(i) + 1];
    const double s = (x - cx) * nx + (y - cy) * ny;
    if (std::abs(s) <= 1e-9 * R) {
      image[i] = i;
      continue;
    }
    image[i] = static_cast<int>(X.size() / 2);
    X.push_back(x - 2 * s * nx);
    X.push_back(y - 2 * s * ny);
  }
  HostMesh m = std::move(half);
  m.X = std::move(X);
  m.node_origin.resize(m.num_nodes());  // identity, as extracted meshes have it
  std::iota(m.node_origin.begin(), m.node_origin.end(), 0);
  m.elems.reserve(2 * m.elems.size());
  for (int e = 0; e < ne; ++e) {
    const int a = m.elems[3 * static_cast<size_t>(e)], b = m.elems[3 * static_cast<size_t>(e) + 1],
              c = m.elems[3 * static_cast<size_t>(e) + 2];
    m.elems.insert(m.elems.end(), {image[a], image[c], image[b]});
    m.elem_region.push_back(m.elem_region[e]);
  }
  for (auto& [name, set] : m.node_sets) {
    const size_t n = set.size();
    for (size_t k = 0; k < n; ++k)
      if (image[set[k]] != set[k]) set.push_back(image[set[k]]);
    std::sort(set.begin(), set.end());
  }
  for (auto& [name, f] : m.face_sets) {  // (a segment on the diameter is its own image)
    const size_t n = f.size() / 2;
    for (size_t k = 0; k < n; ++k)
      if (image[f[2 * k]] != f[2 * k] || image[f[2 * k + 1]] != f[2 * k + 1])
        f.insert(f.end(), {image[f[2 * k + 1]], image[f[2 * k]]});
  }
  return m;
}

}  // namespace

HostMesh generate_disc(double cx, double cy, double R, double h, const std::string& region, double dx,
                       double dy, bool mirror) {
  const std::string who = "disc generator";
  check_generator_args(who, R, h);
  if (R / h > 5000)
    throw InputError(who + ": radius / element_size = " + fmt(R / h) +
                     " is above the limit 5000: give mesh.element_size >= " + fmt(R / 5000));
  const std::string rname = region.empty() ? std::string("body") : region;
  const double len = std::sqrt(dx * dx + dy * dy);
  if (mirror && !(len > 0))
    throw InputError(who + ": a disc symmetric about its diameter needs the diameter's direction");
  if (mirror) {  // the half disc left of (dx, dy), meshed, then reflected across the diameter
    const double ux = dx / len, uy = dy / len;
    HostMesh half = generate_with_gmsh(who, "mesh the half disc", 2, h, 1, [&] {
      gmsh::model::add("half_disc");
      const double a0 = std::atan2(uy, ux), pi = std::acos(-1.0);
      const int arc = gmsh::model::occ::addCircle(cx, cy, 0.0, R, -1, a0, a0 + pi);
      gmsh::model::occ::synchronize();
      gmsh::vectorpair pts;
      gmsh::model::getBoundary({{1, arc}}, pts, false, false, false);
      const int line = gmsh::model::occ::addLine(std::abs(pts.at(1).second), std::abs(pts.at(0).second));
      const int loop = gmsh::model::occ::addCurveLoop({arc, line});
      const int s = gmsh::model::occ::addPlaneSurface({loop});
      gmsh::model::occ::synchronize();
      const int ps = gmsh::model::addPhysicalGroup(2, {s});
      gmsh::model::setPhysicalName(2, ps, rname);
      const int pc = gmsh::model::addPhysicalGroup(1, {arc});
      gmsh::model::setPhysicalName(1, pc, "boundary");
      const int pd = gmsh::model::addPhysicalGroup(1, {line});
      gmsh::model::setPhysicalName(1, pd, "diameter");
    });
    return mirror_across_diameter(std::move(half), cx, cy, ux, uy, R);
  }
  return generate_with_gmsh(who, "mesh the disc", 2, h, 1, [&] {
    gmsh::model::add("disc");
    const int s = gmsh::model::occ::addDisk(cx, cy, 0.0, R, R);
    std::vector<int> surfaces{s}, diameter;
    if (len > 0) {  // the diameter along (dx, dy): the disc cut into two halves that share it
      const double ux = R * dx / len, uy = R * dy / len;
      const int a = gmsh::model::occ::addPoint(cx + ux, cy + uy, 0.0);
      const int b = gmsh::model::occ::addPoint(cx - ux, cy - uy, 0.0);
      const int l = gmsh::model::occ::addLine(a, b);
      gmsh::vectorpair out;
      std::vector<gmsh::vectorpair> map;
      gmsh::model::occ::fragment({{2, s}}, {{1, l}}, out, map);
      surfaces.clear();
      for (const auto& [d, t] : out)
        if (d == 2) surfaces.push_back(t);
      for (const auto& piece : map.at(1)) diameter.push_back(piece.second);  // the line's pieces
    }
    gmsh::model::occ::synchronize();
    gmsh::vectorpair faces, bnd;
    for (int t : surfaces) faces.push_back({2, t});
    gmsh::model::getBoundary(faces, bnd, len > 0, false, false);  // combined: the outer circle only
    std::vector<int> curves;
    for (const auto& [d, t] : bnd) curves.push_back(std::abs(t));
    const int ps = gmsh::model::addPhysicalGroup(2, surfaces);
    gmsh::model::setPhysicalName(2, ps, rname);
    const int pc = gmsh::model::addPhysicalGroup(1, curves);
    gmsh::model::setPhysicalName(1, pc, "boundary");
    if (!diameter.empty()) {
      const int pd = gmsh::model::addPhysicalGroup(1, diameter);
      gmsh::model::setPhysicalName(1, pd, "diameter");
    }
  });
}

HostMesh generate_sphere(const std::array<double, 3>& centre, double R, double h, const std::string& region,
                         const std::string& mesher) {
  const std::string who = "sphere generator";
  check_generator_args(who, R, h);
  if (mesher != "delaunay" && mesher != "hxt")
    throw InputError(who + ": unknown mesher '" + mesher + "' (allowed: delaunay, hxt)");
  if (R / h > 200)
    throw InputError(who + ": radius / element_size = " + fmt(R / h) +
                     " is above the limit 200: give mesh.element_size >= " + fmt(R / 200));
  const std::string rname = region.empty() ? std::string("body") : region;
  // Delaunay (1), or HXT (10; threads: General.NumThreads 1)
  return generate_with_gmsh(who, "mesh the sphere", 3, h, mesher == "hxt" ? 10 : 1, [&] {
    gmsh::model::add("sphere");
    const int v = gmsh::model::occ::addSphere(centre[0], centre[1], centre[2], R);
    gmsh::model::occ::synchronize();
    gmsh::vectorpair bnd;
    gmsh::model::getBoundary({{3, v}}, bnd, false, false, false);
    std::vector<int> surfs;
    for (const auto& [d, t] : bnd) surfs.push_back(std::abs(t));
    const int pv = gmsh::model::addPhysicalGroup(3, {v});
    gmsh::model::setPhysicalName(3, pv, rname);
    const int ps = gmsh::model::addPhysicalGroup(2, surfs);
    gmsh::model::setPhysicalName(2, ps, "surface");
  });
}

}  // namespace fdem
