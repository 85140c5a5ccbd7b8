// Grain-based specimens (src/mesh/grains.hpp, docs/case-format.md "grains"): a Voronoi
// tessellation of a disc or a rectangle that tiles it exactly, minerals by area fraction, the same
// grains for the same seed, and its Gmsh mesh with one region per mineral and the grain boundaries
// as a named curve set.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/grains.hpp"
#include "mesh/mesh.hpp"

namespace {

using json = nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

fdem::MeshSpec disc_spec(unsigned long seed) {
  fdem::MeshSpec s;
  s.kind = "grains";
  s.shape = "disc";
  s.origin = {0.01, -0.02, 0};
  s.radius = 0.025;
  s.grain_size = 0.004;
  s.element_size = 0.0015;
  s.seed = seed;
  s.minerals = {{"biotite", 0.1}, {"feldspar", 0.55}, {"quartz", 0.35}};
  return s;
}

double loop_length_min(const fdem::GrainTessellation& g) {
  double m = 1e300;
  for (size_t c = 0; c < g.loops.size(); ++c)
    for (size_t k = 0; k < g.loops[c].size(); ++k) {
      const auto& p = g.vertices[g.loops[c][k]];
      const auto& q = g.vertices[g.loops[c][(k + 1) % g.loops[c].size()]];
      m = std::min(m, std::hypot(q[0] - p[0], q[1] - p[1]));
    }
  return m;
}

// Point in the straight-line polygon of a loop (crossing number).
bool inside_loop(const fdem::GrainTessellation& g, size_t c, const std::array<double, 2>& x) {
  bool in = false;
  const auto& L = g.loops[c];
  for (size_t k = 0, j = L.size() - 1; k < L.size(); j = k++) {
    const auto& a = g.vertices[L[k]];
    const auto& b = g.vertices[L[j]];
    if ((a[1] > x[1]) != (b[1] > x[1]) && x[0] < (b[0] - a[0]) * (x[1] - a[1]) / (b[1] - a[1]) + a[0])
      in = !in;
  }
  return in;
}

TEST(Grains, DiscTessellationTilesTheDiscWithMineralsByAreaFraction) {
  const fdem::MeshSpec s = disc_spec(7);
  const fdem::GrainTessellation g = fdem::tessellate_grains(s);
  const size_t n = g.loops.size();
  const double area = kPi * s.radius * s.radius;
  // as many grains as circles of diameter grain_size fill the disc (156), all kept
  EXPECT_EQ(n, static_cast<size_t>(std::lround(area / (0.25 * kPi * s.grain_size * s.grain_size))));
  double total = 0, largest = 0;
  for (double a : g.area) {
    EXPECT_GT(a, 0.0);
    total += a;
    largest = std::max(largest, a);
  }
  EXPECT_NEAR(total / area, 1.0, 1e-9);  // the grains tile the disc, arcs included
  // each seed in its grain: inside the loop's polygon or in the circular segment of one of its arcs
  for (size_t c = 0; c < n; ++c) {
    const auto& x = g.seeds[c];
    bool in = inside_loop(g, c, x);
    const auto& L = g.loops[c];
    for (size_t k = 0; k < L.size() && !in; ++k) {
      if (!g.arc[c][k]) continue;
      const auto& p = g.vertices[L[k]];
      const auto& q = g.vertices[L[(k + 1) % L.size()]];
      const double tx = q[0] - p[0], ty = q[1] - p[1], rx = x[0] - p[0], ry = x[1] - p[1];
      const double along = (tx * rx + ty * ry) / (tx * tx + ty * ty);
      in = tx * ry - ty * rx < 0 && along > 0 && along < 1 &&
           std::hypot(x[0] - s.origin[0], x[1] - s.origin[1]) < s.radius;
    }
    EXPECT_TRUE(in) << "grain " << c;
  }
  // each mineral's share within one grain's area of its fraction
  for (size_t m = 0; m < s.minerals.size(); ++m)
    EXPECT_NEAR(g.mineral_area[m] / total, s.minerals[m].second, largest / total) << s.minerals[m].first;
  // no grain boundary much shorter than an element (vertices closer than h / 3 are merged)
  const double shortest = loop_length_min(g);
  std::printf("grains: %zu, shortest segment %.3g h, largest grain %.3g of the disc\n", n,
              shortest / s.element_size, largest / total);
  EXPECT_GT(shortest, 0.1 * s.element_size);
  // every vertex of a grain on or inside the circle
  for (const auto& L : g.loops)
    for (int i : L) {
      const auto& v = g.vertices[i];
      EXPECT_LE(std::hypot(v[0] - s.origin[0], v[1] - s.origin[1]), s.radius * (1 + 1e-12));
    }
}

TEST(Grains, SameSeedSameGrainsOtherSeedOtherGrains) {
  const fdem::GrainTessellation a = fdem::tessellate_grains(disc_spec(3));
  const fdem::GrainTessellation b = fdem::tessellate_grains(disc_spec(3));
  const fdem::GrainTessellation c = fdem::tessellate_grains(disc_spec(4));
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.loops, b.loops);
  EXPECT_EQ(a.mineral, b.mineral);
  EXPECT_NE(a.vertices, c.vertices);
}

TEST(Grains, RectangleMeshHasARegionPerMineralAndTheGrainBoundaries) {
  fdem::MeshSpec s;
  s.kind = "grains";
  s.shape = "rectangle";
  s.origin = {0, 0, 0};
  s.size = {0.02, 0.04, 0};
  s.grain_size = 0.005;
  s.element_size = 0.0015;
  s.seed = 11;
  s.minerals = {{"a", 0.5}, {"b", 0.5}};
  const fdem::GrainTessellation g = fdem::tessellate_grains(s);
  double total = 0;
  for (double a : g.area) total += a;
  EXPECT_NEAR(total, 0.02 * 0.04, 1e-15);
  const fdem::HostMesh m = fdem::build_mesh(s, 2);
  ASSERT_EQ(m.region_names.size(), 2u);
  // the mesh's area per region is each mineral's area (straight boundaries: exact to round-off)
  std::map<std::string, double> area;
  for (int e = 0; e < m.num_elems(); ++e) {
    const int* n = &m.elems[3 * e];
    const double* x = m.X.data();
    area[m.region_names[m.elem_region[e]]] +=
        0.5 * ((x[2 * n[1]] - x[2 * n[0]]) * (x[2 * n[2] + 1] - x[2 * n[0] + 1]) -
               (x[2 * n[2]] - x[2 * n[0]]) * (x[2 * n[1] + 1] - x[2 * n[0] + 1]));
  }
  for (size_t k = 0; k < 2; ++k) EXPECT_NEAR(area.at(g.minerals[k]), g.mineral_area[k], 1e-12);
  for (const char* set : {"grain_boundaries", "boundary", "left", "right", "bottom", "top"})
    EXPECT_EQ(m.node_sets.count(set), 1u) << set;
  ASSERT_EQ(m.face_sets.count("grain_boundaries"), 1u);
  // cutting the grain boundaries only: one interface per grain-boundary facet
  fdem::HostMesh cut = m;
  fdem::insert_interfaces(cut, {false, false}, {"grain_boundaries"});
  EXPECT_EQ(cut.num_ifaces(), static_cast<int>(m.face_sets.at("grain_boundaries").size()) / 2);
  EXPECT_GT(cut.num_ifaces(), 0);
  // the left side: nodes at x = 0 only
  for (int i : m.node_sets.at("left")) EXPECT_EQ(m.X[2 * i], 0.0);
}

// 3D: Voronoi cells of a box after Lloyd's relaxation; the grains fill the box exactly, and the
// tetrahedra of each mineral's region have that mineral's volume.
TEST(Grains, BoxTessellationFillsTheBoxAndItsMeshKeepsTheMineralVolumes) {
  fdem::MeshSpec s;
  s.kind = "grains";
  s.shape = "box";
  s.origin = {0.01, 0, -0.01};
  s.size = {0.02, 0.015, 0.02};
  s.grain_size = 0.006;
  s.element_size = 0.002;
  s.seed = 5;
  s.minerals = {{"a", 0.3}, {"b", 0.7}};
  const fdem::GrainTessellation3 g = fdem::tessellate_grains_3d(s);
  const double box = 0.02 * 0.015 * 0.02;
  double total = 0, largest = 0;
  for (double v : g.volume) {
    total += v;
    largest = std::max(largest, v);
  }
  EXPECT_EQ(g.cells.size(), static_cast<size_t>(std::lround(box / (kPi / 6 * 0.006 * 0.006 * 0.006))));
  EXPECT_NEAR(total / box, 1.0, 1e-9);
  for (size_t m = 0; m < 2; ++m)
    EXPECT_NEAR(g.mineral_volume[m] / total, s.minerals[m].second, largest / total);
  // every face between two grains belongs to exactly two cells, every face on the box to one
  std::vector<int> uses(g.faces.size(), 0);
  for (const auto& c : g.cells)
    for (int f : c) ++uses[f];
  for (size_t f = 0; f < g.faces.size(); ++f) EXPECT_EQ(uses[f], g.face_side[f] < 0 ? 2 : 1) << "face " << f;
  s.mesher = "hxt";  // the default (delaunay) leaves slivers of about 1 degree here
  const fdem::HostMesh m = fdem::build_mesh(s, 3);
  std::map<std::string, double> vol;
  for (int e = 0; e < m.num_elems(); ++e) {
    const int* n = &m.elems[4 * e];
    double a[3][3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) a[r][k] = m.X[3 * n[r + 1] + k] - m.X[3 * n[0] + k];
    vol[m.region_names[m.elem_region[e]]] += (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                                              a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                                              a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) /
                                             6;
  }
  for (size_t k = 0; k < 2; ++k) EXPECT_NEAR(vol.at(g.minerals[k]) / g.mineral_volume[k], 1.0, 1e-9);
  for (const char* set : {"grain_boundaries", "boundary", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax"})
    EXPECT_EQ(m.node_sets.count(set), 1u) << set;
  const fdem::MeshQuality q = fdem::mesh_quality(m);
  std::printf("3D grains: %zu, %d tetrahedra, min dihedral %.2f deg, shortest altitude %.3g h\n",
              g.cells.size(), m.num_elems(), q.min_angle_deg, q.min_size / s.element_size);
  EXPECT_GT(q.min_angle_deg, 3.0);
  EXPECT_GT(q.min_size, 0.05 * s.element_size);
}

// A mineral that gets no grain (its fraction under one grain of the specimen's) is refused by the
// generator, naming its key and what to do; it was reported as an unknown region in `regions`
// when the case gave it a material, and passed without a word when it did not.
TEST(Grains, MineralWithoutAGrainIsNamed) {
  fdem::MeshSpec s = disc_spec(1);
  s.radius = 0.02;
  s.grain_size = 0.008;
  s.element_size = 0.002;
  s.minerals = {{"quartz", 0.999}, {"mica", 0.001}};  // about 25 grains: none is mica
  std::string e = "<no error>";
  try {
    fdem::tessellate_grains(s);
  } catch (const fdem::InputError& err) {
    e = err.what();
  }
  for (const char* part : {"grains generator: mesh.minerals.mica: no grain is 'mica'", "fraction 0.001",
                           "give a grain_size below 0.00126", "about 1000 grains", "or remove 'mica'"})
    EXPECT_NE(e.find(part), std::string::npos) << part << " in: " << e;
  // in 3D as well; and a fraction that no grain count within the limit can honour
  fdem::MeshSpec b;
  b.kind = "grains";
  b.shape = "box";
  b.size = {0.02, 0.02, 0.02};
  b.grain_size = 0.008;
  b.element_size = 0.003;
  b.seed = 1;
  b.minerals = {{"a", 0.99999}, {"b", 0.00001}};
  e = "<no error>";
  try {
    fdem::tessellate_grains_3d(b);
  } catch (const fdem::InputError& err) {
    e = err.what();
  }
  EXPECT_NE(e.find("mesh.minerals.b: no grain is 'b'"), std::string::npos) << e;
  EXPECT_NE(e.find("no grain_size gives it one within the limit of 20000 grains: remove 'b'"),
            std::string::npos)
      << e;
}

// The bounds the messages give are possible ones: a huge grain_size gave "a grain_size below 0 m",
// an element_size whose double overflows "(allowed: >= inf)"; a specimen whose area underflows
// is named as such.
TEST(Grains, MessagesGivePossibleBounds) {
  auto error = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const fdem::InputError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  fdem::MeshSpec s = disc_spec(1);
  s.grain_size = 1e200;
  std::string e = error([&] { fdem::tessellate_grains(s); });
  EXPECT_NE(e.find("give a grain_size below 0.0353553 m (at least 2 grains)"), std::string::npos) << e;
  s = disc_spec(1);
  s.shape = "rectangle";
  s.size = {1e-200, 1e-200, 0};
  s.grain_size = 1e-200;
  s.element_size = 1e-201;
  e = error([&] { fdem::tessellate_grains(s); });
  EXPECT_NE(e.find("the specimen's area is 0 m^2, beyond double precision"), std::string::npos) << e;
  json d = json::parse(R"({"name": "g", "dimension": 2, "time": {"end_time": 1e-3},
    "mesh": {"generator": "grains", "shape": "disc", "radius": 0.02, "grain_size": 0.01, "element_size": 1e308},
    "materials": {"rock": {"density": 2700, "E": 3e10, "nu": 0.2}}, "regions": {"body": "rock"}})");
  e = error([&] { fdem::parse_case(d, "t.json", {}); });
  EXPECT_NE(e.find("mesh.element_size: value 1e+308 leaves no grain_size"), std::string::npos) << e;
  EXPECT_EQ(e.find("inf"), std::string::npos) << e;
}

TEST(Grains, CaseReaderNamesBadKeys) {
  const json doc = json::parse(R"({
    "name": "t", "dimension": 2,
    "mesh": {"generator": "grains", "shape": "disc", "radius": 0.02, "grain_size": 0.004,
             "element_size": 0.001, "minerals": {"q": 0.4, "f": 0.6}},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"q": "rock", "f": "rock"},
    "time": {"end_time": 1e-3}
  })");
  const fdem::Case c = fdem::parse_case(doc, "t.json", {});
  EXPECT_EQ(c.mesh.kind, "grains");
  EXPECT_EQ(c.mesh.seed, 1u);
  ASSERT_EQ(c.mesh.minerals.size(), 2u);
  auto error_of = [&](const std::string& key, const json& value) {
    json d = doc;
    if (value.is_null())
      d["mesh"].erase(key);
    else
      d["mesh"][key] = value;
    try {
      fdem::parse_case(d, "t.json", {});
    } catch (const fdem::InputError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  auto has = [](const std::string& msg, const std::string& part) {
    return msg.find(part) != std::string::npos;
  };
  std::string e = error_of("grain_size", 0.0015);
  EXPECT_TRUE(has(e, "mesh.grain_size") && has(e, "0.002")) << e;
  e = error_of("minerals", json{{"q", 0.4}, {"f", 0.5}});
  EXPECT_TRUE(has(e, "mesh.minerals") && has(e, "0.9")) << e;
  e = error_of("shape", "hexagon");
  EXPECT_TRUE(has(e, "mesh.shape") && has(e, "disc, rectangle")) << e;
  e = error_of("size", json::array({0.1, 0.1}));
  EXPECT_TRUE(has(e, "mesh.size") && has(e, "'rectangle' only")) << e;
  e = error_of("radius", json());
  EXPECT_TRUE(has(e, "mesh.radius")) << e;
  // too small a grain size for the specimen: the message gives the bound
  fdem::MeshSpec s = disc_spec(1);
  s.grain_size = 1e-6;
  s.element_size = 4e-7;
  try {
    fdem::tessellate_grains(s);
    ADD_FAILURE() << "no error";
  } catch (const fdem::InputError& err) {
    EXPECT_TRUE(has(err.what(), "limit 20000")) << err.what();
  }
}

}  // namespace
