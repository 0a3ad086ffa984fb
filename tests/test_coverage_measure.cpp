// Survey coverage: the reference samples with a measured point within the tolerance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "semioctree/sim/coverage/measure.h"
#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/ground_truth.h"
#include "support/coverage_scenes.h"

namespace {

using namespace semioctree::sim;
using namespace semioctree::testing;

TEST(Coverage, CountsSamplesWithAPointWithinTheTolerance) {
  CoverageReference ref;
  for (double x : {-1.0, -0.0149, 0.0, 0.0151, 2.0}) ref.points.emplace_back(x, -0.5, 10.0);
  ref.points.emplace_back(5.0, 5.0, 5.0);
  const Coverage none = measure_coverage(ref, std::vector<Eigen::Vector3d>{});
  EXPECT_EQ(none.reference_points, 6u);
  EXPECT_EQ(none.covered, 0u);
  EXPECT_EQ(none.percent, 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Eigen::Vector3d> measured = {
      {-1.0 + 0.029, -0.5, 10.0},               // 2.9 cm from -1.0, in the next cell
      {2.0, -0.5 + 0.031, 10.0},                // 3.1 cm from 2.0
      {0.0, -0.5, 10.0},                        // 1.49, 0 and 1.51 cm from three samples
      {5.0 + 0.017, 5.0 + 0.017, 5.0 + 0.017},  // 2.94 cm from (5, 5, 5)
      {nan, -0.5, 10.0}};
  const Coverage c = measure_coverage(ref, measured);
  // Everything but 2.0 is covered.
  EXPECT_EQ(c.covered, 5u);
  EXPECT_NEAR(c.percent, 500.0 / 6.0, 1e-9);
  // At 2.85 cm, -1.0 (2.9 cm) and (5, 5, 5) (2.94 cm) drop out too.
  EXPECT_EQ(measure_coverage(ref, measured, 0.0285).covered, 3u);
  std::vector<Eigen::Vector3f> as_float;
  for (const auto& p : measured) as_float.push_back(p.cast<float>());
  EXPECT_EQ(measure_coverage(ref, as_float, 0.0285).covered, 3u);
  // The flags behind those counts, sample by sample.
  EXPECT_EQ(covered_samples(ref, as_float),
            (std::vector<bool>{true, true, true, true, false, true}));
  EXPECT_EQ(count_covered(covered_samples(ref, as_float)).covered, c.covered);
  EXPECT_EQ(covered_samples(ref, as_float, 0.0285),
            (std::vector<bool>{false, true, true, true, false, false}));
  EXPECT_EQ(measure_coverage(CoverageReference{}, measured).percent, 0.0);
}

TEST(Coverage, TheAccumulatorOfScansEqualsTheCoverageOfAllTheirPoints) {
  CoverageReference ref;
  for (int i = 0; i < 40; ++i) ref.points.emplace_back(0.1 * i, 0.0, 1.0);
  CoverageAccumulator acc(ref);
  EXPECT_EQ(acc.covered(), std::vector<bool>(40, false));
  EXPECT_EQ(acc.count().covered, 0u);
  // Two "scans": the first covers samples 0-19, the second 10-29 (overlapping); a third
  // point 2 cm off sample 35 and one 4 cm off sample 37.
  std::vector<Eigen::Vector3f> first, second, all;
  for (int i = 0; i < 20; ++i) first.emplace_back(0.1f * float(i), 0.01f, 1.0f);
  for (int i = 10; i < 30; ++i) second.emplace_back(0.1f * float(i), -0.01f, 1.0f);
  second.emplace_back(3.5f, 0.0f, 1.02f);
  second.emplace_back(3.7f, 0.0f, 1.04f);
  acc.add(first);
  EXPECT_EQ(acc.count().covered, 20u);
  acc.add(second);
  all = first;
  all.insert(all.end(), second.begin(), second.end());
  EXPECT_EQ(acc.covered(), covered_samples(ref, all));
  EXPECT_EQ(acc.count().covered, 31u);  // 0-29 and 35
  EXPECT_FALSE(acc.covered()[37]);
  // What the second scan alone flags; the accumulated flags stay as they are.
  std::vector<bool> second_only(40, false);
  for (int i = 10; i < 30; ++i) second_only[std::size_t(i)] = true;
  second_only[35] = true;
  EXPECT_EQ(acc.flags_of(second), second_only);
  EXPECT_EQ(acc.count().covered, 31u);
  // A point that is not finite flags nothing.
  acc.add(Eigen::Vector3d(std::nan(""), 0.0, 1.0));
  EXPECT_EQ(acc.count().covered, 31u);
  EXPECT_THROW(CoverageAccumulator(ref, 0.0), std::invalid_argument);
}

// Points added on several workers flag what they flag one by one, whatever the workers.
TEST(Coverage, PointsAddedOnWorkersFlagWhatTheyFlagOneByOne) {
  CoverageReference ref;
  for (int i = 0; i < 3000; ++i) ref.points.emplace_back(0.02 * (i % 60), 0.02 * (i / 60), 1.0);
  // 100 000 points (several workers' chunks) near a third of the samples, a few not finite.
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 100000; ++i) {
    const int s = (i * 7) % 3000;
    if (s % 3 != 0) continue;
    points.emplace_back(0.02 * (s % 60) + 0.001 * (i % 11), 0.02 * (s / 60), 1.0 + 0.002 * (i % 5));
  }
  points.emplace_back(std::nan(""), 0.0, 1.0);
  CoverageAccumulator one_by_one(ref);
  for (const Eigen::Vector3d& p : points) one_by_one.add(p);
  ASSERT_GT(one_by_one.count().covered, 500u);
  ASSERT_LT(one_by_one.count().covered, 3000u);
  for (const unsigned threads : {1u, 2u, 3u}) {
    CoverageAccumulator acc(ref);
    acc.add(
        points.size(), [&](std::size_t i) { return points[i]; }, threads);
    EXPECT_EQ(acc.covered(), one_by_one.covered()) << threads << " workers";
  }
}

// Points in sweep order (many in a row near the same samples) and the same points
// shuffled flag exactly the samples a test of every sample against every point flags.
TEST(Coverage, PointsInRunsOrShuffledFlagWhatABruteForceTestFlags) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> in_box(0.0, 0.6), jitter(-0.004, 0.004);
  CoverageReference ref;
  for (int i = 0; i < 2000; ++i) ref.points.emplace_back(in_box(rng), in_box(rng), in_box(rng));
  // Sweeps: runs of points 4 mm apart along lines through the box.
  std::vector<Eigen::Vector3d> sweep;
  for (int line = 0; line < 60; ++line) {
    const Eigen::Vector3d from(in_box(rng), in_box(rng), in_box(rng));
    const Eigen::Vector3d step =
        Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)).normalized() * 0.004;
    for (int k = 0; k < 300; ++k)
      sweep.push_back(from + k * step + Eigen::Vector3d(jitter(rng), jitter(rng), 0.0));
  }
  std::vector<Eigen::Vector3d> shuffled = sweep;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const double tolerance = 0.03;
  // The samples with a point within the tolerance, every sample tested against every point.
  auto brute_force = [&](const std::vector<Eigen::Vector3d>& points) {
    std::vector<bool> flags(ref.points.size(), false);
    for (std::size_t s = 0; s < ref.points.size(); ++s)
      for (const Eigen::Vector3d& p : points)
        if ((p - ref.points[s]).squaredNorm() <= tolerance * tolerance) {
          flags[s] = true;
          break;
        }
    return flags;
  };
  const std::vector<bool> brute = brute_force(sweep);
  const std::size_t flagged = std::size_t(std::count(brute.begin(), brute.end(), true));
  ASSERT_GT(flagged, 200u);
  ASSERT_LT(flagged, 1800u);
  for (const auto* points : {&sweep, &shuffled}) {
    std::vector<Eigen::Vector3f> as_float;
    std::vector<Eigen::Vector3d> floats_as_double;  // what covered_samples reads
    for (const Eigen::Vector3d& p : *points) {
      as_float.push_back(p.cast<float>());
      floats_as_double.push_back(as_float.back().cast<double>());
    }
    const std::vector<bool> from_floats = brute_force(floats_as_double);
    EXPECT_EQ(covered_samples(ref, as_float, tolerance), from_floats);
    for (const unsigned threads : {1u, 2u}) {
      CoverageAccumulator acc(ref, tolerance);
      acc.add(
          points->size(), [&](std::size_t i) { return (*points)[i]; }, threads);
      EXPECT_EQ(acc.covered(), brute) << threads << " workers";
    }
  }
}

TEST(Coverage, AFullScanOfTheEmptyBoxRoomCoversItsReference) {
  // box-room: walls, floor and ceiling only (no furniture), a convex room: one scan
  // from the start sees every inner wall face the reference holds.
  const GroundTruth truth(load("box-room"));
  ASSERT_TRUE(truth.scene().boxes.empty() && truth.scene().cylinders.empty() &&
              truth.scene().meshes.empty());
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<Eigen::Vector3d> points = scan_from_start(truth);
  ASSERT_GT(points.size(), 100000u);
  const Coverage full = measure_coverage(ref, points);
  std::cout << "box-room, one scan from the start: " << full.covered << " of "
            << full.reference_points << " = " << full.percent << " %\n";
  EXPECT_EQ(full.reference_points, ref.visible.size());
  EXPECT_GE(full.percent, 99.0);

  EXPECT_EQ(measure_coverage(ref, std::vector<Eigen::Vector3f>{}).percent, 0.0);

  // 5 cm along x: the points of the east and west walls leave their faces by 5 cm,
  // those of the north and south walls slide along them (about 60 % of the walls' area).
  std::vector<Eigen::Vector3d> shifted = points;
  for (auto& p : shifted) p.x() += 0.05;
  const Coverage along_x = measure_coverage(ref, shifted);
  EXPECT_LT(along_x.percent, full.percent - 30.0) << along_x.percent;
  // 5 cm diagonally in the xy-plane: every wall's points are 3.5 cm off its face.
  shifted = points;
  const Eigen::Vector3d diagonal = Eigen::Vector3d(1, 1, 0).normalized() * 0.05;
  for (auto& p : shifted) p += diagonal;
  const Coverage diag = measure_coverage(ref, shifted);
  std::cout << "shifted 5 cm: along x " << along_x.percent << " %, diagonally " << diag.percent
            << " %\n";
  EXPECT_LT(diag.percent, 5.0);
}

}  // namespace
