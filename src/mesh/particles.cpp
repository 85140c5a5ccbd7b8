// Mesh generator "particles" (particles.hpp): shapes, sizes and orientations drawn from a seeded
// generator, placement by random sequential addition with a bounding-sphere test, and one Gmsh
// session (generate_with_gmsh, gmsh_io.cpp) that meshes every particle as its own volume.
#include "mesh/particles.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <random>
#include <utility>

#include "common/error.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

using mesh_detail::fmt;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform numbers from the 64-bit Mersenne twister, converted by hand (the standard
// distributions differ between standard libraries; this does not).
struct Rng {
  std::mt19937_64 g;
  explicit Rng(unsigned long seed) : g(seed) {}
  double uniform() { return static_cast<double>(g() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
};

// Uniformly distributed rotation (Shoemake's random unit quaternion), row-major.
std::array<double, 9> random_rotation(Rng& r) {
  const double u1 = r.uniform(), u2 = r.uniform(), u3 = r.uniform();
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  const double x = a * std::sin(2 * kPi * u2), y = a * std::cos(2 * kPi * u2);
  const double z = b * std::sin(2 * kPi * u3), w = b * std::cos(2 * kPi * u3);
  return {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
          2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
          2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
}

std::array<double, 3> unit_vector(Rng& r) {
  const double z = r.uniform(-1, 1), phi = r.uniform(0, 2 * kPi), s = std::sqrt(std::max(0.0, 1 - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

// A random convex polyhedron of `n` vertices: points on the unit sphere at least 0.6 of the mean
// spacing apart (no short edges, which would force small elements), their hull, scaled to the
// volume of the sphere of radius `r`.
void random_polyhedron(Rng& rng, int n, double r, Particle& p, const std::string& who) {
  const double sep = 0.6 * std::sqrt(4 * kPi / n), cos_sep = std::cos(sep);
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::vector<double> pts;
    for (int tries = 0; static_cast<int>(pts.size()) < 3 * n && tries < 100000; ++tries) {
      const auto u = unit_vector(rng);
      bool ok = true;
      for (std::size_t j = 0; ok && j < pts.size(); j += 3)
        ok = u[0] * pts[j] + u[1] * pts[j + 1] + u[2] * pts[j + 2] < cos_sep;
      if (ok) pts.insert(pts.end(), u.begin(), u.end());
    }
    if (static_cast<int>(pts.size()) < 3 * n || !sphere_hull(pts, p.tris)) continue;
    const double s = std::cbrt(4.0 / 3.0 * kPi * r * r * r / hull_volume(pts, p.tris));
    double mean[3] = {0, 0, 0};  // centred on the vertices' mean: a tighter bounding sphere
    for (std::size_t j = 0; j < pts.size(); ++j) mean[j % 3] += pts[j] / n;
    p.bound = 0;
    for (std::size_t j = 0; j < pts.size(); j += 3) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        pts[j + k] = s * (pts[j + k] - mean[k]);
        d2 += pts[j + k] * pts[j + k];
      }
      p.bound = std::max(p.bound, std::sqrt(d2));
    }
    p.verts = std::move(pts);
    return;
  }
  throw InputError(who + ": could not draw a convex polyhedron of " + std::to_string(n) + " vertices");
}

}  // namespace

bool sphere_hull(const std::vector<double>& p, std::vector<int>& tris) {
  const int n = static_cast<int>(p.size() / 3);
  tris.clear();
  auto P = [&](int i) { return &p[3 * static_cast<std::size_t>(i)]; };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        const double *a = P(i), *b = P(j), *c = P(k);
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                               u[0] * v[1] - u[1] * v[0]};
        const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (!(len > 1e-12)) return false;
        int above = 0, below = 0, on = 0;
        for (int l = 0; l < n; ++l) {
          if (l == i || l == j || l == k) continue;
          const double* q = P(l);
          const double d = ((q[0] - a[0]) * nrm[0] + (q[1] - a[1]) * nrm[1] + (q[2] - a[2]) * nrm[2]) / len;
          if (d > 1e-9)
            ++above;
          else if (d < -1e-9)
            ++below;
          else
            ++on;
        }
        if (above && below) continue;
        if (on) return false;  // four points on one face: not a triangulated hull
        if (above)
          tris.insert(tris.end(), {i, k, j});  // the others lie on the normal's side: flip
        else
          tris.insert(tris.end(), {i, j, k});
      }
  return n >= 4 && static_cast<int>(tris.size()) == 3 * (2 * n - 4);
}

double hull_volume(const std::vector<double>& p, const std::vector<int>& tris) {
  double v = 0;
  for (std::size_t t = 0; t + 2 < tris.size(); t += 3) {
    const double *a = &p[3 * tris[t]], *b = &p[3 * tris[t + 1]], *c = &p[3 * tris[t + 2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6.0;
  }
  return v;
}

namespace {

// The spec's keys in range; throws InputError naming `who`.
void check_particle_spec(const ParticleSpec& s, const std::string& who) {
  if (s.count < 1 || s.count > 100000)
    throw InputError(who + ": count must be in 1 .. 100000 (got " + std::to_string(s.count) + ")");
  if (!(s.rmin > 0) || !(s.rmax >= s.rmin) || !std::isfinite(s.rmax))
    throw InputError(who + ": radius must be [rmin, rmax] with 0 < rmin <= rmax (got [" + fmt(s.rmin) + ", " +
                     fmt(s.rmax) + "])");
  if (s.shape != "sphere" && s.shape != "ellipsoid" && s.shape != "polyhedron")
    throw InputError(who + ": unknown shape '" + s.shape + "' (allowed: sphere, ellipsoid, polyhedron)");
  if (!(s.ratio_min > 0) || !(s.ratio_max >= s.ratio_min) || !(s.ratio_max <= 1))
    throw InputError(who + ": axis_ratio must be [lo, hi] with 0 < lo <= hi <= 1");
  if (s.vertices < 6 || s.vertices > 60)
    throw InputError(who + ": vertices must be in 6 .. 60 (got " + std::to_string(s.vertices) + ")");
  if (!(s.gap >= 0)) throw InputError(who + ": gap must be >= 0 (got " + fmt(s.gap) + ")");
  for (int k = 0; k < 3; ++k)
    if (!(s.box_size[k] > 0) || !std::isfinite(s.box_size[k]))
      throw InputError(who + ": box.size must be positive in x, y and z");
}

// Sizes, orientations and shapes of s.count particles drawn from `rng`, the largest bounding
// sphere first (shapes before positions: a larger box keeps the shapes).
std::vector<Particle> draw_shapes(const ParticleSpec& s, Rng& rng, const std::string& who) {
  std::vector<Particle> ps(s.count);
  for (Particle& p : ps) {
    p.radius = s.rmin == s.rmax ? s.rmin : rng.uniform(s.rmin, s.rmax);
    p.rot = random_rotation(rng);
    if (s.shape == "sphere") {
      p.axes = {p.radius, p.radius, p.radius};
      p.bound = p.radius;
    } else if (s.shape == "ellipsoid") {
      double rb = rng.uniform(s.ratio_min, s.ratio_max), rc = rng.uniform(s.ratio_min, s.ratio_max);
      if (rc > rb) std::swap(rb, rc);
      const double a = p.radius / std::cbrt(rb * rc);
      p.axes = {a, a * rb, a * rc};
      p.bound = a;
    } else {
      random_polyhedron(rng, s.vertices, p.radius, p, who);
    }
  }
  std::stable_sort(ps.begin(), ps.end(),
                   [](const Particle& a, const Particle& b) { return a.bound > b.bound; });
  return ps;
}

// Grid over the box of cells at least one largest interaction distance (`reach`) wide: a
// particle's neighbours lie in the 27 cells around its own. Each cell lists the particles placed
// in it.
struct CellGrid {
  std::array<double, 3> origin{};
  std::array<int, 3> nc{};
  std::array<double, 3> cell{};
  std::vector<std::vector<int>> cells;
  CellGrid(const ParticleSpec& s, double reach) : origin(s.box_origin) {
    for (int k = 0; k < 3; ++k) {
      nc[k] = std::max(1, std::min(200, static_cast<int>(s.box_size[k] / reach)));
      cell[k] = s.box_size[k] / nc[k];
    }
    cells.resize(static_cast<std::size_t>(nc[0]) * nc[1] * nc[2]);
  }
  int cell_of(const std::array<double, 3>& x, int k) const {
    return std::min(nc[k] - 1, std::max(0, static_cast<int>((x[k] - origin[k]) / cell[k])));
  }
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * nc[1] + y) * nc[0] + x;
  }
  // Particle i, centred at x, listed in its cell.
  void add(int i, const std::array<double, 3>& x) {
    cells[index(cell_of(x, 0), cell_of(x, 1), cell_of(x, 2))].push_back(i);
  }
};

// Whether `p` keeps at least `gap` of clearance (by bounding spheres) from every particle of `ps`
// placed in `grid`.
bool is_free(const CellGrid& grid, const std::vector<Particle>& ps, const Particle& p, double gap) {
  const auto& nc = grid.nc;
  const int cx = grid.cell_of(p.centre, 0), cy = grid.cell_of(p.centre, 1), cz = grid.cell_of(p.centre, 2);
  bool free = true;
  for (int x = std::max(0, cx - 1); free && x <= std::min(nc[0] - 1, cx + 1); ++x)
    for (int y = std::max(0, cy - 1); free && y <= std::min(nc[1] - 1, cy + 1); ++y)
      for (int z = std::max(0, cz - 1); free && z <= std::min(nc[2] - 1, cz + 1); ++z)
        for (int j : grid.cells[grid.index(x, y, z)]) {
          const Particle& q = ps[j];
          double d2 = 0;
          for (int k = 0; k < 3; ++k) d2 += (p.centre[k] - q.centre[k]) * (p.centre[k] - q.centre[k]);
          const double need = p.bound + q.bound + gap;
          if (d2 < need * need) {
            free = false;
            break;
          }
        }
  return free;
}

// Random sequential addition: each particle of out.particles in turn (largest first) at random
// centres in the box until one is free; fills the volume fractions. Throws InputError naming
// `who` when the largest particle does not fit in the box or when a particle finds no place.
void place_by_random_addition(const ParticleSpec& s, Rng& rng, Placement& out, const std::string& who) {
  std::vector<Particle>& ps = out.particles;
  const double bmax = ps.front().bound;
  for (int k = 0; k < 3; ++k)
    if (s.box_size[k] < 2 * bmax)
      throw InputError(who + ": the largest particle (bounding radius " + fmt(bmax) +
                       " m) does not fit in box.size " + fmt(s.box_size[k]) + " m along " + "xyz"[k] +
                       "; give a larger mesh.box or smaller mesh.radius");
  CellGrid grid(s, 2 * bmax + s.gap);
  const long max_tries = 20000;
  double vsolid = 0, vbound = 0;
  const double vbox = s.box_size[0] * s.box_size[1] * s.box_size[2];
  for (int i = 0; i < s.count; ++i) {
    Particle& p = ps[i];
    bool placed = false;
    for (long t = 0; t < max_tries && !placed; ++t) {
      for (int k = 0; k < 3; ++k)
        p.centre[k] = rng.uniform(s.box_origin[k] + p.bound, s.box_origin[k] + s.box_size[k] - p.bound);
      if (is_free(grid, ps, p, s.gap)) {
        grid.add(i, p.centre);
        placed = true;
      }
    }
    if (!placed)
      throw InputError(who + ": placed only " + std::to_string(i) + " of " + std::to_string(s.count) +
                       " particles in mesh.box (" + std::to_string(max_tries) +
                       " random tries for the next one failed): the particles fill " + fmt(vsolid / vbox) +
                       " of the box volume, their bounding spheres " + fmt(vbound / vbox) +
                       " (random sequential addition jams near 0.38 for spheres); give a larger mesh.box, "
                       "a smaller mesh.count, mesh.radius or mesh.gap");
    vsolid += 4.0 / 3.0 * kPi * p.radius * p.radius * p.radius;
    vbound += 4.0 / 3.0 * kPi * p.bound * p.bound * p.bound;
  }
  out.solid_fraction = vsolid / vbox;
  out.bound_fraction = vbound / vbox;
}

}  // namespace

// Three phases: the spec's checks, the shapes, their placement.
Placement place_particles(const ParticleSpec& s, const std::string& who) {
  check_particle_spec(s, who);
  Rng rng(s.seed);
  Placement out;
  out.particles = draw_shapes(s, rng, who);
  place_by_random_addition(s, rng, out, who);
  return out;
}

namespace {

// Gmsh OpenCASCADE volume of one particle; returns its tag.
int add_particle(const Particle& p, const std::string& shape) {
  namespace occ = gmsh::model::occ;
  const auto& R = p.rot;
  const auto& c = p.centre;
  if (shape == "sphere") return occ::addSphere(c[0], c[1], c[2], p.radius);
  if (shape == "ellipsoid") {
    const int v = occ::addSphere(0, 0, 0, 1);
    const auto& a = p.axes;
    occ::affineTransform({{3, v}}, {R[0] * a[0], R[1] * a[1], R[2] * a[2], c[0],  //
                                    R[3] * a[0], R[4] * a[1], R[5] * a[2], c[1],  //
                                    R[6] * a[0], R[7] * a[1], R[8] * a[2], c[2]});
    return v;
  }
  const int n = static_cast<int>(p.verts.size() / 3);
  std::vector<int> pt(n);
  for (int i = 0; i < n; ++i) {
    const double* v = &p.verts[3 * static_cast<std::size_t>(i)];
    pt[i] = occ::addPoint(c[0] + R[0] * v[0] + R[1] * v[1] + R[2] * v[2],
                          c[1] + R[3] * v[0] + R[4] * v[1] + R[5] * v[2],
                          c[2] + R[6] * v[0] + R[7] * v[1] + R[8] * v[2]);
  }
  std::map<std::pair<int, int>, int> lines;  // each edge once, shared by its two faces
  auto line = [&](int a, int b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    auto it = lines.find(key);
    if (it == lines.end()) it = lines.emplace(key, occ::addLine(pt[key.first], pt[key.second])).first;
    return it->second;
  };
  std::vector<int> faces;
  for (std::size_t t = 0; t + 2 < p.tris.size(); t += 3) {
    const int a = p.tris[t], b = p.tris[t + 1], d = p.tris[t + 2];
    const int loop = occ::addCurveLoop({line(a, b), line(b, d), line(d, a)});
    faces.push_back(occ::addPlaneSurface({loop}));
  }
  return occ::addVolume({occ::addSurfaceLoop(faces)});
}

// Smallest half-width: the shortest semi-axis, or a polyhedron's least distance from its centre
// (the vertices' mean) to a face plane.
double half_width(const Particle& p, const std::string& shape) {
  if (shape != "polyhedron") return p.axes[2];
  double w = p.bound;
  for (std::size_t t = 0; t + 2 < p.tris.size(); t += 3) {
    const double *a = &p.verts[3 * p.tris[t]], *b = &p.verts[3 * p.tris[t + 1]],
                 *c = &p.verts[3 * p.tris[t + 2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
                 v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0) w = std::min(w, std::abs(a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / len);
  }
  return w;
}

// `b` appended to `a` as separate bodies: node ids shifted, regions, node and face sets joined by name.
void append_mesh(HostMesh& a, const HostMesh& b) {
  if (a.X.empty()) {
    a = b;
    return;
  }
  const int off = a.num_nodes();
  a.X.insert(a.X.end(), b.X.begin(), b.X.end());
  for (int v : b.elems) a.elems.push_back(v + off);
  for (int r : b.elem_region) {
    int ra = a.region_index(b.region_names[r]);
    if (ra < 0) {
      ra = static_cast<int>(a.region_names.size());
      a.region_names.push_back(b.region_names[r]);
    }
    a.elem_region.push_back(ra);
  }
  for (const auto& [name, set] : b.node_sets)
    for (int v : set) a.node_sets[name].push_back(v + off);
  for (const auto& [name, set] : b.face_sets)
    for (int v : set) a.face_sets[name].push_back(v + off);
  for (int v : b.node_origin) a.node_origin.push_back(v + off);
  a.warnings.insert(a.warnings.end(), b.warnings.begin(), b.warnings.end());
}

}  // namespace

HostMesh generate_particles(const ParticleSpec& s, double h, const std::string& region) {
  const std::string who = "particles generator";
  const Placement pl = place_particles(s, who);
  if (!(h > 0) || !std::isfinite(h))
    throw InputError(who + ": element_size must be positive (got " + fmt(h) + ")");
  double rsmall = pl.particles.back().radius, vsolid = 0;
  for (const Particle& p : pl.particles) {
    rsmall = std::min(rsmall, half_width(p, s.shape));
    vsolid += 4.0 / 3.0 * kPi * p.radius * p.radius * p.radius;
  }
  if (h > 2 * rsmall)
    throw InputError(who + ": element_size " + fmt(h) + " m is larger than the thinnest particle's width " +
                     fmt(2 * rsmall) + " m; give mesh.element_size <= " + fmt(2 * rsmall));
  if (s.rmax / h > 200)
    throw InputError(who + ": radius / element_size = " + fmt(s.rmax / h) +
                     " is above the limit 200: give mesh.element_size >= " + fmt(s.rmax / 200));
  check_fits_in_memory(estimate_gmsh_elements(3, vsolid, h), 3,
                       "mesh.element_size = " + fmt(h) + " m (" + std::to_string(s.count) + " particles)", h,
                       "mesh.element_size", estimate_gmsh_elements(3, vsolid, 1.0));
  const std::string rname = region.empty() ? std::string("particles") : region;
  // Batches of s.batch particles, one Gmsh session each: Gmsh's 3D meshing of one volume takes
  // time in proportion to the whole model, so one session for all N particles costs O(N^2)
  // (1000 spheres: ~0.7 s per volume against ~0.05 s with 100); batches keep it linear.
  HostMesh all;
  const int n = static_cast<int>(pl.particles.size()), batch = std::max(1, s.batch);
  for (int first = 0; first < n; first += batch) {
    const int last = std::min(n, first + batch);
    HostMesh part =
        mesh_detail::generate_with_gmsh(who, "mesh the particles", 3, h, s.mesher == "hxt" ? 10 : 1, [&] {
          gmsh::model::add("particles");
          if (s.threads > 1) {  // surfaces and volumes meshed in parallel (Gmsh's OpenMP)
            gmsh::option::setNumber("General.NumThreads", s.threads);
            gmsh::option::setNumber("Mesh.MaxNumThreads2D", s.threads);
            gmsh::option::setNumber("Mesh.MaxNumThreads3D", s.threads);
          }
          std::vector<int> vols;
          for (int i = first; i < last; ++i) vols.push_back(add_particle(pl.particles[i], s.shape));
          gmsh::model::occ::synchronize();
          gmsh::vectorpair vt, bnd;
          for (int v : vols) vt.push_back({3, v});
          gmsh::model::getBoundary(vt, bnd, false, false, false);
          std::vector<int> surfs;
          for (const auto& [d, t] : bnd) surfs.push_back(std::abs(t));
          std::sort(surfs.begin(), surfs.end());
          surfs.erase(std::unique(surfs.begin(), surfs.end()), surfs.end());
          const int pv = gmsh::model::addPhysicalGroup(3, vols);
          gmsh::model::setPhysicalName(3, pv, rname);
          const int ps = gmsh::model::addPhysicalGroup(2, surfs);
          gmsh::model::setPhysicalName(2, ps, "surface");
        });
    append_mesh(all, part);
  }
  return all;
}

}  // namespace fdem
