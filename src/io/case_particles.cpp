// Case schema: "mesh": {"generator": "particles", ...} (src/mesh/particles.cpp makes the mesh).
#include <string>

#include "io/case_internal.hpp"

namespace fdem::case_detail {

namespace {

// A number or a [lo, hi] pair (lo <= hi) at `key`, each in `r`.
std::pair<double, double> range_pair(json& m, const std::string& P, const char* key, const Range& r,
                                     std::optional<std::pair<double, double>> def, const Reader& R) {
  const std::string p = child(P, key);
  if (!m.contains(key)) {
    if (!def) R.fail(p, "missing (a number or [min, max])");
    m[key] = {def->first, def->second};
    return *def;
  }
  const json& v = m[key];
  if (!v.is_array()) {
    const double x = R.number_value(v, p, r);
    return {x, x};
  }
  if (v.size() != 2)
    R.fail(p, "expected a number or [min, max], got " + std::to_string(v.size()) + " elements");
  const double lo = R.number_value(v[0], child(p, 0), r), hi = R.number_value(v[1], child(p, 1), r);
  if (hi < lo) R.fail(p, "min " + fmt_num(lo) + " is larger than max " + fmt_num(hi));
  return {lo, hi};
}

}  // namespace

void read_particles_generator(json& m, MeshSpec& s, const Reader& R) {
  const std::string P = "mesh";
  R.keys(m, P,
         {"generator", "count", "shape", "radius", "axis_ratio", "vertices", "box", "gap", "seed",
          "element_size", "region", "threads", "batch", "mesher"});
  ParticleSpec& q = s.particles;
  q.count = static_cast<int>(R.integer(m, P, "count", 1, 100000));
  q.shape = R.string(m, P, "shape", std::string("sphere"));
  if (q.shape != "sphere" && q.shape != "ellipsoid" && q.shape != "polyhedron")
    R.fail(child(P, "shape"), "unknown shape '" + q.shape + "' (allowed: sphere, ellipsoid, polyhedron)");
  const auto rad = range_pair(m, P, "radius", gt(0), std::nullopt, R);
  q.rmin = rad.first;
  q.rmax = rad.second;
  if (q.shape == "ellipsoid") {
    const auto ar = range_pair(m, P, "axis_ratio", between(0, true, 1, false), std::make_pair(0.5, 1.0), R);
    q.ratio_min = ar.first;
    q.ratio_max = ar.second;
  } else if (m.contains("axis_ratio")) {
    R.fail(child(P, "axis_ratio"), "applies to shape 'ellipsoid' only (shape is '" + q.shape + "')");
  }
  if (q.shape == "polyhedron")
    q.vertices = static_cast<int>(R.integer(m, P, "vertices", 6, 60, 12));
  else if (m.contains("vertices"))
    R.fail(child(P, "vertices"), "applies to shape 'polyhedron' only (shape is '" + q.shape + "')");
  const std::string B = child(P, "box");
  json& box = R.object(m, P, "box", true);
  R.keys(box, B, {"origin", "size"});
  q.box_origin = R.vec(box, B, "origin", 3, Vec3{0, 0, 0});
  q.box_size = R.vec(box, B, "size", 3, std::nullopt, gt(0));
  q.gap = R.number(m, P, "gap", ge(0), 0.0);
  q.seed = static_cast<unsigned long>(R.integer(m, P, "seed", 0, 2147483647L, 1));
  q.threads = static_cast<int>(R.integer(m, P, "threads", 1, 64, 1));
  q.batch = static_cast<int>(R.integer(m, P, "batch", 1, 100000, 50));
  q.mesher = R.string(m, P, "mesher", std::string("delaunay"));
  if (q.mesher != "delaunay" && q.mesher != "hxt")
    R.fail(child(P, "mesher"), "unknown mesher '" + q.mesher + "' (allowed: delaunay, hxt)");
  // no larger than the smallest particle's radius (the generator also checks its half-width)
  s.element_size = R.number(m, P, "element_size", between(0, true, q.rmin, false));
  s.region = R.name(m, P, "region", std::string("particles"));
}

}  // namespace fdem::case_detail
