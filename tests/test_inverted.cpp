// Elements turned inside out during a run are detected and reported with their position
// (Simulation::check_inverted; check_stability warns once per run).
#include <gtest/gtest.h>

#include <string>

#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

template <int D>
void inverted_test(const HostMesh& mesh) {
  auto c = fdem_test::basic_case(D);
  Simulation<D> sim(c, mesh);
  std::string where;
  EXPECT_EQ(sim.check_inverted(&where), 0);
  EXPECT_TRUE(where.empty());
  // push vertex 0 of element 5 through its opposite face (mirror it at the face's plane)
  auto x = Kokkos::create_mirror_view(sim.m.x);
  auto el = Kokkos::create_mirror_view(sim.m.elem);
  Kokkos::deep_copy(x, sim.m.x);
  Kokkos::deep_copy(el, sim.m.elem);
  const int e = 5, n0 = el(e, 0);
  double c0[3] = {0, 0, 0};
  for (int a = 1; a <= D; ++a)
    for (int k = 0; k < D; ++k) c0[k] += x(el(e, a), k) / D;
  for (int k = 0; k < D; ++k) x(n0, k) = 2 * c0[k] - x(n0, k);  // through the opposite face's centroid
  Kokkos::deep_copy(sim.m.x, x);
  const long n = sim.check_inverted(&where);
  EXPECT_GE(n, 1);
  // node n0 may be shared by other elements (no interfaces here): the first inverted is <= e
  EXPECT_NE(where.find("turned inside out"), std::string::npos) << where;
  EXPECT_NE(where.find("centroid at ("), std::string::npos) << where;
  std::printf("%s\n", where.c_str());
}

TEST(Inverted, DetectedAndLocated2D) {
  inverted_test<2>(generate_crossed_rectangle(0, 0, 1, 1, 3, 3, "body"));
}

TEST(Inverted, DetectedAndLocated3D) { inverted_test<3>(generate_box({0, 0, 0}, {1, 1, 1}, 2, 2, 2, "body")); }

}  // namespace
