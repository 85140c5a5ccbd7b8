// Uniform refinement (src/mesh/refine.hpp, case key mesh.refine): counts, conformity and measure
// against the coarse mesh, nodes on curved boundaries, node and face sets, quality, and the
// property the runs over processes will rely on: refining some coarse elements gives the same
// global ids, coordinates and elements as the whole refinement restricted to them.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/refine.hpp"

namespace {

using fdem::HostMesh;
const double kPi = std::acos(-1.0);

double measure(const HostMesh& m, int e) {
  const int d = m.dim, npe = d + 1;
  const double* x[4];
  for (int a = 0; a < npe; ++a) x[a] = &m.X[static_cast<std::size_t>(m.elems[e * npe + a]) * d];
  if (d == 2) return 0.5 * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]));
  double u[3][3];
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) u[r][k] = x[r + 1][k] - x[0][k];
  return (u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[2][1]) - u[0][1] * (u[1][0] * u[2][2] - u[1][2] * u[2][0]) +
          u[0][2] * (u[1][0] * u[2][1] - u[1][1] * u[2][0])) /
         6;
}

double total_measure(const HostMesh& m) {
  double s = 0;
  for (int e = 0; e < m.num_elems(); ++e) s += measure(m, e);
  return s;
}

// Facets (sorted node keys) and how many elements hold each.
std::map<std::array<int, 3>, int> facet_uses(const HostMesh& m) {
  static const int f2[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  static const int f3[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, int> uses;
  const int d = m.dim, npe = d + 1;
  for (int e = 0; e < m.num_elems(); ++e)
    for (int f = 0; f < npe; ++f) {
      std::array<int, 3> k{-1, -1, -1};
      for (int j = 0; j < d; ++j) k[j] = m.elems[e * npe + (d == 2 ? f2[f][j] : f3[f][j])];
      std::sort(k.begin(), k.begin() + d);
      ++uses[k];
    }
  return uses;
}

int boundary_facets(const HostMesh& m) {
  int n = 0;
  for (const auto& [k, u] : facet_uses(m)) {
    EXPECT_LE(u, 2) << "a facet held by more than two elements";
    n += u == 1;
  }
  return n;
}

// Every element positive, every facet held by one or two elements, no node twice.
void expect_valid(const HostMesh& m) {
  for (int e = 0; e < m.num_elems(); ++e) ASSERT_GT(measure(m, e), 0) << "element " << e;
  std::set<std::vector<double>> points;
  for (int n = 0; n < m.num_nodes(); ++n)
    points.insert(std::vector<double>(m.X.begin() + n * m.dim, m.X.begin() + (n + 1) * m.dim));
  EXPECT_EQ(static_cast<int>(points.size()), m.num_nodes()) << "two nodes at one place";
}

TEST(Refine, BoxCountsVolumeConformityAndNodeSets) {
  const HostMesh coarse = fdem::generate_box({1, 2, 3}, {3.0, 1.0, 2.0}, 2, 2, 2, "rock");
  const int cb = boundary_facets(coarse);
  for (int k : {1, 2}) {
    SCOPED_TRACE("levels " + std::to_string(k));
    const int m = 1 << k;
    const HostMesh f = fdem::refine_mesh(coarse, k, {});
    expect_valid(f);
    EXPECT_EQ(f.num_elems(), coarse.num_elems() * m * m * m);
    EXPECT_NEAR(total_measure(f), 6.0, 1e-12);
    EXPECT_EQ(boundary_facets(f), cb * m * m);  // the boundary refined, no facet left unmatched inside
    // the nodes are the lattice of the 2 x 2 x 2 cells at spacing 1/m of a cell
    EXPECT_EQ(f.num_nodes(), (2 * m + 1) * (2 * m + 1) * (2 * m + 1));
    // coarse nodes keep their ids and places
    for (int n = 0; n < coarse.num_nodes() * 3; ++n) EXPECT_EQ(f.X[n], coarse.X[n]);
    // xmin: every node on the plane x = 1, and nothing else
    const std::vector<int>& xmin = f.node_sets.at("xmin");
    int on_plane = 0;
    for (int n = 0; n < f.num_nodes(); ++n) on_plane += f.X[n * 3] == 1.0;
    EXPECT_EQ(static_cast<int>(xmin.size()), on_plane);
    EXPECT_EQ(on_plane, (2 * m + 1) * (2 * m + 1));
    for (int n : xmin) EXPECT_EQ(f.X[n * 3], 1.0);
    EXPECT_EQ(static_cast<int>(f.node_sets.at("all").size()), f.num_nodes());
    EXPECT_EQ(f.region_names, coarse.region_names);
  }
  EXPECT_THROW(fdem::refine_mesh(coarse, 11, {}), fdem::InputError);
  EXPECT_THROW(fdem::refine_mesh(coarse, -1, {}), fdem::InputError);
  EXPECT_EQ(fdem::refine_mesh(coarse, 0, {}).X, coarse.X);
}

TEST(Refine, RectangleAreaNodeSetsAndCounts) {
  const HostMesh coarse = fdem::generate_crossed_rectangle(0, 0, 2.0, 1.0, 2, 1);
  const HostMesh f = fdem::refine_mesh(coarse, 3, {});
  expect_valid(f);
  EXPECT_EQ(f.num_elems(), coarse.num_elems() * 64);
  EXPECT_NEAR(total_measure(f), 2.0, 1e-13);
  EXPECT_EQ(boundary_facets(f), boundary_facets(coarse) * 8);
  int top = 0;
  for (int n = 0; n < f.num_nodes(); ++n) top += f.X[n * 2 + 1] == 1.0;
  EXPECT_EQ(static_cast<int>(f.node_sets.at("top").size()), top);
  EXPECT_EQ(top, 2 * 8 + 1);
}

// Edge case of the set rule: a node set of one point keeps that point only.
TEST(Refine, PointSetsKeepTheirPoint) {
  HostMesh coarse = fdem::generate_crossed_rectangle(0, 0, 1.0, 1.0, 1, 1);
  coarse.node_sets["corner"] = {0};
  const HostMesh f = fdem::refine_mesh(coarse, 2, {});
  EXPECT_EQ(f.node_sets.at("corner"), std::vector<int>{0});
}

// The sphere's new surface nodes lie on it, the volume approaches 4/3 pi R^3, quality holds.
TEST(Refine, SphereSurfaceNodesOnTheSphereAndQuality) {
  const double R = 0.025;
  const std::array<double, 3> c{0.01, -0.02, 0.03};
  const HostMesh coarse = fdem::generate_sphere(c, R, 0.008);
  const double exact = 4.0 / 3.0 * kPi * R * R * R;
  const fdem::MeshQuality q0 = fdem::mesh_quality(coarse);
  double err = std::abs(total_measure(coarse) - exact) / exact;
  for (int k : {1, 2}) {
    SCOPED_TRACE("levels " + std::to_string(k));
    const HostMesh f = fdem::refine_mesh(coarse, k, {{c, R}});
    expect_valid(f);
    for (int n : f.node_sets.at("surface")) {
      double r2 = 0;
      for (int j = 0; j < 3; ++j) r2 += (f.X[n * 3 + j] - c[j]) * (f.X[n * 3 + j] - c[j]);
      ASSERT_NEAR(std::sqrt(r2), R, 1e-15) << "node " << n;
    }
    EXPECT_EQ(static_cast<int>(f.node_sets.at("surface").size()),
              static_cast<int>(coarse.node_sets.at("surface").size()) +
                  boundary_facets(f) / 2 - boundary_facets(coarse) / 2);  // Euler on a sphere: V = F/2 + 2
    const double e = std::abs(total_measure(f) - exact) / exact;
    EXPECT_LT(e, 0.5 * err) << "the volume error did not fall";
    err = e;
    // red refinement with the shortest diagonal keeps the smallest dihedral angle within 1.5 of
    // the coarse mesh's (measured: 11.7 -> 10.8 degrees on the 3D impact's sphere)
    const fdem::MeshQuality q = fdem::mesh_quality(f);
    EXPECT_GT(q.min_angle_deg, q0.min_angle_deg / 1.5);
    EXPECT_NEAR(q.mean_size, q0.mean_size / (1 << k), 0.15 * q0.mean_size / (1 << k));
  }
  // linear (no surface given): the new nodes stay inside, the volume is the coarse one
  const HostMesh lin = fdem::refine_mesh(coarse, 1, {});
  EXPECT_NEAR(total_measure(lin), total_measure(coarse), 1e-12 * exact);
}

// The mirror-symmetric disc stays symmetric; its circle's new nodes lie on the circle.
TEST(Refine, SymmetricDiscStaysSymmetric) {
  const double R = 0.05;
  const HostMesh coarse = fdem::generate_disc(0, 0, R, 0.01, "body", 0, 1, true);
  const HostMesh f = fdem::refine_mesh(coarse, 2, {{{0, 0, 0}, R}});
  expect_valid(f);
  for (int n : f.node_sets.at("boundary")) EXPECT_NEAR(std::hypot(f.X[n * 2], f.X[n * 2 + 1]), R, 1e-16);
  std::set<std::pair<double, double>> pts;
  for (int n = 0; n < f.num_nodes(); ++n) pts.insert({f.X[n * 2], f.X[n * 2 + 1]});
  int mirrored = 0;
  for (int n = 0; n < f.num_nodes(); ++n) {
    const auto it = pts.lower_bound({-f.X[n * 2] - 1e-15, -1e300});
    bool found = false;
    for (auto j = it; j != pts.end() && j->first <= -f.X[n * 2] + 1e-15 && !found; ++j)
      found = std::abs(j->second - f.X[n * 2 + 1]) <= 1e-15;
    mirrored += found;
  }
  EXPECT_EQ(mirrored, f.num_nodes());
  EXPECT_NEAR(total_measure(f), kPi * R * R, 0.002 * kPi * R * R);
}

// Face sets are cut into facets of the same orientation on the same plane, and a cut through them
// inserts the interfaces there.
TEST(Refine, FaceSetsRefinedWithTheirOrientation) {
  HostMesh coarse = fdem::generate_box({0, 0, 0}, {2.0, 1.0, 1.0}, 2, 1, 1);
  // the facets on the plane x = 1, oriented towards +x
  std::vector<int>& mid = coarse.face_sets["joint"];
  for (const auto& [k, u] : facet_uses(coarse)) {
    if (coarse.X[k[0] * 3] != 1.0 || coarse.X[k[1] * 3] != 1.0 || coarse.X[k[2] * 3] != 1.0) continue;
    const double* a = &coarse.X[k[0] * 3];
    const double* b = &coarse.X[k[1] * 3];
    const double* c = &coarse.X[k[2] * 3];
    const double nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
    if (nx > 0)
      mid.insert(mid.end(), {k[0], k[1], k[2]});
    else
      mid.insert(mid.end(), {k[0], k[2], k[1]});
  }
  ASSERT_EQ(mid.size(), 2u * 3);
  const HostMesh f = fdem::refine_mesh(coarse, 2, {});
  const std::vector<int>& fine = f.face_sets.at("joint");
  ASSERT_EQ(fine.size(), 2u * 16 * 3);
  double area = 0;
  for (std::size_t i = 0; i < fine.size(); i += 3) {
    const double* a = &f.X[fine[i] * 3];
    const double* b = &f.X[fine[i + 1] * 3];
    const double* c = &f.X[fine[i + 2] * 3];
    EXPECT_EQ(a[0], 1.0);
    EXPECT_EQ(b[0], 1.0);
    EXPECT_EQ(c[0], 1.0);
    const double nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
    EXPECT_GT(nx, 0);
    area += 0.5 * nx;
  }
  EXPECT_NEAR(area, 1.0, 1e-14);
  HostMesh cut = f;
  fdem::insert_interfaces(cut, {false}, {"joint"});
  EXPECT_EQ(cut.num_ifaces(), 32);
}

// Refining some coarse elements gives what the whole refinement gives on them: the same global
// ids, the same coordinates to the bit, the same elements and node-set memberships.
TEST(Refine, PartIsTheWholeRefinementRestricted) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE("dim " + std::to_string(dim));
    const double R = 0.025;
    const HostMesh coarse = dim == 3 ? fdem::generate_sphere({0, 0, 0}, R, 0.008)
                                     : fdem::generate_disc(0, 0, R, 0.004, "body", 1, 0, false);
    const std::vector<fdem::CurvedSurface> s{{{0, 0, 0}, R}};
    const int k = 2;
    const HostMesh whole = fdem::refine_mesh(coarse, k, s);
    const fdem::CoarseTopology t = fdem::coarse_topology(coarse, k, s);
    EXPECT_EQ(t.num_fine_nodes, whole.num_nodes());
    std::vector<int> part;  // the elements with a centroid at x < 0, in reverse order
    for (int e = coarse.num_elems() - 1; e >= 0; --e) {
      double cx = 0;
      for (int a = 0; a <= dim; ++a) cx += coarse.X[coarse.elems[e * (dim + 1) + a] * dim];
      if (cx < 0) part.push_back(e);
    }
    const fdem::RefinedPart p = fdem::refine_elements(coarse, t, part);
    const int per = dim == 2 ? 16 : 64;
    ASSERT_EQ(p.mesh.num_elems(), static_cast<int>(part.size()) * per);
    ASSERT_LT(p.mesh.num_nodes(), whole.num_nodes());
    for (int n = 0; n < p.mesh.num_nodes(); ++n)
      for (int j = 0; j < dim; ++j) ASSERT_EQ(p.mesh.X[n * dim + j], whole.X[p.node_gid[n] * dim + j]) << n;
    for (int e = 0; e < p.mesh.num_elems(); ++e) {
      const std::int64_t g = p.elem_gid[e];
      ASSERT_EQ(g / per, part[e / per]);
      for (int a = 0; a <= dim; ++a)
        ASSERT_EQ(p.node_gid[p.mesh.elems[e * (dim + 1) + a]], whole.elems[g * (dim + 1) + a]);
    }
    for (const auto& [name, nodes] : p.mesh.node_sets) {
      const std::vector<int>& w = whole.node_sets.at(name);
      for (int n : nodes) EXPECT_TRUE(std::binary_search(w.begin(), w.end(), static_cast<int>(p.node_gid[n])));
      int in_part = 0;  // and no member of the part's nodes is missing
      std::set<std::int64_t> mine(p.node_gid.begin(), p.node_gid.end());
      for (int n : w) in_part += mine.count(n);
      EXPECT_EQ(in_part, static_cast<int>(nodes.size())) << name;
    }
  }
}

}  // namespace

namespace {

// The interface numbering of the whole refined mesh follows from the coarse mesh: every interface
// insert_interfaces makes (side A: the lower element) lies in the range of its side A's coarse
// element that refined_interface_offsets computes.
TEST(Refine, InterfaceNumberingFollowsFromTheCoarseMesh) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE("dim " + std::to_string(dim));
    const double R = 0.025;
    const HostMesh coarse = dim == 3 ? fdem::generate_sphere({0, 0, 0}, R, 0.01)
                                     : fdem::generate_disc(0, 0, R, 0.005, "body", 0, 0, false);
    for (int k : {1, 2}) {
      const std::vector<fdem::CurvedSurface> s{{{0, 0, 0}, R}};
      HostMesh fine = fdem::refine_mesh(coarse, k, s);
      fdem::insert_interfaces(fine, {true});
      const std::vector<std::int64_t> off =
          fdem::refined_interface_offsets(coarse, fdem::coarse_topology(coarse, k, s));
      ASSERT_EQ(off.size(), static_cast<std::size_t>(coarse.num_elems()) + 1);
      EXPECT_EQ(off.back(), fine.num_ifaces());
      const int children = static_cast<int>(fdem::refine_factor(dim, k));
      for (int i = 0; i < fine.num_ifaces(); ++i) {
        const int a = fine.iface_elems[2 * i], b = fine.iface_elems[2 * i + 1];
        ASSERT_LT(a, b);
        const int E = a / children;
        ASSERT_GE(i, off[E]) << "interface " << i;
        ASSERT_LT(i, off[E + 1]) << "interface " << i;
      }
    }
  }
}

// The embedded diameter of the disc generator is a node set and a face set ("diameter"), plain and
// mirror-symmetric: a jitter leaves its nodes on it (before, `mesh.jitter` moved them off and the
// Brazilian disc's split no longer had its straight path: strength +23 to +29 % on two meshes), and
// a refinement keeps it a straight chain of edges in the set.
TEST(Refine, DiscDiameterKeptByJitterAndRefinement) {
  const double R = 0.05;
  for (bool mirror : {false, true}) {
    SCOPED_TRACE(mirror ? "symmetric" : "plain");
    HostMesh d = fdem::generate_disc(0, 0, R, 0.006, "body", 0, 1, mirror);
    ASSERT_TRUE(d.node_sets.count("diameter"));
    ASSERT_TRUE(d.face_sets.count("diameter"));
    double length = 0;
    const std::vector<int>& f = d.face_sets.at("diameter");
    for (std::size_t i = 0; i < f.size(); i += 2) {
      EXPECT_NEAR(d.X[2 * f[i]], 0.0, 1e-15);
      length += std::abs(d.X[2 * f[i] + 1] - d.X[2 * f[i + 1] + 1]);
    }
    EXPECT_NEAR(length, 2 * R, 1e-12);  // each segment once
    fdem::MeshSpec spec;
    spec.kind = "disc";
    spec.radius = R;
    spec.refine = 1;
    spec.jitter = 0.3;
    HostMesh r = fdem::refine_mesh(d, spec.refine, fdem::curved_surfaces(spec, 2));
    EXPECT_GT(fdem::transform_mesh(r, spec), r.num_nodes() / 2);  // most nodes moved
    int on = 0;
    for (int n : r.node_sets.at("diameter")) {
      EXPECT_NEAR(r.X[2 * n], 0.0, 1e-15) << "node " << n;
      ++on;
    }
    EXPECT_EQ(on, 2 * static_cast<int>(d.node_sets.at("diameter").size()) - 1);
  }
}

}  // namespace

namespace {

// The mean element size of a refined mesh summed per coarse element (refined_mean_size): from the
// sums of two processes' own coarse elements (each refined alone) added in coarse order, the same
// bits as from the whole mesh, and the plain mean to round-off.
TEST(Refine, MeanSizeSummedPerCoarseElementIsTheSameFromParts) {
  const double R = 0.025;
  const HostMesh coarse = fdem::generate_sphere({0, 0, 0}, R, 0.009);
  const std::vector<fdem::CurvedSurface> s{{{0, 0, 0}, R}};
  const int k = 1, children = 8;
  const HostMesh whole = fdem::refine_mesh(coarse, k, s);
  const fdem::CoarseTopology t = fdem::coarse_topology(coarse, k, s);
  const double mean = fdem::refined_mean_size(whole, children);
  EXPECT_NEAR(mean, fdem::mesh_quality(whole).mean_size, 1e-12 * mean);
  std::vector<int> even, odd;
  for (int e = 0; e < coarse.num_elems(); ++e) (e % 2 ? odd : even).push_back(e);
  std::vector<double> sums(coarse.num_elems());
  for (const std::vector<int>* own : {&even, &odd}) {
    const std::vector<double> part = fdem::coarse_edge_sums(fdem::refine_elements(coarse, t, *own).mesh, children);
    ASSERT_EQ(part.size(), own->size());
    for (size_t i = 0; i < own->size(); ++i) sums[(*own)[i]] = part[i];
  }
  EXPECT_EQ(fdem::mean_size_from_sums(sums, whole.num_elems(), 3), mean);  // the same bits
  EXPECT_THROW(fdem::coarse_edge_sums(whole, 7), fdem::InputError);
}

}  // namespace
