// Mesh generator "particles" (src/mesh/particles.cpp, reader src/io/case_particles.cpp): placement
// without overlap, reproducible from the seed, one body per particle, the particles' volumes, the
// reader's messages; fragments per initial body (src/solver/fragment_bodies.cpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "mesh/mesh_internal.hpp"
#include "mesh/particles.hpp"
#include "solver/fragment_bodies.hpp"
#include "solver/run.hpp"

namespace {

using fdem::HostMesh;
using fdem::InputError;
using fdem::ParticleSpec;
using json = nlohmann::json;
namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

ParticleSpec spheres(int n) {
  ParticleSpec s;
  s.count = n;
  s.rmin = 0.004;
  s.rmax = 0.008;
  s.box_origin = {-0.05, -0.05, 0.001};
  s.box_size = {0.1, 0.1, 0.06};
  s.gap = 0.0005;
  s.seed = 7;
  return s;
}

// Body of every element (elements joined through shared nodes) and the body count.
int bodies_of(const HostMesh& m, std::vector<int>& body) {
  fdem::UnionFind uf(m.num_nodes());
  for (int e = 0; e < m.num_elems(); ++e)
    for (int a = 1; a < 4; ++a) uf.join(m.elems[4 * e], m.elems[4 * e + a]);
  std::vector<int> id(m.num_nodes(), -1);
  int n = 0;
  body.resize(m.num_elems());
  for (int e = 0; e < m.num_elems(); ++e) {
    const int r = uf.find(m.elems[4 * e]);
    if (id[r] < 0) id[r] = n++;
    body[e] = id[r];
  }
  return n;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace

// 150 particles: no two closer than the gap, all inside the box, the same from the same seed and
// another from another seed.
TEST(Particles, PlacementKeepsGapAndIsReproducible) {
  for (const std::string shape : {"sphere", "ellipsoid", "polyhedron"}) {
    ParticleSpec s = spheres(150);
    s.shape = shape;
    s.box_size = {0.15, 0.15, 0.08};
    const fdem::Placement a = fdem::place_particles(s, "t");
    ASSERT_EQ(a.particles.size(), 150u);
    double worst = 1;
    for (std::size_t i = 0; i < a.particles.size(); ++i) {
      const auto& p = a.particles[i];
      EXPECT_GE(p.radius, s.rmin);
      EXPECT_LE(p.radius, s.rmax);
      EXPECT_GE(p.bound, p.radius * (1 - 1e-12)) << shape;  // a bounding sphere holds the volume
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(p.centre[k] - p.bound, s.box_origin[k] - 1e-12);
        EXPECT_LE(p.centre[k] + p.bound, s.box_origin[k] + s.box_size[k] + 1e-12);
      }
      for (std::size_t j = 0; j < i; ++j) {
        const auto& q = a.particles[j];
        const double d =
            std::hypot(p.centre[0] - q.centre[0], p.centre[1] - q.centre[1], p.centre[2] - q.centre[2]);
        worst = std::min(worst, d - p.bound - q.bound);
      }
    }
    EXPECT_GE(worst, s.gap * (1 - 1e-9)) << shape;
    EXPECT_GT(a.solid_fraction, 0.05);
    const fdem::Placement b = fdem::place_particles(s, "t");
    EXPECT_EQ(b.particles[149].centre, a.particles[149].centre);
    s.seed = 8;
    const fdem::Placement c = fdem::place_particles(s, "t");
    EXPECT_NE(c.particles[149].centre, a.particles[149].centre);
  }
}

// Too many for the box: the message says how far it got and what to change.
TEST(Particles, TooManyNamesPackingFraction) {
  ParticleSpec s = spheres(3000);
  const std::string e = error_of([&] { fdem::place_particles(s, "particles generator"); });
  EXPECT_NE(e.find("placed only"), std::string::npos) << e;
  EXPECT_NE(e.find("of 3000 particles"), std::string::npos) << e;
  EXPECT_NE(e.find("of the box volume"), std::string::npos) << e;
  EXPECT_NE(e.find("give a larger mesh.box"), std::string::npos) << e;
}

// The hull of the octahedron's 6 vertices: 8 outward faces, volume 4/3; a cube's 8 vertices have
// four coplanar points on a face: refused.
TEST(Particles, SphereHull) {
  const std::vector<double> oct = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  std::vector<int> tris;
  ASSERT_TRUE(fdem::sphere_hull(oct, tris));
  EXPECT_EQ(tris.size(), 24u);
  EXPECT_NEAR(fdem::hull_volume(oct, tris), 4.0 / 3.0, 1e-12);
  std::vector<double> cube;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) cube.push_back((i >> k & 1) ? 1 : -1);
  EXPECT_FALSE(fdem::sphere_hull(cube, tris));
}

// Meshed in two batches: one body per particle, no node of one particle within the gap of
// another's, each particle's volume that of its equivalent sphere (polyhedra: exact; spheres: the
// inscribed facets lose less than 0.4 (h/r)^2, ellipsoids less than 15 % at h = 0.3 to 0.6 r),
// and the same mesh from the same seed.
TEST(Particles, MeshOneBodyPerParticle) {
  for (const std::string shape : {"sphere", "ellipsoid", "polyhedron"}) {
    ParticleSpec s = spheres(6);
    s.shape = shape;
    s.box_size = {0.05, 0.05, 0.04};
    s.batch = 4;  // two Gmsh sessions, their meshes appended
    const double h = 0.0025;
    const HostMesh m = fdem::generate_particles(s, h, "particles");
    std::vector<int> body;
    ASSERT_EQ(bodies_of(m, body), 6) << shape;
    EXPECT_EQ(m.region_names, std::vector<std::string>{"particles"});
    ASSERT_TRUE(m.node_sets.count("surface"));
    std::vector<double> vol(6, 0.0);
    for (int e = 0; e < m.num_elems(); ++e) vol[body[e]] += fdem::mesh_detail::signed_measure(m, e);
    std::vector<double> want;
    for (const auto& p : fdem::place_particles(s, "t").particles)
      want.push_back(4.0 / 3.0 * kPi * std::pow(p.radius, 3));
    std::sort(vol.begin(), vol.end());
    std::sort(want.begin(), want.end());
    for (int i = 0; i < 6; ++i) {
      const double r = std::cbrt(want[i] / (4.0 / 3.0 * kPi));
      if (shape == "polyhedron")
        EXPECT_NEAR(vol[i] / want[i], 1.0, 1e-9) << shape;
      else if (shape == "sphere")  // the sorted volumes pair up with the sorted radii
        EXPECT_GT(vol[i] / want[i], 1 - 0.4 * (h / r) * (h / r)) << shape;
      else
        EXPECT_GT(vol[i] / want[i], 0.85) << shape;
      EXPECT_LT(vol[i] / want[i], 1 + 1e-9) << shape;  // facets inscribed in the curved surface
    }
    // nodes of different bodies at least the gap apart (surface nodes lie on the exact surface)
    std::vector<int> nbody(m.num_nodes());
    for (int e = 0; e < m.num_elems(); ++e)
      for (int a = 0; a < 4; ++a) nbody[m.elems[4 * e + a]] = body[e];
    const auto& surf = m.node_sets.at("surface");
    std::vector<int> on_surface(6, 0);
    for (int p : surf) on_surface[nbody[p]] = 1;
    EXPECT_EQ(std::count(on_surface.begin(), on_surface.end(), 1), 6) << shape;  // both sessions' sets
    double dmin = 1;
    for (std::size_t i = 0; i < surf.size(); ++i)
      for (std::size_t j = i + 1; j < surf.size(); ++j) {
        const int p = surf[i], q = surf[j];
        if (nbody[p] == nbody[q]) continue;
        dmin = std::min(dmin, std::hypot(m.X[3 * p] - m.X[3 * q], m.X[3 * p + 1] - m.X[3 * q + 1],
                                         m.X[3 * p + 2] - m.X[3 * q + 2]));
      }
    EXPECT_GE(dmin, s.gap * (1 - 1e-6)) << shape;
    if (shape == "sphere") {
      const HostMesh again = fdem::generate_particles(s, h, "particles");
      EXPECT_EQ(again.X, m.X);
      EXPECT_EQ(again.elems, m.elems);
    }
  }
}

// The element size does not depend on mesh.batch: a particle meshed alone in its Gmsh session got
// about 1.8 times finer elements than element_size (Gmsh's size from points falls back to a tenth
// of the session's bounding box), so 51 particles at the default batch of 50 had a 40 % smaller
// step than 50. The same particles in batches of 1 and of 4: element counts within 5 %, mean edge
// within 15 % of element_size in both.
TEST(Particles, ElementSizeDoesNotDependOnTheBatch) {
  for (const std::string shape : {"sphere", "polyhedron"}) {
    ParticleSpec s = spheres(4);
    s.shape = shape;
    s.rmin = 0.0035;
    s.rmax = 0.005;
    s.box_size = {0.05, 0.05, 0.04};
    const double h = 0.003;
    s.batch = 1;  // four sessions, one particle each
    const HostMesh one = fdem::generate_particles(s, h, "particles");
    s.batch = 4;  // one session
    const HostMesh four = fdem::generate_particles(s, h, "particles");
    ASSERT_GT(four.num_elems(), 0) << shape;
    const double ratio = static_cast<double>(one.num_elems()) / four.num_elems();
    EXPECT_NEAR(ratio, 1.0, 0.05) << shape << ": " << one.num_elems() << " elements in batches of 1, "
                                  << four.num_elems() << " in one batch";
    EXPECT_NEAR(fdem::mesh_quality(one).mean_size / h, 1.0, 0.15) << shape << ", batches of 1";
    EXPECT_NEAR(fdem::mesh_quality(four).mean_size / h, 1.0, 0.15) << shape << ", one batch";
  }
}

// The case reader: bad keys name their path.
TEST(Particles, ReaderErrorsNameTheKey) {
  const json base = json::parse(R"({
    "name": "t", "dimension": 3,
    "mesh": {"generator": "particles", "count": 5, "radius": [0.004, 0.008],
             "box": {"origin": [0, 0, 0], "size": [0.1, 0.1, 0.1]}, "element_size": 0.002},
    "materials": {"rock": {"density": 2700, "E": 30e9, "nu": 0.25}},
    "regions": {"particles": "rock"},
    "time": {"end_time": 1e-5}
  })");
  const fdem::Case c = fdem::parse_case(base, "t.json");
  EXPECT_EQ(c.mesh.kind, "particles");
  EXPECT_EQ(c.mesh.region, "particles");
  EXPECT_EQ(c.mesh.particles.count, 5);
  EXPECT_EQ(c.mesh.particles.rmax, 0.008);
  auto err = [&](const std::string& key, const json& v) {
    json d = base;
    if (v.is_null())
      d["mesh"].erase(key);
    else
      d["mesh"][key] = v;
    return error_of([&] { fdem::parse_case(d, "t.json"); });
  };
  EXPECT_NE(err("count", 0).find("mesh.count"), std::string::npos);
  EXPECT_NE(err("radius", json::array({0.008, 0.004})).find("mesh.radius: min 0.008 is larger"),
            std::string::npos);
  EXPECT_NE(err("radius", nullptr).find("mesh.radius: missing"), std::string::npos);
  EXPECT_NE(err("shape", "cube").find("mesh.shape: unknown shape 'cube'"), std::string::npos);
  EXPECT_NE(err("axis_ratio", json::array({0.5, 1})).find("mesh.axis_ratio: applies to shape 'ellipsoid'"),
            std::string::npos);
  EXPECT_NE(err("element_size", 0.005).find("mesh.element_size"), std::string::npos);
  EXPECT_NE(err("box", json::object({{"origin", {0, 0, 0}}})).find("mesh.box.size"), std::string::npos);
  EXPECT_NE(err("gap", -1).find("mesh.gap"), std::string::npos);
  EXPECT_NE(err("colour", 1).find("colour"), std::string::npos);
  json two = base;
  two["dimension"] = 2;
  EXPECT_NE(error_of([&] { fdem::parse_case(two, "t.json"); }).find("mesh.generator"), std::string::npos);
}

// Fragments per body, a known answer: body 0 (elements 0-3) broken into fragments 0 (mass 3) and
// 1 (mass 1), body 1 (elements 4-5) intact as fragment 2.
TEST(Particles, BodyFragmentsKnownAnswer) {
  const std::vector<int> body = {0, 0, 0, 0, 1, 1}, frag = {0, 0, 1, 0, 2, 2};
  const std::vector<double> emass = {1, 1, 1, 1, 2, 2}, fmass = {3, 1, 4};
  const std::vector<double> cen = {0, 0, 0, 2, 0, 0, 0, 0, 0, 2, 0, 0, 5, 1, 0, 5, 3, 0};
  const auto b = fdem::body_fragments(body, 2, frag, fmass, emass, cen);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].fragments, 2);
  EXPECT_DOUBLE_EQ(b[0].mass, 4);
  EXPECT_DOUBLE_EQ(b[0].largest_fraction, 0.75);
  EXPECT_DOUBLE_EQ(b[0].centroid[0], 1.0);
  EXPECT_EQ(b[1].fragments, 1);
  EXPECT_DOUBLE_EQ(b[1].largest_fraction, 1.0);
  EXPECT_DOUBLE_EQ(b[1].centroid[1], 2.0);
  const json s = fdem::body_fragments_summary(b, "bodies.csv");
  EXPECT_EQ(s["broken"], 1);
  EXPECT_DOUBLE_EQ(s["mean_fragments"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(s["mean_largest_fraction"].get<double>(), 0.875);
  EXPECT_EQ(s["histogram"]["bodies"], json::array({1, 1}));
  const std::vector<int> bad = {0, 0, 1, 0, 2, 0};  // fragment 0 in both bodies
  EXPECT_THROW(fdem::body_fragments(body, 2, bad, fmass, emass, cen), std::logic_error);
}

// A run of two particles with interfaces that do not break in two steps: bodies.csv has both,
// intact, and their masses add up to the total.
TEST(Particles, RunWritesBodies) {
  const fs::path dir = fs::temp_directory_path() / ("fdem_particles_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const json doc = json::parse(R"({
    "name": "two", "dimension": 3,
    "mesh": {"generator": "particles", "count": 2, "radius": 0.005, "gap": 0.001,
             "box": {"origin": [0, 0, 0], "size": [0.03, 0.015, 0.015]}, "element_size": 0.004},
    "materials": {"rock": {"density": 2700, "E": 30e9, "nu": 0.25}},
    "regions": {"particles": "rock"},
    "interface_materials": {"rif": {"kn": 3e14, "ks": 1e14, "ft": 8e6, "c": 16e6, "phi_deg": 45,
                                    "Gnc": 75, "Gsc": 1500}},
    "fracture": {"regions": ["particles"], "interface_material": "rif"},
    "time": {"end_time": 1, "max_steps": 2},
    "output": {"history_rows": 2}
  })");
  const std::string path = (dir / "two.json").string();
  std::ofstream(path) << doc.dump();
  fdem::RunOptions opt;
  opt.out_dir = (dir / "out").string();
  opt.progress = false;
  const json s = fdem::run_case(path, opt);
  const json& pb = s["fragments"]["per_body"];
  EXPECT_EQ(pb["bodies"], 2);
  EXPECT_EQ(pb["broken"], 0);
  EXPECT_DOUBLE_EQ(pb["mean_fragments"].get<double>(), 1.0);
  std::ifstream in(opt.out_dir + "/bodies.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("body,elements,mass [kg],fragments,largest_fraction", 0), 0u) << line;
  double mass = 0;
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    std::vector<std::string> f;
    std::size_t a = 0;
    for (std::size_t b; (b = line.find(',', a)) != std::string::npos; a = b + 1)
      f.push_back(line.substr(a, b - a));
    mass += std::stod(f[2]);
    EXPECT_EQ(f[3], "1");
  }
  EXPECT_EQ(rows, 2);
  EXPECT_NEAR(mass, s["fragments"]["total_mass_kg"].get<double>(), 1e-8 * mass);  // 9 digits
  fs::remove_all(dir);
}
