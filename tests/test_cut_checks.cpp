// Where a part's contact zones were taken (solver/cut_checks.hpp, CutChecks::start): at the start
// of a run the own rows of the reference positions themselves (no copy), after a cut or at a
// restart a copy of the positions the part was cut at; a part whose cut positions do not match its
// nodes is refused.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "solver/cut_checks.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

TEST(CutChecks, ZonesTakenAtTheReferencePositionsShareThem) {
  Simulation<2> sim(fdem_test::basic_case(2), generate_crossed_rectangle(0, 0, 1, 1, 4, 4, "body"));
  Model<2> m = sim.m;  // (the same Views)
  m.nn_own = m.nn - 5;  // as a part with five ghost nodes
  SubMesh part;
  part.contact_reach = 1e-3;
  CutChecks<2> checks;
  checks.start(part, m, true);
  const auto& xc = checks.cut_positions();
  ASSERT_EQ(static_cast<int>(xc.extent(0)), m.nn - 5);
  EXPECT_EQ(xc.data(), m.X.data()) << "a copy of the reference positions";

  // cut during the run: the positions of the cut, copied
  part.cut_x.assign(static_cast<size_t>(m.nn) * 2, 0.0);
  for (size_t j = 0; j < part.cut_x.size(); ++j) part.cut_x[j] = 0.25 * static_cast<double>(j);
  CutChecks<2> after;
  after.start(part, m, true);
  const auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), after.cut_positions());
  ASSERT_EQ(static_cast<int>(h.extent(0)), m.nn - 5);
  EXPECT_NE(after.cut_positions().data(), m.X.data());
  for (int i = 0; i < m.nn - 5; ++i)
    for (int k = 0; k < 2; ++k) ASSERT_EQ(h(i, k), 0.25 * (2 * i + k)) << "node " << i;

  // cut positions of another part's size
  part.cut_x.resize(static_cast<size_t>(m.nn) * 2 - 2);
  CutChecks<2> wrong;
  EXPECT_THROW(wrong.start(part, m, true), InputError);
}

}  // namespace
