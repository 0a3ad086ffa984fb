// The dense-array homogeneous grid of the benchmarks (support/dense_grid.h): its region and
// occupancy against discretize's, and its occlusion study against brute force (every
// occupied voxel tested against every segment) on a tiny map, a wall with a hole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "semioctree/discretize.h"
#include "support/dense_grid.h"

namespace semioctree::testing {
namespace {

constexpr double kLeaf = 0.05;

pcl::PointXYZ point(double x, double y, double z) {
  return pcl::PointXYZ{float(x), float(y), float(z)};
}

// A room 1.2 × 0.8 × 0.8 m: a wall one voxel thick across it at x = 0.60–0.65 m with a
// square hole of 0.2 m at y, z = 0.30–0.50 m, and a point in two opposite corners so that
// the bounds cover the room.
Cloud wall_with_hole() {
  Cloud cloud;
  for (int j = 0; j < 16; ++j)
    for (int k = 0; k < 16; ++k) {
      const bool hole = j >= 6 && j < 10 && k >= 6 && k < 10;
      if (!hole) cloud.push_back(point(0.625, (j + 0.5) * kLeaf, (k + 0.5) * kLeaf));
    }
  cloud.push_back(point(0.02, 0.02, 0.02));
  cloud.push_back(point(1.18, 0.78, 0.02));
  return cloud;
}

// Whether the segment a → b crosses the inside of the box [lo, lo + kLeaf)³ (slabs).
bool crosses_box(const Point3& a, const Point3& b, const Point3& lo) {
  const double from[3] = {a.x, a.y, a.z}, d[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
  const double box_lo[3] = {lo.x, lo.y, lo.z};
  double t0 = 0, t1 = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const double l = box_lo[axis], h = box_lo[axis] + kLeaf;
    if (d[axis] == 0) {
      if (from[axis] <= l || from[axis] >= h) return false;
      continue;
    }
    double ta = (l - from[axis]) / d[axis], tb = (h - from[axis]) / d[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 - t0 > 1e-12;
}

// Brute force: blocked if the segment crosses an occupied voxel other than the scanner's
// and the target's.
bool blocked_brute_force(const DenseGrid& grid, const Point3& a, const Point3& b) {
  std::int64_t ai, aj, ak, bi, bj, bk;
  grid.voxel_of(a, ai, aj, ak);
  grid.voxel_of(b, bi, bj, bk);
  for (std::int64_t k = 0; k < grid.size(2); ++k)
    for (std::int64_t j = 0; j < grid.size(1); ++j)
      for (std::int64_t i = 0; i < grid.size(0); ++i) {
        if (grid.label(i, j, k) != Label::kOccupied) continue;
        if ((i == ai && j == aj && k == ak) || (i == bi && j == bj && k == bk)) continue;
        const Point3 c = grid.centre(i, j, k);
        if (crosses_box(a, b, {c.x - kLeaf / 2, c.y - kLeaf / 2, c.z - kLeaf / 2})) return true;
      }
  return false;
}

// A scanner off the voxel lattice (no line through a voxel's edge or corner), with every
// range and elevation allowed.
ScannerView open_view() {
  ScannerView view(Point3(0.213, 0.401, 0.397));
  view.min_range = 0;
  view.elevation_min_deg = -90;
  view.elevation_max_deg = 90;
  return view;
}

TEST(DenseGrid, CoversTheRegionDiscretizeCoversWithTheSameOccupiedVoxels) {
  const Cloud cloud = wall_with_hole();
  const double ceiling = 0.78;
  const DenseGrid grid = DenseGrid::from_cloud(cloud, ceiling, kLeaf, 0.4);
  DiscretizeReport report;
  const auto tree = discretize(cloud, ceiling, {kLeaf, 0.4, 0.4}, &report);
  // 0.4 m coarse voxels: 8³ leaves each. The room spans 3 × 2 × 2 of them.
  EXPECT_EQ(grid.size(0), 24);
  EXPECT_EQ(grid.size(1), 16);
  EXPECT_EQ(grid.size(2), 16);
  EXPECT_EQ(grid.voxels(), tree->statistics().coarse_voxels * 8 * 8 * 8);
  EXPECT_EQ(grid.count(Label::kOccupied), report.occupied_leaves);
  std::int64_t i, j, k;
  ASSERT_TRUE(grid.voxel_of({0.62, 0.1, 0.1}, i, j, k));
  EXPECT_EQ(grid.label(i, j, k), Label::kOccupied);
  ASSERT_TRUE(grid.voxel_of({0.62, 0.4, 0.4}, i, j, k));  // in the hole
  EXPECT_EQ(grid.label(i, j, k), Label::kEmpty);
}

TEST(DenseGrid, StudyAgreesWithBruteForceOnAWallWithAHole) {
  DenseGrid grid = DenseGrid::from_cloud(wall_with_hole(), 0.78, kLeaf, 0.4);
  const DenseGrid before = grid;
  const ScannerView view = open_view();
  const DenseOcclusionReport report = study_occlusion_dense(grid, view, 2);
  std::size_t visible = 0, occluded = 0, mismatches = 0;
  for (std::int64_t k = 0; k < grid.size(2); ++k)
    for (std::int64_t j = 0; j < grid.size(1); ++j)
      for (std::int64_t i = 0; i < grid.size(0); ++i) {
        if (before.label(i, j, k) == Label::kOccupied) {
          EXPECT_EQ(grid.label(i, j, k), Label::kOccupied);
          continue;
        }
        const bool seen = !blocked_brute_force(before, view.position, grid.centre(i, j, k));
        ++(seen ? visible : occluded);
        mismatches += grid.label(i, j, k) != (seen ? Label::kEmpty : Label::kOccluded);
      }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(report.visible, visible);
  EXPECT_EQ(report.occluded, occluded);
  EXPECT_EQ(report.occupied, grid.count(Label::kOccupied));
  EXPECT_EQ(report.visible, grid.count(Label::kEmpty));
  EXPECT_EQ(report.occluded, grid.count(Label::kOccluded));
  // The wall hides most of what lies behind it; the hole lets some of it be seen.
  EXPECT_GT(occluded, 1000u);
  EXPECT_GT(visible, 3000u);

  std::int64_t i, j, k;
  ASSERT_TRUE(grid.voxel_of({1.0, 0.4, 0.4}, i, j, k));  // behind the hole
  EXPECT_EQ(grid.label(i, j, k), Label::kEmpty);
  ASSERT_TRUE(grid.voxel_of({1.0, 0.1, 0.1}, i, j, k));  // behind the wall
  EXPECT_EQ(grid.label(i, j, k), Label::kOccluded);
  ASSERT_TRUE(grid.voxel_of({0.4, 0.1, 0.7}, i, j, k));  // in front of the wall
  EXPECT_EQ(grid.label(i, j, k), Label::kEmpty);
}

TEST(DenseGrid, SegmentsFromOutsideTheGridAreTraversedToo) {
  const DenseGrid grid = DenseGrid::from_cloud(wall_with_hole(), 0.78, kLeaf, 0.4);
  const Point3 outside(-0.513, 0.407, 0.391);  // before the room's face at x = 0
  EXPECT_TRUE(grid.segment_blocked(outside, {1.013, 0.102, 0.111}));   // through the wall
  EXPECT_FALSE(grid.segment_blocked(outside, {1.013, 0.402, 0.411}));  // through the hole
  for (double y = 0.01; y < 0.8; y += 0.07)
    for (double z = 0.02; z < 0.8; z += 0.07) {
      const Point3 b(1.11, y, z);
      EXPECT_EQ(grid.segment_blocked(outside, b), blocked_brute_force(grid, outside, b))
          << "to " << y << ", " << z;
    }
}

TEST(DenseGrid, StudyKeepsToTheScannersLimits) {
  DenseGrid grid = DenseGrid::from_cloud(wall_with_hole(), 0.78, kLeaf, 0.4);
  ScannerView view = open_view();
  view.max_range = 0.3;
  view.elevation_min_deg = 0;  // nothing below the optical centre
  const DenseOcclusionReport one = study_occlusion_dense(grid, view, 1);
  std::int64_t i, j, k;
  ASSERT_TRUE(grid.voxel_of({0.4, 0.4, 0.5}, i, j, k));  // within range, above
  EXPECT_EQ(grid.label(i, j, k), Label::kEmpty);
  ASSERT_TRUE(grid.voxel_of({0.4, 0.4, 0.3}, i, j, k));  // within range, below
  EXPECT_EQ(grid.label(i, j, k), Label::kOccluded);
  ASSERT_TRUE(grid.voxel_of({0.55, 0.4, 0.45}, i, j, k));  // beyond the range
  EXPECT_EQ(grid.label(i, j, k), Label::kOccluded);
  // The same labels on any number of threads.
  DenseGrid again = DenseGrid::from_cloud(wall_with_hole(), 0.78, kLeaf, 0.4);
  const DenseOcclusionReport two = study_occlusion_dense(again, view, 3);
  EXPECT_EQ(one.visible, two.visible);
  EXPECT_EQ(one.occluded, two.occluded);
  EXPECT_EQ(one.segments, two.segments);
}

}  // namespace
}  // namespace semioctree::testing
