// Survey plans with perfect knowledge: greedy, then local search.
#include <gtest/gtest.h>

#include <cstddef>
#include <initializer_list>
#include <stdexcept>
#include <vector>

#include "semioctree/sim/coverage/plan.h"

namespace {

using namespace semioctree::sim;

// Six samples; from the first position nothing is seen. Greedy takes A (4 new)
// then B (1 new; C too, B comes first) and covers 5; swapping A for C covers all.
TEST(CoveragePlan, GreedyThenLocalSearch) {
  auto set = [](std::initializer_list<int> members) {
    std::vector<bool> s(6, false);
    for (int i : members) s[std::size_t(i)] = true;
    return s;
  };
  const std::vector<std::vector<bool>> covered = {set({}), set({0, 1, 2, 3}), set({0, 1, 4}),
                                                  set({2, 3, 5})};
  const CoveragePlan greedy = greedy_coverage_plan(covered, 0, 3);
  EXPECT_EQ(greedy.views, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_NEAR(greedy.percent, 500.0 / 6.0, 1e-9);
  const CoveragePlan best = improve_coverage_plan(covered, greedy);
  EXPECT_EQ(best.views, (std::vector<std::size_t>{0, 3, 2}));
  EXPECT_NEAR(best.percent, 100.0, 1e-9);
  // One scan: the first position alone.
  EXPECT_NEAR(greedy_coverage_plan(covered, 1, 1).percent, 400.0 / 6.0, 1e-9);
  EXPECT_THROW(greedy_coverage_plan(covered, 4, 2), std::invalid_argument);
  EXPECT_THROW(greedy_coverage_plan({set({0}), std::vector<bool>(3)}, 0, 2), std::invalid_argument);
}

// Once no position adds a sample, a plan ends: asked for more scans it never
// repeats a position (at 100 %, and when what is left is seen from nowhere).
TEST(CoveragePlan, EndsWhenNothingIsLeftToAdd) {
  auto set = [](std::initializer_list<int> members) {
    std::vector<bool> s(5, false);
    for (int i : members) s[std::size_t(i)] = true;
    return s;
  };
  const std::vector<std::vector<bool>> all = {set({0, 1}), set({2, 3, 4}), set({1, 2})};
  const CoveragePlan full = greedy_coverage_plan(all, 0, 3);
  EXPECT_EQ(full.views, (std::vector<std::size_t>{0, 1}));
  EXPECT_NEAR(full.percent, 100.0, 1e-9);
  EXPECT_EQ(improve_coverage_plan(all, full).views.size(), 2u);
  // Sample 4 is seen from nowhere: 80 % is all there is.
  const std::vector<std::vector<bool>> partial = {set({0}), set({1, 2}), set({3}), set({0, 3})};
  const CoveragePlan most = greedy_coverage_plan(partial, 0, 4);
  EXPECT_EQ(most.views, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_NEAR(most.percent, 80.0, 1e-9);
}

}  // namespace
