// Fragment analysis (kernels/fragments.hpp, src/solver/fragment_analysis.cpp) on small meshes
// with known answers: cut lines and planes of failed interfaces, all interfaces failed, a
// non-fracturable region, partly failed interfaces, and random failure patterns checked against a
// plain host union-find.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <vector>

#include "mesh/mesh.hpp"
#include "solver/fragment_analysis.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

template <int D>
Case frac_case() {
  auto c = fdem_test::basic_case(D, 30e9, 0.2, 2500);
  c.interface_materials = {fdem_test::strong_interface(1e13, 4e12)};
  c.fracture_material = 0;
  return c;
}

// Sets the history of the chosen integration points of interface q so that their damage is 1
// (dmax beyond dmf) or leaves them intact.
template <int D>
void set_failed(Simulation<D>& sim, const std::vector<std::array<bool, 3>>& failed_points) {
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  Kokkos::deep_copy(h, sim.m.ihist);
  for (int q = 0; q < sim.m.ni; ++q)
    for (int k = 0; k < D; ++k) {
      const bool f = failed_points[q][k];
      h(q, k, 0) = f ? 3e-6 : 0.0;  // dmax
      h(q, k, 1) = f ? 1e-6 : 0.0;  // dm0
      h(q, k, 2) = f ? 2e-6 : 0.0;  // dmf
      h(q, k, 3) = 0.0;
    }
  Kokkos::deep_copy(sim.m.ihist, h);
}

template <int D>
std::vector<std::array<bool, 3>> whole(const HostMesh& mesh, const std::function<bool(int)>& fail) {
  std::vector<std::array<bool, 3>> out(mesh.num_ifaces());
  for (int q = 0; q < mesh.num_ifaces(); ++q) {
    const bool f = fail(q);
    out[q] = {f, f && D >= 2, f && D >= 3};
    if (D == 2) out[q][2] = false;
  }
  return out;
}

template <int D>
std::array<double, 3> centroid(const HostMesh& m, int e) {
  std::array<double, 3> c{0, 0, 0};
  for (int a = 0; a < D + 1; ++a)
    for (int k = 0; k < D; ++k) c[k] += m.X[static_cast<size_t>(m.elems[e * (D + 1) + a]) * D + k] / (D + 1);
  return c;
}

template <int D>
double element_mass(const HostMesh& m, int e, double rho, double thickness) {
  double x[D + 1][D];
  for (int a = 0; a < D + 1; ++a)
    for (int k = 0; k < D; ++k) x[a][k] = m.X[static_cast<size_t>(m.elems[e * (D + 1) + a]) * D + k];
  if constexpr (D == 2) {
    return rho * thickness * 0.5 *
           std::fabs((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]));
  } else {
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = x[1][k] - x[0][k];
      b[k] = x[2][k] - x[0][k];
      c[k] = x[3][k] - x[0][k];
    }
    return rho * std::fabs(a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                           a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
}

// Reference answer: union-find over elements on the host, joining elements that share a node or
// an interface that has not failed (some point intact).
template <int D>
std::vector<double> reference_masses(const HostMesh& m, const std::vector<std::array<bool, 3>>& fp,
                                     double rho, double thickness) {
  const int ne = m.num_elems();
  std::vector<int> p(ne);
  std::iota(p.begin(), p.end(), 0);
  std::function<int(int)> find = [&](int i) { return p[i] == i ? i : p[i] = find(p[i]); };
  auto unite = [&](int a, int b) { p[find(a)] = find(b); };
  std::vector<int> node_elem(m.num_nodes(), -1);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < D + 1; ++a) {
      int& n = node_elem[m.elems[e * (D + 1) + a]];
      if (n >= 0) unite(n, e);
      n = e;
    }
  for (int q = 0; q < m.num_ifaces(); ++q) {
    bool all = true;
    for (int k = 0; k < D; ++k) all = all && fp[q][k];
    if (!all) unite(m.iface_elems[2 * q], m.iface_elems[2 * q + 1]);
  }
  std::vector<double> mass(ne, 0.0);
  for (int e = 0; e < ne; ++e) mass[find(e)] += element_mass<D>(m, e, rho, thickness);
  std::vector<double> out;
  for (double x : mass)
    if (x > 0) out.push_back(x);
  std::sort(out.begin(), out.end());
  return out;
}

template <int D>
std::vector<double> sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// A 4 x 2 crossed rectangle (8 m^2, 1 m thick, rho 2500) cut along x = 1 by failed interfaces:
// exactly two fragments of 1/4 and 3/4 of the mass; every element left of the cut carries one id.
TEST(Fragments, CutLineSplitsCrossedRectangleInTwo) {
  HostMesh mesh = generate_crossed_rectangle(0, 0, 4, 2, 4, 2);
  insert_interfaces(mesh, {true});
  Simulation<2> sim(frac_case<2>(), mesh);
  FragmentAnalysis<2> fa(sim.m);
  // before any failure: one fragment with the whole mass
  FragmentStats s = fa.compute(sim.m);
  EXPECT_EQ(s.count, 1);
  EXPECT_NEAR(s.total_mass, 2500 * 8.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.largest_fraction, 1.0);
  auto cut = [&](int q) {
    const double xa = centroid<2>(mesh, mesh.iface_elems[2 * q])[0];
    const double xb = centroid<2>(mesh, mesh.iface_elems[2 * q + 1])[0];
    return (xa < 1) != (xb < 1);
  };
  set_failed<2>(sim, whole<2>(mesh, cut));
  s = fa.compute(sim.m);
  EXPECT_EQ(s.count, 2);
  EXPECT_EQ(s.single_element, 0);
  EXPECT_NEAR(s.total_mass, 2500 * 8.0, 1e-9);
  EXPECT_NEAR(s.largest_mass, 2500 * 6.0, 1e-9);
  EXPECT_NEAR(s.largest_fraction, 0.75, 1e-14);
  const auto m = sorted<2>(fa.masses());
  EXPECT_NEAR(m[0], 2500 * 2.0, 1e-9);
  EXPECT_NEAR(m[1], 2500 * 6.0, 1e-9);
  std::vector<int> ids;
  fa.element_ids(ids);
  ASSERT_EQ(static_cast<int>(ids.size()), mesh.num_elems());
  int left = -1, right = -1;
  for (int e = 0; e < mesh.num_elems(); ++e) {
    int& want = centroid<2>(mesh, e)[0] < 1 ? left : right;
    if (want < 0) want = ids[e];
    EXPECT_EQ(ids[e], want) << "element " << e;
  }
  EXPECT_NE(left, right);
  // distribution: both fragments in the top decade, all the mass there
  EXPECT_EQ(s.bin_count[0], 2.0);
  EXPECT_NEAR(s.bin_mass_fraction[0], 1.0, 1e-14);
}

// A cut line of interfaces with only some of their points failed holds together.
TEST(Fragments, PartlyFailedInterfacesStillConnect) {
  HostMesh mesh = generate_crossed_rectangle(0, 0, 4, 2, 4, 2);
  insert_interfaces(mesh, {true});
  Simulation<2> sim(frac_case<2>(), mesh);
  std::vector<std::array<bool, 3>> fp(mesh.num_ifaces(), {false, false, false});
  for (int q = 0; q < mesh.num_ifaces(); ++q) {
    const double xa = centroid<2>(mesh, mesh.iface_elems[2 * q])[0];
    const double xb = centroid<2>(mesh, mesh.iface_elems[2 * q + 1])[0];
    if ((xa < 1) != (xb < 1)) fp[q] = {true, false, false};
  }
  set_failed<2>(sim, fp);
  FragmentAnalysis<2> fa(sim.m);
  EXPECT_EQ(fa.compute(sim.m).count, 1);
}

// Every interface failed: one fragment per element, each with its own mass, all single-element.
TEST(Fragments, AllFailedGivesOneFragmentPerElement) {
  HostMesh mesh = generate_crossed_rectangle(0, 0, 3, 2, 3, 2);
  insert_interfaces(mesh, {true});
  auto c = frac_case<2>();
  c.thickness = 0.01;
  Simulation<2> sim(c, mesh);
  set_failed<2>(sim, whole<2>(mesh, [](int) { return true; }));
  FragmentAnalysis<2> fa(sim.m);
  const FragmentStats s = fa.compute(sim.m);
  const int ne = mesh.num_elems();
  EXPECT_EQ(s.count, ne);
  EXPECT_EQ(s.single_element, ne);
  EXPECT_NEAR(s.total_mass, 2500 * 6.0 * 0.01, 1e-12);
  EXPECT_NEAR(s.largest_fraction, 1.0 / ne, 1e-14);  // equal triangles
  double nsum = 0, msum = 0;
  for (int b = 0; b < kFragmentBins; ++b) {
    nsum += s.bin_count[b];
    msum += s.bin_mass_fraction[b];
  }
  EXPECT_EQ(nsum, ne);
  EXPECT_NEAR(msum, 1.0, 1e-14);
  EXPECT_EQ(s.bin_count[1], ne);  // 1/24 lies in [1e-2, 1e-1)
  std::vector<int> ids;
  fa.element_ids(ids);
  std::vector<int> sorted_ids = ids;
  std::sort(sorted_ids.begin(), sorted_ids.end());
  for (int e = 0; e < ne; ++e) EXPECT_EQ(sorted_ids[e], e);
}

// Left half non-fracturable (shared nodes, no interfaces inside), right half fracturable; every
// interface failed: the left half stays one fragment, every right element is its own.
TEST(Fragments, NonFracturableRegionStaysOneFragment) {
  HostMesh mesh = generate_crossed_rectangle(0, 0, 4, 2, 4, 2);
  mesh.region_names = {"solid", "rock"};
  int nright = 0;
  for (int e = 0; e < mesh.num_elems(); ++e) {
    mesh.elem_region[e] = centroid<2>(mesh, e)[0] < 2 ? 0 : 1;
    nright += mesh.elem_region[e];
  }
  insert_interfaces(mesh, {false, true});
  auto c = frac_case<2>();
  c.region_material = {{"solid", 0}, {"rock", 0}};
  Simulation<2> sim(c, mesh);
  set_failed<2>(sim, whole<2>(mesh, [](int) { return true; }));
  FragmentAnalysis<2> fa(sim.m);
  const FragmentStats s = fa.compute(sim.m);
  EXPECT_EQ(s.count, 1 + nright);
  EXPECT_EQ(s.single_element, nright);
  EXPECT_NEAR(s.largest_mass, 2500 * 4.0, 1e-9);
  EXPECT_NEAR(s.total_mass, 2500 * 8.0, 1e-9);
}

// 3D: a 2 x 2 x 2 box cut by the plane z = 1: two equal fragments; all failed: one per element.
TEST(Fragments, BoxCutPlaneAndAllFailed3D) {
  HostMesh mesh = generate_box({0, 0, 0}, {2, 2, 2}, 2, 2, 2);
  insert_interfaces(mesh, {true});
  Simulation<3> sim(frac_case<3>(), mesh);
  FragmentAnalysis<3> fa(sim.m);
  EXPECT_EQ(fa.compute(sim.m).count, 1);
  set_failed<3>(sim, whole<3>(mesh, [&](int q) {
                  return (centroid<3>(mesh, mesh.iface_elems[2 * q])[2] < 1) !=
                         (centroid<3>(mesh, mesh.iface_elems[2 * q + 1])[2] < 1);
                }));
  FragmentStats s = fa.compute(sim.m);
  EXPECT_EQ(s.count, 2);
  EXPECT_NEAR(s.largest_fraction, 0.5, 1e-14);
  EXPECT_NEAR(s.total_mass, 2500 * 8.0, 1e-9);
  const auto m = fa.masses();
  EXPECT_NEAR(m[0], 2500 * 4.0, 1e-9);
  EXPECT_NEAR(m[1], 2500 * 4.0, 1e-9);
  set_failed<3>(sim, whole<3>(mesh, [](int) { return true; }));
  s = fa.compute(sim.m);
  EXPECT_EQ(s.count, mesh.num_elems());
  EXPECT_EQ(s.single_element, mesh.num_elems());
  EXPECT_NEAR(s.total_mass, 2500 * 8.0, 1e-9);
}

// Random failure patterns (from a few to most interfaces failed, some partly) against a host
// union-find: same number of fragments, same sorted masses, and the masses sum to the total.
template <int D>
void random_patterns(const HostMesh& base, unsigned seed0) {
  HostMesh mesh = base;
  insert_interfaces(mesh, {true});
  Simulation<D> sim(frac_case<D>(), mesh);
  FragmentAnalysis<D> fa(sim.m);
  double total = 0;
  for (int e = 0; e < mesh.num_elems(); ++e) total += element_mass<D>(mesh, e, 2500, 1.0);
  for (double pfail : {0.1, 0.4, 0.6, 0.8, 0.95}) {
    unsigned s = seed0 + static_cast<unsigned>(pfail * 1000);
    std::vector<std::array<bool, 3>> fp(mesh.num_ifaces(), {false, false, false});
    for (int q = 0; q < mesh.num_ifaces(); ++q) {
      const bool f = 0.5 * (fdem_test::prand(s) + 1) < pfail;
      for (int k = 0; k < D; ++k) fp[q][k] = f;
      if (f && 0.5 * (fdem_test::prand(s) + 1) < 0.1) fp[q][0] = false;  // partly failed: intact
    }
    set_failed<D>(sim, fp);
    const FragmentStats st = fa.compute(sim.m);
    const auto want = reference_masses<D>(mesh, fp, 2500, 1.0);
    const auto got = sorted<D>(fa.masses());
    ASSERT_EQ(st.count, static_cast<int>(want.size())) << "p_fail " << pfail;
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12 * total);
    EXPECT_NEAR(st.total_mass, total, 1e-12 * total) << "p_fail " << pfail;
    EXPECT_NEAR(st.largest_mass, want.back(), 1e-12 * total);
  }
}

TEST(Fragments, RandomFailurePatternsMatchHostUnionFind2D) {
  random_patterns<2>(generate_crossed_rectangle(0, 0, 1, 1, 12, 12), 11);
}

TEST(Fragments, RandomFailurePatternsMatchHostUnionFind3D) {
  random_patterns<3>(generate_box({0, 0, 0}, {1, 1, 1}, 5, 5, 5), 23);
}

}  // namespace
