// Grain-based specimens: the Voronoi tessellation (plain geometry) and its mesh through Gmsh
// (src/mesh/grains.hpp).
#include "mesh/grains.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/error.hpp"
#include "mesh/grains_internal.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem {

using mesh_detail::fmt;

namespace {

using P2 = std::array<double, 2>;
constexpr double kPi = 3.14159265358979323846;

struct Domain {
  bool disc = false;
  double cx = 0, cy = 0, R = 0;           // disc
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // rectangle, or the disc's bounding square
  double area() const { return disc ? kPi * R * R : (x1 - x0) * (y1 - y0); }
  bool inside(const P2& p) const {
    if (disc) return std::hypot(p[0] - cx, p[1] - cy) < R;
    return p[0] > x0 && p[0] < x1 && p[1] > y0 && p[1] < y1;
  }
};

// The part of a convex polygon where n . p <= c (Sutherland-Hodgman against one half-plane).
std::vector<P2> clip(const std::vector<P2>& poly, const P2& n, double c) {
  std::vector<P2> out;
  const size_t m = poly.size();
  for (size_t i = 0; i < m; ++i) {
    const P2& a = poly[i];
    const P2& b = poly[(i + 1) % m];
    const double da = n[0] * a[0] + n[1] * a[1] - c, db = n[0] * b[0] + n[1] * b[1] - c;
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
      const double t = da / (da - db);
      out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
    }
  }
  return out;
}

// Voronoi cell of seeds[i] in the box of dom, counter-clockwise.
std::vector<P2> voronoi_cell(const std::vector<P2>& seeds, int i, const Domain& dom) {
  std::vector<P2> poly{{dom.x0, dom.y0}, {dom.x1, dom.y0}, {dom.x1, dom.y1}, {dom.x0, dom.y1}};
  const P2 p = seeds[i];
  std::vector<std::pair<double, int>> order;
  order.reserve(seeds.size());
  for (int j = 0; j < static_cast<int>(seeds.size()); ++j)
    if (j != i) order.push_back({std::hypot(seeds[j][0] - p[0], seeds[j][1] - p[1]), j});
  std::sort(order.begin(), order.end());
  for (const auto& [dist, j] : order) {
    double reach = 0;  // a seed further than twice the cell's reach cannot cut it
    for (const P2& v : poly) reach = std::max(reach, std::hypot(v[0] - p[0], v[1] - p[1]));
    if (dist > 2 * reach) break;
    const P2 n{seeds[j][0] - p[0], seeds[j][1] - p[1]};
    poly = clip(poly, n, 0.5 * (n[0] * (p[0] + seeds[j][0]) + n[1] * (p[1] + seeds[j][1])));
  }
  return poly;
}

// Merge the cells' vertices closer than tol (a hash grid of cell size tol); returns per cell the
// loop of merged vertex ids (consecutive repeats removed) and fills `verts`.
std::vector<std::vector<int>> merge_vertices(const std::vector<std::vector<P2>>& cells, double tol,
                                             const Domain& dom, std::vector<P2>& verts) {
  std::vector<P2> all;
  for (const auto& c : cells) all.insert(all.end(), c.begin(), c.end());
  const int n = static_cast<int>(all.size());
  mesh_detail::UnionFind uf(n);
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  auto key = [&](long gx, long gy) { return gx * 4000037LL + gy; };
  auto cell_of = [&](double v, double o) { return static_cast<long>(std::floor((v - o) / tol)); };
  for (int i = 0; i < n; ++i) {
    const long gx = cell_of(all[i][0], dom.x0), gy = cell_of(all[i][1], dom.y0);
    for (long a = gx - 1; a <= gx + 1; ++a)
      for (long b = gy - 1; b <= gy + 1; ++b) {
        auto it = grid.find(key(a, b));
        if (it == grid.end()) continue;
        for (int j : it->second)
          if (std::hypot(all[i][0] - all[j][0], all[i][1] - all[j][1]) < tol) uf.join(i, j);
      }
    grid[key(gx, gy)].push_back(i);
  }
  // Position of a merged vertex: the mean, kept on the rectangle's sides where a member lies on one.
  const double eps = 1e-9 * std::max(dom.x1 - dom.x0, dom.y1 - dom.y0);
  std::vector<int> id(n, -1);
  std::vector<std::array<double, 3>> sum;
  std::vector<std::array<int, 4>> side;  // a member on x0, x1, y0, y1
  for (int i = 0; i < n; ++i) {
    const int r = uf.find(i);
    if (id[r] < 0) {
      id[r] = static_cast<int>(sum.size());
      sum.push_back({0, 0, 0});
      side.push_back({0, 0, 0, 0});
    }
    const int v = id[r];
    sum[v][0] += all[i][0];
    sum[v][1] += all[i][1];
    sum[v][2] += 1;
    if (!dom.disc) {
      side[v][0] |= std::abs(all[i][0] - dom.x0) < eps;
      side[v][1] |= std::abs(all[i][0] - dom.x1) < eps;
      side[v][2] |= std::abs(all[i][1] - dom.y0) < eps;
      side[v][3] |= std::abs(all[i][1] - dom.y1) < eps;
    }
  }
  verts.resize(sum.size());
  for (size_t v = 0; v < sum.size(); ++v) {
    P2 p{sum[v][0] / sum[v][2], sum[v][1] / sum[v][2]};
    if (side[v][0]) p[0] = dom.x0;
    if (side[v][1]) p[0] = dom.x1;
    if (side[v][2]) p[1] = dom.y0;
    if (side[v][3]) p[1] = dom.y1;
    if (dom.disc) {  // onto the circle when that close to it
      const double r = std::hypot(p[0] - dom.cx, p[1] - dom.cy);
      if (std::abs(r - dom.R) < tol)
        p = {dom.cx + (p[0] - dom.cx) * dom.R / r, dom.cy + (p[1] - dom.cy) * dom.R / r};
    }
    verts[v] = p;
  }
  std::vector<std::vector<int>> loops;
  int k = 0;
  for (const auto& c : cells) {
    std::vector<int> loop;
    for (size_t a = 0; a < c.size(); ++a, ++k) {
      const int v = id[uf.find(k)];
      if (loop.empty() || loop.back() != v) loop.push_back(v);
    }
    while (loop.size() > 1 && loop.back() == loop.front()) loop.pop_back();
    loops.push_back(loop);
  }
  return loops;
}

// Clip the merged loops to the disc's circle: the parts outside become arcs (see grains.hpp).
void clip_to_circle(GrainTessellation& g, const Domain& dom) {
  auto& V = g.vertices;
  const double eps = 1e-9 * dom.R;
  auto radius = [&](const P2& p) { return std::hypot(p[0] - dom.cx, p[1] - dom.cy); };
  auto outside = [&](const P2& p) { return radius(p) > dom.R + eps; };
  // Crossings of the edge (a, b), a < b, with the circle strictly between its ends, in order from a.
  std::map<std::pair<int, int>, std::vector<int>> crossings;
  auto cross = [&](int a, int b) -> const std::vector<int>& {
    auto it = crossings.find({a, b});
    if (it != crossings.end()) return it->second;
    std::vector<int> out;
    const P2 p = V[a], d{V[b][0] - V[a][0], V[b][1] - V[a][1]};
    const double A = d[0] * d[0] + d[1] * d[1], B = 2 * (d[0] * (p[0] - dom.cx) + d[1] * (p[1] - dom.cy));
    const double C = (p[0] - dom.cx) * (p[0] - dom.cx) + (p[1] - dom.cy) * (p[1] - dom.cy) - dom.R * dom.R;
    const double disc = B * B - 4 * A * C;
    if (disc > 0) {
      const double sq = std::sqrt(disc), tol_t = 1e-9;
      for (double t : {(-B - sq) / (2 * A), (-B + sq) / (2 * A)})
        if (t > tol_t && t < 1 - tol_t) {
          P2 q{p[0] + t * d[0], p[1] + t * d[1]};
          const double r = radius(q);
          q = {dom.cx + (q[0] - dom.cx) * dom.R / r, dom.cy + (q[1] - dom.cy) * dom.R / r};
          out.push_back(static_cast<int>(V.size()));
          V.push_back(q);
        }
    }
    return crossings.emplace(std::make_pair(a, b), out).first->second;
  };
  std::vector<std::vector<int>> loops;
  std::vector<std::vector<char>> arcs;
  std::vector<P2> seeds;
  for (size_t c = 0; c < g.loops.size(); ++c) {
    const auto& L = g.loops[c];
    const size_t n = L.size();
    std::vector<int> pts;
    std::vector<char> arc;
    bool pending = false, before_first = false;
    auto push = [&](int v) {
      if (!pts.empty() && pts.back() == v) return;
      if (pts.empty())
        before_first = pending;
      else
        arc.back() = pending;
      pending = false;
      pts.push_back(v);
      arc.push_back(0);
    };
    auto sub = [&](const P2& a, const P2& b) {  // a piece of an edge between two events
      if (outside({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])})) pending = true;
    };
    for (size_t k = 0; k < n; ++k) {
      const int a = L[k], b = L[(k + 1) % n];
      if (!outside(V[a])) push(a);
      std::vector<int> x = a < b ? cross(a, b) : cross(b, a);
      if (a > b) std::reverse(x.begin(), x.end());
      P2 prev = V[a];
      for (int q : x) {
        sub(prev, V[q]);
        push(q);
        prev = V[q];
      }
      sub(prev, V[b]);
    }
    if (pts.empty()) continue;  // outside the disc
    arc.back() = pending || before_first;
    if (pts.size() < 2 || (pts.size() == 2 && !arc[0] && !arc[1])) continue;  // degenerate sliver
    loops.push_back(pts);
    arcs.push_back(arc);
    seeds.push_back(g.seeds[c]);
  }
  g.loops = std::move(loops);
  g.arc = std::move(arcs);
  g.seeds = std::move(seeds);
}

// Counter-clockwise angle from p to q around the circle's centre, in (0, 2 pi].
double arc_angle(const Domain& dom, const P2& p, const P2& q) {
  double a = std::atan2(q[1] - dom.cy, q[0] - dom.cx) - std::atan2(p[1] - dom.cy, p[0] - dom.cx);
  while (a <= 0) a += 2 * kPi;
  return a;
}

// Arcs of a quarter turn or more split in pieces (Gmsh's arcs are less than half a turn).
void split_long_arcs(GrainTessellation& g, const Domain& dom) {
  for (size_t c = 0; c < g.loops.size(); ++c) {
    std::vector<int> pts;
    std::vector<char> arc;
    const auto& L = g.loops[c];
    for (size_t k = 0; k < L.size(); ++k) {
      pts.push_back(L[k]);
      arc.push_back(g.arc[c][k]);
      if (!g.arc[c][k]) continue;
      const P2 p = g.vertices[L[k]];
      const double th = arc_angle(dom, p, g.vertices[L[(k + 1) % L.size()]]);
      const int pieces = static_cast<int>(std::ceil(th / (0.5 * kPi) - 1e-9));
      const double a0 = std::atan2(p[1] - dom.cy, p[0] - dom.cx);
      for (int i = 1; i < pieces; ++i) {
        const double a = a0 + th * i / pieces;
        pts.push_back(static_cast<int>(g.vertices.size()));
        arc.push_back(1);
        g.vertices.push_back({dom.cx + dom.R * std::cos(a), dom.cy + dom.R * std::sin(a)});
      }
    }
    g.loops[c] = pts;
    g.arc[c] = arc;
  }
}

Domain domain_of(const MeshSpec& s) {
  Domain d;
  d.disc = s.shape == "disc";
  if (d.disc) {
    d.cx = s.origin[0];
    d.cy = s.origin[1];
    d.R = s.radius;
    d.x0 = d.cx - 1.05 * d.R;
    d.x1 = d.cx + 1.05 * d.R;
    d.y0 = d.cy - 1.05 * d.R;
    d.y1 = d.cy + 1.05 * d.R;
  } else {
    d.x0 = s.origin[0];
    d.y0 = s.origin[1];
    d.x1 = d.x0 + s.size[0];
    d.y1 = d.y0 + s.size[1];
  }
  return d;
}

}  // namespace

GrainTessellation tessellate_grains(const MeshSpec& s) {
  const std::string who = "grains generator";
  if (s.shape != "disc" && s.shape != "rectangle")
    throw InputError(who + ": unknown shape '" + s.shape + "' (allowed: disc, rectangle)");
  const double d = s.grain_size, h = s.element_size;
  if (!(d > 0) || !(h > 0)) throw InputError(who + ": grain_size and element_size must be positive");
  if (d < 2 * h)
    throw InputError(who + ": grain_size " + fmt(d) + " m is less than twice the element_size " + fmt(h) +
                     " m: a grain needs a few elements across (give grain_size >= " + fmt(2 * h) + ")");
  const Domain dom = domain_of(s);
  GrainTessellation g;
  {
    const double lo[3] = {dom.x0, dom.y0, 0}, hi[3] = {dom.x1, dom.y1, 0};
    for (const auto& p :
         grain_detail::draw_seeds(2, lo, hi, dom.area(), d, s.seed, who, [&](const std::array<double, 3>& x) {
           return dom.inside({x[0], x[1]});
         }))
      g.seeds.push_back({p[0], p[1]});
  }
  std::vector<std::vector<P2>> cells;
  for (int i = 0; i < static_cast<int>(g.seeds.size()); ++i) cells.push_back(voronoi_cell(g.seeds, i, dom));
  g.loops = merge_vertices(cells, std::min(h / 3, 0.15 * d), dom, g.vertices);
  g.arc.clear();
  for (const auto& L : g.loops) g.arc.emplace_back(L.size(), 0);
  if (dom.disc) {
    clip_to_circle(g, dom);
    split_long_arcs(g, dom);
  }
  for (const auto& L : g.loops)
    if (L.size() < 2)
      throw InputError(who + ": a grain collapsed while merging its vertices; give another seed");
  // Areas: the polygon of the loop plus the circular segments of its arcs.
  const size_t ng = g.loops.size();
  g.area.assign(ng, 0.0);
  for (size_t c = 0; c < ng; ++c) {
    const auto& L = g.loops[c];
    double a = 0;
    for (size_t k = 0; k < L.size(); ++k) {
      const P2 p = g.vertices[L[k]], q = g.vertices[L[(k + 1) % L.size()]];
      a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
      if (g.arc[c][k]) {
        const double th = arc_angle(dom, p, q);
        a += 0.5 * dom.R * dom.R * (th - std::sin(th));
      }
    }
    g.area[c] = a;
  }
  grain_detail::assign_minerals(g.area, s, who, g.mineral, g.minerals, g.mineral_area);
  return g;
}

HostMesh generate_grains(const MeshSpec& s) {
  const std::string who = "grains generator";
  const GrainTessellation g = tessellate_grains(s);
  const Domain dom = domain_of(s);
  return mesh_detail::generate_with_gmsh(who, "mesh the grains", 2, s.element_size, 1, [&] {
    namespace occ = gmsh::model::occ;
    gmsh::model::add("grains");
    std::vector<int> ptag(g.vertices.size(), 0);
    auto point = [&](int v) {
      if (!ptag[v]) ptag[v] = occ::addPoint(g.vertices[v][0], g.vertices[v][1], 0.0);
      return ptag[v];
    };
    const int centre = dom.disc ? occ::addPoint(dom.cx, dom.cy, 0.0) : 0;
    std::map<std::pair<int, int>, int> lines;  // shared by the two grains on either side
    std::map<int, int> uses;
    std::vector<int> outer;
    std::vector<std::vector<int>> by_mineral(g.minerals.size());
    for (size_t c = 0; c < g.loops.size(); ++c) {
      const auto& L = g.loops[c];
      std::vector<int> curves;
      for (size_t k = 0; k < L.size(); ++k) {
        const int a = L[k], b = L[(k + 1) % L.size()];
        if (g.arc[c][k]) {
          const int t = occ::addCircleArc(point(a), centre, point(b));
          outer.push_back(t);
          curves.push_back(t);
          continue;
        }
        const auto key = std::make_pair(std::min(a, b), std::max(a, b));
        auto it = lines.find(key);
        if (it == lines.end())
          it = lines.emplace(key, occ::addLine(point(key.first), point(key.second))).first;
        ++uses[it->second];
        curves.push_back(it->second);
      }
      const int loop = occ::addCurveLoop(curves);
      by_mineral[g.mineral[c]].push_back(occ::addPlaneSurface({loop}));
    }
    if (centre) occ::remove({{0, centre}});
    occ::synchronize();
    std::vector<int> inner;
    std::map<std::string, std::vector<int>> sides;
    const double eps = 1e-9 * std::max(dom.x1 - dom.x0, dom.y1 - dom.y0);
    for (const auto& [key, tag] : lines) {
      if (uses[tag] == 2) {
        inner.push_back(tag);
        continue;
      }
      outer.push_back(tag);
      const P2 p = g.vertices[key.first], q = g.vertices[key.second];
      if (dom.disc) continue;
      auto on = [&](int k, double v) { return std::abs(p[k] - v) < eps && std::abs(q[k] - v) < eps; };
      if (on(0, dom.x0)) sides["left"].push_back(tag);
      if (on(0, dom.x1)) sides["right"].push_back(tag);
      if (on(1, dom.y0)) sides["bottom"].push_back(tag);
      if (on(1, dom.y1)) sides["top"].push_back(tag);
    }
    for (size_t m = 0; m < g.minerals.size(); ++m) {
      if (by_mineral[m].empty()) continue;
      gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, by_mineral[m]), g.minerals[m]);
    }
    auto curve_group = [](const std::vector<int>& tags, const std::string& name) {
      if (!tags.empty()) gmsh::model::setPhysicalName(1, gmsh::model::addPhysicalGroup(1, tags), name);
    };
    curve_group(inner, "grain_boundaries");
    curve_group(outer, "boundary");
    for (const auto& [name, tags] : sides) curve_group(tags, name);
  });
}

}  // namespace fdem
