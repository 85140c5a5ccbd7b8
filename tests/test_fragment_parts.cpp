// The joining of every process's fragment tokens on process 0 (src/solver/fragment_parts.hpp):
// classes through the edges, numbered by their smallest key, the classes without own elements
// dropped, and damaged buffers refused. The whole labelling over processes is checked against the
// run on one process by tests/mpi/check_runs.py.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "solver/fragment_parts.hpp"

namespace fdem {
namespace {

// One process's buffer: tokens of (key, mass, count) and edges (token, process, token).
std::vector<double> buffer(const std::vector<std::vector<double>>& tokens,
                           const std::vector<std::vector<double>>& edges) {
  std::vector<double> b = {double(tokens.size()), double(edges.size())};
  for (const auto& t : tokens) b.insert(b.end(), t.begin(), t.end());
  for (const auto& e : edges) b.insert(b.end(), e.begin(), e.end());
  return b;
}

std::vector<double> three_processes() {
  std::vector<double> all;
  // process 0: token 0 (key 5, two elements), token 1 (key 0, one element)
  for (double x : buffer({{5, 1.0, 2}, {0, 2.0, 1}}, {})) all.push_back(x);
  // process 1: token 0 (key 3, one element) joined to process 0's token 0; token 1 (key 1, a
  // ghost's view: no own element) joined to process 2's token 0
  for (double x : buffer({{3, 1.0, 1}, {1, 0.0, 0}}, {{0, 0, 0}, {1, 2, 0}})) all.push_back(x);
  // process 2: token 0 (key 7, one element); token 1 (key 2, no own element, no edge)
  for (double x : buffer({{7, 4.0, 1}, {2, 0.0, 0}}, {{0, 1, 1}})) all.push_back(x);
  return all;
}

TEST(FragmentParts, TokensJoinThroughEdgesAndAreNumberedBySmallestKey) {
  std::vector<double> values;
  std::vector<int> offset;
  const std::vector<int> rep = join_tokens(three_processes(), 3, 3, values, offset);
  EXPECT_EQ(offset, (std::vector<int>{0, 2, 4, 6}));
  ASSERT_EQ(values.size(), 18u);
  EXPECT_EQ(values[3 * 2], 3.0);  // process 1's token 0
  // classes: {0.0, 1.0}, {0.1}, {1.1, 2.0}, {2.1}
  EXPECT_EQ(rep[0], rep[2]);
  EXPECT_EQ(rep[3], rep[4]);
  EXPECT_NE(rep[0], rep[1]);
  EXPECT_NE(rep[0], rep[3]);
  EXPECT_NE(rep[5], rep[3]);
  int n = -1;
  const std::vector<int> cls = number_classes(rep, values, 3, 0, 2, n);
  // keys: {0.0, 1.0}: 3; {0.1}: 0; {1.1, 2.0}: 1 (its ghost's key counts); {2.1}: no own element
  EXPECT_EQ(n, 3);
  EXPECT_EQ(cls, (std::vector<int>{2, 0, 2, 1, 1, -1}));
}

TEST(FragmentParts, DamagedBuffersAreRefused) {
  std::vector<double> values;
  std::vector<int> offset;
  std::vector<double> all = three_processes();
  all.pop_back();  // the last edge cut short
  EXPECT_THROW(join_tokens(all, 3, 3, values, offset), std::logic_error);
  std::vector<double> bad = buffer({{0, 1.0, 1}}, {{0, 1, 5}});  // process 1 has no token 5
  for (double x : buffer({{1, 1.0, 1}}, {})) bad.push_back(x);
  EXPECT_THROW(join_tokens(bad, 2, 3, values, offset), std::logic_error);
}

// summary.json fragments.largest from pieces (elements, or processes' parts of fragments): the
// mass-weighted centroid and the box of the pieces' boxes, largest fragment first, in 2D the first
// two of the three coordinates each piece carries.
TEST(FragmentParts, LargestFragmentsFromPieces) {
  FragmentPieces p;
  const double a[3] = {1.0, 2.0, 0.0}, b[3] = {3.0, 2.0, 0.0}, c[3] = {-1.0, -1.0, 0.0};
  double ma[3], mb[3], mc[3];
  for (int k = 0; k < 3; ++k) {
    ma[k] = 2.0 * a[k];
    mb[k] = 6.0 * b[k];
    mc[k] = 1.0 * c[k];
  }
  p.add(1, 2.0, ma, a, a);  // fragment 1: two pieces of 2 and 6 kg
  p.add(0, 1.0, mc, c, c);  // fragment 0: one of 1 kg
  p.add(1, 6.0, mb, b, b);
  const nlohmann::json j = largest_fragments(p, {1.0, 8.0}, 2);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_DOUBLE_EQ(j[0]["fraction"].get<double>(), 8.0 / 9.0);
  EXPECT_EQ(j[0]["reference_centroid"].size(), 2u);
  EXPECT_DOUBLE_EQ(j[0]["reference_centroid"][0].get<double>(), (2.0 * 1.0 + 6.0 * 3.0) / 8.0);
  EXPECT_DOUBLE_EQ(j[0]["reference_centroid"][1].get<double>(), 2.0);
  EXPECT_EQ(j[0]["reference_box_min"], (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(j[0]["reference_box_max"], (std::vector<double>{3.0, 2.0}));
  EXPECT_EQ(j[1]["reference_centroid"], (std::vector<double>{-1.0, -1.0}));
}

}  // namespace
}  // namespace fdem
