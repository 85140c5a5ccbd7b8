// The unstructured generators (disc, sphere) through the Gmsh C++ API; the session (a child
// process, Gmsh's errors as InputError, the size check, orientation) is generate_with_gmsh in
// gmsh_io.cpp.
#include <gmsh.h>

#include <cmath>
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

}  // namespace

HostMesh generate_disc(double cx, double cy, double R, double h, const std::string& region, double dx,
                       double dy) {
  const std::string who = "disc generator";
  check_generator_args(who, R, h);
  if (R / h > 5000)
    throw InputError(who + ": radius / element_size = " + fmt(R / h) +
                     " is above the limit 5000: give mesh.element_size >= " + fmt(R / 5000));
  const std::string rname = region.empty() ? std::string("body") : region;
  return generate_with_gmsh(who, "mesh the disc", 2, h, 1, [&] {
    gmsh::model::add("disc");
    const int s = gmsh::model::occ::addDisk(cx, cy, 0.0, R, R);
    std::vector<int> surfaces{s};
    const double len = std::sqrt(dx * dx + dy * dy);
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
