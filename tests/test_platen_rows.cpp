// The platens' rows (kernels/model.hpp, PlatenData): one per node they act on, not one per node of
// the mesh; carried to the nodes' new places when contact's surfaces grow (carry_platen_rows,
// Platens::follow_surfaces); stored in checkpoints per node id, as before they were compacted.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "kernels/platens.hpp"
#include "mesh/mesh.hpp"
#include "solver/contact_system.hpp"
#include "solver/run.hpp"
#include "solver/simulation.hpp"

namespace {

using namespace fdem;

const std::string kImpact2D = std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_2d/case.json";

template <class V>
auto on_host(const V& v) {
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
}

// Rows for the nodes `ids` of two platens, row b holding (b + 1) times 10, 100, 1000 (area,
// allowance, spring).
PlatenData<3> rows_of(const std::vector<int>& ids) {
  PlatenData<3> d;
  d.platens.count = 2;
  d.nb = static_cast<int>(ids.size());
  d.bnode = Kokkos::View<int*>("bnode", d.nb);
  d.barea = Kokkos::View<double*>("barea", d.nb);
  d.platen_fs = Kokkos::View<double** [3]>("fs", 2, d.nb);
  d.platen_g0 = Kokkos::View<double**>("g0", 2, d.nb);
  auto bn = Kokkos::create_mirror_view(d.bnode);
  auto a = Kokkos::create_mirror_view(d.barea);
  auto fs = Kokkos::create_mirror_view(d.platen_fs);
  auto g0 = Kokkos::create_mirror_view(d.platen_g0);
  for (int b = 0; b < d.nb; ++b) {
    bn(b) = ids[b];
    a(b) = 10.0 * (b + 1);
    for (int p = 0; p < 2; ++p) {
      g0(p, b) = -100.0 * (b + 1) - p;
      for (int k = 0; k < 3; ++k) fs(p, b, k) = 1000.0 * (b + 1) + 10 * p + k;
    }
  }
  Kokkos::deep_copy(d.bnode, bn);
  Kokkos::deep_copy(d.barea, a);
  Kokkos::deep_copy(d.platen_fs, fs);
  Kokkos::deep_copy(d.platen_g0, g0);
  return d;
}

// place(i) = 1 + node i's place in `list` (0 elsewhere) over nn nodes.
Kokkos::View<int*> places(const std::vector<int>& list, int nn) {
  Kokkos::View<int*> place("place", nn);
  auto h = Kokkos::create_mirror_view(place);
  for (size_t b = 0; b < list.size(); ++b) h(list[b]) = static_cast<int>(b) + 1;
  Kokkos::deep_copy(place, h);
  return place;
}

TEST(PlatenRows, CarriedToTheirNodesPlacesInTheNewList) {
  const PlatenData<3> from = rows_of({2, 5, 9});
  PlatenData<3> to = rows_of({1, 2, 5, 7, 9});
  Kokkos::deep_copy(to.barea, 0.0);
  Kokkos::deep_copy(to.platen_fs, 0.0);
  Kokkos::deep_copy(to.platen_g0, 0.0);
  EXPECT_EQ(carry_platen_rows<3>(from, from.nb, to, places({1, 2, 5, 7, 9}, 10)), 0);
  const auto a = on_host(to.barea);
  const auto g0 = on_host(to.platen_g0);
  const auto fs = on_host(to.platen_fs);
  const int old_row[5] = {-1, 0, 1, -1, 2};  // the new rows' old ones (-1: a new node)
  for (int c = 0; c < 5; ++c) {
    const double s = old_row[c] + 1.0;  // (0 for a new node: its rows start at zero)
    EXPECT_EQ(a(c), 10.0 * s) << "row " << c;
    for (int p = 0; p < 2; ++p) {
      EXPECT_EQ(g0(p, c), old_row[c] < 0 ? 0.0 : -100.0 * s - p);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(fs(p, c, k), old_row[c] < 0 ? 0.0 : 1000.0 * s + 10 * p + k);
    }
  }
  // a node of the old list missing from the new one: counted (follow_surfaces refuses it)
  EXPECT_EQ(carry_platen_rows<3>(from, from.nb, to, places({1, 2, 7, 9}, 10)), 1);
}

// The 2D impact with contact: the platen acts on the surface nodes only, its rows follow them as
// cracks are handed over, and a checkpoint holds them per node id and loads them back.
TEST(PlatenRows, OnePerSurfaceNodeAndPerNodeIdInCheckpoints) {
  const Case c = load_case(kImpact2D, {"parameters.speed=15", "parameters.h=0.008"});
  const HostMesh mesh = prepare_mesh(c);
  Simulation<2> sim(c, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  const int nb0 = sim.m.nb;
  EXPECT_EQ(nb0, sim.contact()->own_surface_nodes());
  EXPECT_EQ(static_cast<int>(sim.m.barea.extent(0)), nb0);
  EXPECT_EQ(static_cast<int>(sim.m.platen_fs.extent(1)), nb0);
  EXPECT_LT(nb0, sim.m.nn / 2) << "the intact disc's surface is its outer boundary";
  while (sim.contact()->handed_over() == 0 && sim.step_count < 4000) sim.step(false);
  for (int n = 0; n < 200; ++n) sim.step(false);  // (and springs on the plate)
  ASSERT_GT(sim.contact()->handed_over(), 0) << "no crack reached contact";
  ASSERT_GT(sim.m.nb, nb0);
  EXPECT_EQ(static_cast<int>(sim.m.platen_g0.extent(1)), sim.m.nb);

  StateArrays s;
  sim.save_state(s);
  const std::vector<double>& area = s.f64.at("model/platen_area");
  const std::vector<double>& fs = s.f64.at("model/platen_fs");
  ASSERT_EQ(area.size(), static_cast<size_t>(sim.m.nn));
  ASSERT_EQ(fs.size(), static_cast<size_t>(sim.m.nn) * 2);
  const auto bn = on_host(sim.m.bnode);
  const auto a = on_host(sim.m.barea);
  const auto f = on_host(sim.m.platen_fs);
  std::vector<int> row(sim.m.nn, -1);
  int springs = 0;
  for (int b = 0; b < sim.m.nb; ++b) row[bn(b)] = b;
  for (int i = 0; i < sim.m.nn; ++i) {
    const int b = row[i];
    ASSERT_EQ(area[i], b < 0 ? 0.0 : a(b)) << "node " << i;
    for (int k = 0; k < 2; ++k) ASSERT_EQ(fs[2 * static_cast<size_t>(i) + k], b < 0 ? 0.0 : f(0, b, k));
    springs += b >= 0 && f(0, b, 0) != 0.0;
  }
  EXPECT_GT(springs, 0) << "no shear spring on the plate to carry";

  Simulation<2> again(c, mesh);
  again.load_state(s);
  ASSERT_EQ(again.m.nb, sim.m.nb);
  const auto bn2 = on_host(again.m.bnode);
  const auto a2 = on_host(again.m.barea);
  const auto f2 = on_host(again.m.platen_fs);
  const auto g1 = on_host(sim.m.platen_g0), g2 = on_host(again.m.platen_g0);
  for (int b = 0; b < sim.m.nb; ++b) {
    ASSERT_EQ(bn2(b), bn(b));
    ASSERT_EQ(a2(b), a(b));
    ASSERT_EQ(g2(0, b), g1(0, b));
    for (int k = 0; k < 2; ++k) ASSERT_EQ(f2(0, b, k), f(0, b, k));
  }
}

}  // namespace
