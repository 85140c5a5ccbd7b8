// Grain-based specimens in 3D: the Voronoi tessellation of a box (plain geometry) and its mesh
// through Gmsh's built-in kernel (src/mesh/grains.hpp).
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/error.hpp"
#include "mesh/grains.hpp"
#include "mesh/grains_internal.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

namespace {

using P3 = std::array<double, 3>;
// Lloyd's relaxation: each seed moved to its cell's centroid this many times before the final
// tessellation (rounder grains, far fewer short edges and thin faces than random seeds give).
constexpr int kLloydSteps = 4;

P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
P3 cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// A face of a cell while it is being clipped: its polygon and what made it (a neighbour's seed
// index >= 0, or -(k + 1) for the box's side k).
struct Face {
  std::vector<P3> pts;
  int id;
};

std::vector<Face> box_cell(const P3& lo, const P3& hi) {
  auto p = [&](int i, int j, int k) { return P3{i ? hi[0] : lo[0], j ? hi[1] : lo[1], k ? hi[2] : lo[2]}; };
  return {{{p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1)}, -1},
          {{p(1, 0, 0), p(1, 0, 1), p(1, 1, 1), p(1, 1, 0)}, -2},
          {{p(0, 0, 0), p(0, 0, 1), p(1, 0, 1), p(1, 0, 0)}, -3},
          {{p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1)}, -4},
          {{p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0)}, -5},
          {{p(0, 0, 1), p(0, 1, 1), p(1, 1, 1), p(1, 0, 1)}, -6}};
}

// The part of a convex polyhedron where n . x <= c (n of unit length); the cut becomes face `id`.
std::vector<Face> clip(const std::vector<Face>& poly, const P3& n, double c, int id, double eps) {
  std::vector<Face> out;
  std::vector<P3> cap;
  for (const Face& f : poly) {
    std::vector<P3> q;
    const size_t m = f.pts.size();
    for (size_t i = 0; i < m; ++i) {
      const P3& a = f.pts[i];
      const P3& b = f.pts[(i + 1) % m];
      const double da = dot(n, a) - c, db = dot(n, b) - c;
      if (da <= eps) q.push_back(a);
      if (std::abs(da) <= eps) cap.push_back(a);
      if ((da < -eps && db > eps) || (da > eps && db < -eps)) {
        const double t = da / (da - db);
        const P3 p{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
        q.push_back(p);
        cap.push_back(p);
      }
    }
    if (q.size() >= 3) out.push_back({q, f.id});
  }
  std::vector<P3> u;  // the cap's distinct points
  for (const P3& p : cap) {
    bool dup = false;
    for (const P3& v : u) dup = dup || std::sqrt(dot(sub(p, v), sub(p, v))) <= 10 * eps;
    if (!dup) u.push_back(p);
  }
  if (u.size() < 3) return out;
  P3 cc{0, 0, 0};
  for (const P3& p : u)
    for (int k = 0; k < 3; ++k) cc[k] += p[k] / static_cast<double>(u.size());
  const P3 any = std::abs(n[0]) < 0.9 ? P3{1, 0, 0} : P3{0, 1, 0};
  P3 e1 = cross(n, any);
  const double l1 = std::sqrt(dot(e1, e1));
  for (double& x : e1) x /= l1;
  const P3 e2 = cross(n, e1);
  std::sort(u.begin(), u.end(), [&](const P3& a, const P3& b) {
    return std::atan2(dot(sub(a, cc), e2), dot(sub(a, cc), e1)) <
           std::atan2(dot(sub(b, cc), e2), dot(sub(b, cc), e1));
  });
  out.push_back({u, id});
  return out;
}

std::vector<Face> voronoi_cell(const std::vector<P3>& seeds, int i, const P3& lo, const P3& hi, double eps) {
  std::vector<Face> poly = box_cell(lo, hi);
  const P3 p = seeds[i];
  std::vector<std::pair<double, int>> order;
  for (int j = 0; j < static_cast<int>(seeds.size()); ++j)
    if (j != i) order.push_back({std::sqrt(dot(sub(seeds[j], p), sub(seeds[j], p))), j});
  std::sort(order.begin(), order.end());
  for (const auto& [dist, j] : order) {
    double reach = 0;
    for (const Face& f : poly)
      for (const P3& v : f.pts) reach = std::max(reach, std::sqrt(dot(sub(v, p), sub(v, p))));
    if (dist > 2 * reach) break;
    P3 n = sub(seeds[j], p);
    for (double& x : n) x /= dist;
    const P3 mid{0.5 * (p[0] + seeds[j][0]), 0.5 * (p[1] + seeds[j][1]), 0.5 * (p[2] + seeds[j][2])};
    poly = clip(poly, n, dot(n, mid), j, eps);
  }
  return poly;
}

// Centroid of a convex cell: tetrahedra from `inside` to the fan of each face.
P3 centroid(const std::vector<Face>& cell, const P3& inside) {
  P3 c{0, 0, 0};
  double vol = 0;
  for (const Face& f : cell) {
    P3 m{0, 0, 0};
    for (const P3& p : f.pts)
      for (int k = 0; k < 3; ++k) m[k] += p[k] / static_cast<double>(f.pts.size());
    for (size_t a = 0; a < f.pts.size(); ++a) {
      const P3& b = f.pts[a];
      const P3& e = f.pts[(a + 1) % f.pts.size()];
      const double v = std::abs(dot(sub(m, inside), cross(sub(b, inside), sub(e, inside)))) / 6;
      for (int k = 0; k < 3; ++k) c[k] += v * (inside[k] + m[k] + b[k] + e[k]) / 4;
      vol += v;
    }
  }
  for (double& x : c) x /= vol;
  return c;
}

// Merged vertex id of every point of every face of every cell (in that order), vertices closer
// than tol merged (their mean, kept on the box's sides where a member lies on one).
std::vector<int> merge_points(const std::vector<std::vector<Face>>& cells, double tol, const P3& lo,
                              const P3& hi, std::vector<P3>& verts) {
  std::vector<P3> all;
  for (const auto& c : cells)
    for (const Face& f : c) all.insert(all.end(), f.pts.begin(), f.pts.end());
  const int n = static_cast<int>(all.size());
  mesh_detail::UnionFind uf(n);
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  auto cell_of = [&](const P3& x, int k) {
    return static_cast<std::int64_t>(std::floor((x[k] - lo[k]) / tol));
  };
  auto key = [](std::int64_t a, std::int64_t b, std::int64_t c) { return (a * 1000003 + b) * 1000033 + c; };
  for (int i = 0; i < n; ++i) {
    const std::int64_t g[3] = {cell_of(all[i], 0), cell_of(all[i], 1), cell_of(all[i], 2)};
    for (std::int64_t a = g[0] - 1; a <= g[0] + 1; ++a)
      for (std::int64_t b = g[1] - 1; b <= g[1] + 1; ++b)
        for (std::int64_t c = g[2] - 1; c <= g[2] + 1; ++c) {
          auto it = grid.find(key(a, b, c));
          if (it == grid.end()) continue;
          for (int j : it->second)
            if (std::sqrt(dot(sub(all[i], all[j]), sub(all[i], all[j]))) < tol) uf.join(i, j);
        }
    grid[key(g[0], g[1], g[2])].push_back(i);
  }
  const double eps = 1e-9 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  std::vector<int> id(n, -1), count;
  std::vector<P3> sum;
  std::vector<std::array<int, 6>> side;
  for (int i = 0; i < n; ++i) {
    const int r = uf.find(i);
    if (id[r] < 0) {
      id[r] = static_cast<int>(sum.size());
      sum.push_back({0, 0, 0});
      side.push_back({0, 0, 0, 0, 0, 0});
      count.push_back(0);
    }
    const int v = id[r];
    id[i] = v;
    for (int k = 0; k < 3; ++k) {
      sum[v][k] += all[i][k];
      side[v][2 * k] |= std::abs(all[i][k] - lo[k]) < eps;
      side[v][2 * k + 1] |= std::abs(all[i][k] - hi[k]) < eps;
    }
    ++count[v];
  }
  verts.resize(sum.size());
  for (size_t v = 0; v < sum.size(); ++v)
    for (int k = 0; k < 3; ++k) {
      verts[v][k] = sum[v][k] / count[v];
      if (side[v][2 * k]) verts[v][k] = lo[k];
      if (side[v][2 * k + 1]) verts[v][k] = hi[k];
    }
  for (int i = 0; i < n; ++i) id[i] = id[uf.find(i)];
  return id;
}

}  // namespace

GrainTessellation3 tessellate_grains_3d(const MeshSpec& s) {
  const std::string who = "grains generator";
  if (s.shape != "box") throw InputError(who + ": unknown 3D shape '" + s.shape + "' (allowed: box)");
  const double d = s.grain_size, h = s.element_size;
  if (!(d > 0) || !(h > 0)) throw InputError(who + ": grain_size and element_size must be positive");
  if (d < 2 * h)
    throw InputError(who + ": grain_size " + mesh_detail::fmt(d) + " m is less than twice the element_size " +
                     mesh_detail::fmt(h) + " m (give grain_size >= " + mesh_detail::fmt(2 * h) + ")");
  const P3 lo = s.origin, hi{s.origin[0] + s.size[0], s.origin[1] + s.size[1], s.origin[2] + s.size[2]};
  GrainTessellation3 g;
  g.seeds = grain_detail::draw_seeds(3, lo.data(), hi.data(), s.size[0] * s.size[1] * s.size[2], d, s.seed,
                                     who, [](const P3&) { return true; });
  const double eps = 1e-12 * std::max({s.size[0], s.size[1], s.size[2]});
  std::vector<std::vector<Face>> cells;
  for (int it = 0; it <= kLloydSteps; ++it) {
    cells.clear();
    for (int i = 0; i < static_cast<int>(g.seeds.size()); ++i)
      cells.push_back(voronoi_cell(g.seeds, i, lo, hi, eps));
    if (it < kLloydSteps)
      for (size_t i = 0; i < cells.size(); ++i) g.seeds[i] = centroid(cells[i], g.seeds[i]);
  }
  const std::vector<int> id = merge_points(cells, std::min(h / 3, 0.15 * d), lo, hi, g.vertices);
  // Faces once each: between grains i < j keyed (i, j), on the box (grain, side).
  std::map<std::pair<int, int>, int> face_of;
  size_t k = 0;
  long mismatched = 0;
  for (int c = 0; c < static_cast<int>(cells.size()); ++c) {
    std::vector<int> mine;
    for (const Face& f : cells[c]) {
      std::vector<int> loop;
      for (size_t a = 0; a < f.pts.size(); ++a, ++k)
        if (loop.empty() || loop.back() != id[k]) loop.push_back(id[k]);
      while (loop.size() > 1 && loop.back() == loop.front()) loop.pop_back();
      if (loop.size() < 3) continue;  // collapsed by the merge
      const auto key =
          f.id >= 0 ? std::make_pair(std::min(c, f.id), std::max(c, f.id)) : std::make_pair(c, f.id);
      auto it = face_of.find(key);
      if (it == face_of.end()) {
        it = face_of.emplace(key, static_cast<int>(g.faces.size())).first;
        g.faces.push_back(loop);
        g.face_side.push_back(f.id >= 0 ? -1 : -f.id - 1);
      } else {
        std::vector<int> a = loop, b = g.faces[it->second];
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        mismatched += a != b;
      }
      mine.push_back(it->second);
    }
    g.cells.push_back(mine);
  }
  if (mismatched)
    throw InputError(who + ": " + std::to_string(mismatched) +
                     " grain faces came out differently on their two " +
                     "sides after merging close vertices; give another seed");
  // Volumes: tetrahedra from the seed to the fan of each face.
  for (size_t c = 0; c < g.cells.size(); ++c) {
    double v = 0;
    for (int f : g.cells[c]) {
      const auto& L = g.faces[f];
      P3 m{0, 0, 0};
      for (int i : L)
        for (int q = 0; q < 3; ++q) m[q] += g.vertices[i][q] / static_cast<double>(L.size());
      for (size_t a = 0; a < L.size(); ++a) {
        const P3 e1 = sub(g.vertices[L[a]], g.seeds[c]),
                 e2 = sub(g.vertices[L[(a + 1) % L.size()]], g.seeds[c]);
        v += std::abs(dot(sub(m, g.seeds[c]), cross(e1, e2))) / 6;
      }
    }
    g.volume.push_back(v);
  }
  grain_detail::assign_minerals(g.volume, s, who, g.mineral, g.minerals, g.mineral_volume);
  return g;
}

HostMesh generate_grains_3d(const MeshSpec& s) {
  const GrainTessellation3 g = tessellate_grains_3d(s);
  // Gmsh's Delaunay (Algorithm3D 1) by default: the same mesh on every invocation, but with the many
  // internal faces of the grains it leaves slivers (minimum dihedral angle about 1 degree: a stable
  // time step about ten times smaller than the elements' size asks). HXT (10, one thread) keeps about
  // 5 degrees, but its mesh differs slightly from one invocation to the next (docs/case-format.md).
  if (s.mesher != "delaunay" && s.mesher != "hxt")
    throw InputError("grains generator: unknown mesher '" + s.mesher + "' (allowed: delaunay, hxt)");
  return mesh_detail::generate_with_gmsh(
      "grains generator", "mesh the grains", 3, s.element_size, s.mesher == "hxt" ? 10 : 1, [&] {
        namespace geo = gmsh::model::geo;
        gmsh::model::add("grains3d");
        std::vector<int> ptag(g.vertices.size(), 0);
        auto point = [&](int v) {
          if (!ptag[v]) ptag[v] = geo::addPoint(g.vertices[v][0], g.vertices[v][1], g.vertices[v][2]);
          return ptag[v];
        };
        std::map<std::pair<int, int>, int> lines;
        auto line = [&](int a, int b) {  // signed: from a to b
          const auto key = std::make_pair(std::min(a, b), std::max(a, b));
          auto it = lines.find(key);
          if (it == lines.end())
            it = lines.emplace(key, geo::addLine(point(key.first), point(key.second))).first;
          return a < b ? it->second : -it->second;
        };
        auto triangle = [&](int a, int b, int c) {
          return geo::addPlaneSurface({geo::addCurveLoop({line(a, b), line(b, c), line(c, a)})});
        };
        std::vector<std::vector<int>> face_tris(g.faces.size());
        std::vector<int> inner;
        std::map<std::string, std::vector<int>> sides;
        const char* side_names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
        for (size_t f = 0; f < g.faces.size(); ++f) {
          const auto& L = g.faces[f];
          if (L.size() == 3) {
            face_tris[f].push_back(triangle(L[0], L[1], L[2]));
          } else {  // a fan around the face's centre (planar pieces even where the merge bent the face)
            P3 m{0, 0, 0};
            for (int i : L)
              for (int q = 0; q < 3; ++q) m[q] += g.vertices[i][q] / static_cast<double>(L.size());
            const int centre = static_cast<int>(ptag.size());
            ptag.push_back(geo::addPoint(m[0], m[1], m[2]));
            for (size_t a = 0; a < L.size(); ++a) {
              const int b = L[(a + 1) % L.size()];
              face_tris[f].push_back(triangle(centre, L[a], b));
            }
          }
          auto& dest = g.face_side[f] < 0 ? inner : sides[side_names[g.face_side[f]]];
          dest.insert(dest.end(), face_tris[f].begin(), face_tris[f].end());
        }
        std::vector<std::vector<int>> by_mineral(g.minerals.size());
        for (size_t c = 0; c < g.cells.size(); ++c) {
          std::vector<int> surfs;
          for (int f : g.cells[c]) surfs.insert(surfs.end(), face_tris[f].begin(), face_tris[f].end());
          by_mineral[g.mineral[c]].push_back(geo::addVolume({geo::addSurfaceLoop(surfs)}));
        }
        geo::synchronize();
        for (size_t m = 0; m < g.minerals.size(); ++m)
          if (!by_mineral[m].empty())
            gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, by_mineral[m]), g.minerals[m]);
        std::vector<int> outer;
        for (const auto& [name, tags] : sides) outer.insert(outer.end(), tags.begin(), tags.end());
        auto group = [](const std::vector<int>& tags, const std::string& name) {
          if (!tags.empty()) gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, tags), name);
        };
        group(inner, "grain_boundaries");
        group(outer, "boundary");
        for (const auto& [name, tags] : sides) group(tags, name);
      });
}

}  // namespace fdem
