// Preprocessing (paper 2.1): levelling by RANSAC floor/ceiling planes (Eq 1-2; the floor
// alone without a ceiling),
// floor to z = 0, z-histogram floor/ceiling removal at 2σ, decimation.
#include <gtest/gtest.h>
#include <pcl/common/centroid.h>
#include <pcl/common/transforms.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "semioctree/preprocess.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

// Eq 1 angles of the normal of the tilted floor.
std::pair<double, double> eq1_angles(double alpha_deg, double beta_deg) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(beta_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(alpha_deg * M_PI / 180, Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  const Eigen::Vector3d n = R * Eigen::Vector3d::UnitZ();
  return {std::atan(n.x() / n.z()) * 180 / M_PI, std::atan(n.y() / n.z()) * 180 / M_PI};
}

// The cloud tilted by (a, b) was levelled by its floor alone: Eq 1 angles within 0.1°, no
// ceiling found.
void expect_levelled_without_ceiling(const PreprocessResult& r, double a, double b) {
  const auto [want_a, want_b] = eq1_angles(a, b);
  EXPECT_NEAR(r.alpha_deg, want_a, 0.1) << "alpha for tilt " << a << ", " << b;
  EXPECT_NEAR(r.beta_deg, want_b, 0.1) << "beta for tilt " << a << ", " << b;
  EXPECT_FALSE(r.ceiling_found);
}

TEST(Preprocess, RecoversKnownTiltWithinATenthOfADegree) {
  const auto room = testing::synthetic_room();
  for (const auto& [a, b] :
       {std::pair{3.0, -2.0}, std::pair{-7.5, 4.0}, std::pair{0.0, 0.0}, std::pair{1.2, 9.0}}) {
    const auto tilted = testing::tilt(*room, a, b);
    const PreprocessResult r = preprocess(*tilted);
    const auto [want_a, want_b] = eq1_angles(a, b);
    EXPECT_NEAR(r.alpha_deg, want_a, 0.1) << "alpha for tilt " << a << ", " << b;
    EXPECT_NEAR(r.beta_deg, want_b, 0.1) << "beta for tilt " << a << ", " << b;
    EXPECT_NEAR(r.ceiling_height, 3.0, 0.01);
    // The levelled floor is flat and at 0: transform the original floor points.
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(b * M_PI / 180, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(a * M_PI / 180, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    for (const Eigen::Vector3d& corner :
         {Eigen::Vector3d(-3, -2.5, -1.5), Eigen::Vector3d(5, 3.5, -1.5)}) {
      const Eigen::Vector3d levelled = r.transform * (R * corner);
      EXPECT_NEAR(levelled.z(), 0.0, 0.01) << "floor corner";
    }
  }
}

// An open ceiling: the floor alone levels the cloud, its points alone are cut, and the
// room's height is the top of the walls. The walls' bands of heights hold more points than
// min_plane_fraction, but are no horizontal surface: no ceiling is made of them.
TEST(Preprocess, LevelsByTheFloorAloneWithoutACeiling) {
  const double spacing = 0.03;
  const auto room = testing::synthetic_room(8, 6, 3, spacing, 0.002, 1, 3.0, 2.5, 1.5, false);
  for (const auto& [a, b] : {std::pair{3.0, -2.0}, std::pair{-7.5, 4.0}, std::pair{0.0, 0.0}}) {
    const auto tilted = testing::tilt(*room, a, b);
    const PreprocessResult r = preprocess(*tilted);
    expect_levelled_without_ceiling(r, a, b);
    EXPECT_EQ(r.height_from, RoomHeightFrom::kPoints);
    EXPECT_EQ(r.ceiling.removed, 0u);
    // The top of the walls (their last row of points is at about 3 m).
    EXPECT_NEAR(r.ceiling_height, 3.0, 0.01);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(b * M_PI / 180, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(a * M_PI / 180, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    for (const Eigen::Vector3d& corner :
         {Eigen::Vector3d(-3, -2.5, -1.5), Eigen::Vector3d(5, 3.5, -1.5)}) {
      const Eigen::Vector3d levelled = r.transform * (R * corner);
      EXPECT_NEAR(levelled.z(), 0.0, 0.01) << "floor corner";
    }
    // The floor's points went, the walls' stayed (up to the top row).
    EXPECT_EQ(r.after_cut, r.input_points - r.floor.removed);
    const double per_plane = (std::floor(8 / spacing) + 1) * (std::floor(6 / spacing) + 1);
    EXPECT_NEAR(double(r.floor.removed), 0.954 * per_plane, 0.03 * per_plane);
    std::size_t high = 0;
    for (const auto& p : *r.cloud) high += p.z > 2.9;
    EXPECT_GT(high, 1000u);
  }
  // A height given replaces the points' top.
  PreprocessParams given;
  given.ceiling_height = 2.5;
  const PreprocessResult g = preprocess(*room, given);
  EXPECT_FALSE(g.ceiling_found);
  EXPECT_EQ(g.height_from, RoomHeightFrom::kGiven);
  EXPECT_DOUBLE_EQ(g.ceiling_height, 2.5);
  // With a ceiling, the ceiling's height, as before.
  const PreprocessResult closed = preprocess(*testing::synthetic_room());
  EXPECT_TRUE(closed.ceiling_found);
  EXPECT_EQ(closed.height_from, RoomHeightFrom::kCeiling);
  EXPECT_NEAR(closed.ceiling_height, 3.0, 0.01);
}

// A scan without a ceiling whose scanner looks down no further than -35°: its returns
// crowd on the walls beside it (it stands 0.7 m from two of them) while the floor shows
// only as a sparse ring beyond 2.6 m. The floor must still level it: planes are searched
// among points spread evenly over the surfaces, not over the returns.
TEST(Preprocess, LevelsAScanCrowdedOnNearWallsByItsSparseFloor) {
  const auto room = testing::scanned_open_room(12, 9, 3, 0.7, 0.7, 1.8, -35.0, 0.2);
  for (const auto& [a, b] : {std::pair{0.0, 0.0}, std::pair{2.0, -3.0}, std::pair{-4.0, 1.5}}) {
    const auto tilted = testing::tilt(*room, a, b);
    const PreprocessResult r = preprocess(*tilted);
    expect_levelled_without_ceiling(r, a, b);
    EXPECT_NEAR(r.ceiling_height, 3.0, 0.05);
  }
}

TEST(Preprocess, RemovesFloorAndCeilingWithinTwoSigma) {
  const auto room = testing::synthetic_room(8, 6, 3, 0.03, 0.003);
  const PreprocessResult r = preprocess(*room);
  EXPECT_NEAR(r.floor.sigma, 0.003, 0.001);
  EXPECT_NEAR(r.ceiling.sigma, 0.003, 0.001);
  // Floor and ceiling each hold (8/0.03+1)·(6/0.03+1) points; 2σ keeps ~95 % of a Gaussian.
  const double per_plane = (std::floor(8 / 0.03) + 1) * (std::floor(6 / 0.03) + 1);
  EXPECT_NEAR(double(r.floor.removed), 0.954 * per_plane, 0.03 * per_plane);
  EXPECT_NEAR(double(r.ceiling.removed), 0.954 * per_plane, 0.03 * per_plane);
  EXPECT_EQ(r.after_cut, r.input_points - r.floor.removed - r.ceiling.removed);
  // The table top at 0.75 m and the walls survive.
  std::size_t table = 0;
  for (const auto& p : *r.cloud) table += std::fabs(p.z - 0.75) < 0.01;
  EXPECT_GT(table, 1000u);
  for (const auto& p : *r.cloud) {
    EXPECT_FALSE(std::fabs(p.z) <= 2 * r.floor.sigma);
    EXPECT_FALSE(std::fabs(p.z - r.ceiling_height) <= 2 * r.ceiling.sigma);
  }
}

std::size_t distinct_cells(const Cloud& c, double spacing) {
  std::set<std::tuple<long, long, long>> cells;
  for (const auto& p : c)
    cells.emplace(long(std::floor(p.x / spacing)), long(std::floor(p.y / spacing)),
                  long(std::floor(p.z / spacing)));
  return cells.size();
}

TEST(Preprocess, CountsCellsExactlyWithTablesOfBoundedSize) {
  const auto room = testing::synthetic_room(8, 6, 3, 0.02, 0.002);
  ASSERT_GT(room->size(), 100000u);
  for (double spacing : {0.01, 0.03, 0.2}) {
    const std::size_t truth = distinct_cells(*room, spacing);
    // Room for all of them (counted in CellBits blocks within the tables' memory: a set a
    // worker, or one set on one thread where a worker's share cannot hold one); tables
    // of 7/10 of the count (on 2 or 3 threads each
    // share's table holds its cells, and their union overflows while they merge); and
    // tables of a tenth (counted in about 13 parts, shared by the workers) and, on one
    // thread, a fiftieth (about 63 parts).
    for (unsigned threads : {1u, 2u, 3u}) {
      EXPECT_EQ(count_cells(*room, spacing, room->size(), threads), truth) << spacing;
      EXPECT_EQ(count_cells(*room, spacing, truth * 7 / 10, threads), truth) << spacing;
      EXPECT_EQ(count_cells(*room, spacing, truth / 10, threads), truth) << spacing;
    }
    EXPECT_EQ(count_cells(*room, spacing, truth / 50), truth) << spacing;
  }
}

// The counts and the thinning run on shares of the scan: the spacing found and the
// points kept, in their order, are the same on any number of threads.
TEST(Preprocess, KeepsTheSamePointsOnAnyThreads) {
  auto room = testing::synthetic_room(8, 6, 3, 0.01, 0.002);
  PreprocessParams p;
  p.target_points = 50000;
  p.threads = 1;
  const PreprocessResult one = preprocess(*room, p);
  ASSERT_GT(one.after_cut, 4 * 65536u);  // shares of at least 65 536 points on 3 threads
  for (unsigned threads : {2u, 3u}) {
    p.threads = threads;
    const PreprocessResult r = preprocess(*room, p);
    EXPECT_EQ(r.decimation_spacing, one.decimation_spacing) << threads;
    ASSERT_EQ(r.cloud->size(), one.cloud->size()) << threads;
    for (std::size_t i = 0; i < r.cloud->size(); ++i) {
      const auto &a = (*r.cloud)[i], &b = (*one.cloud)[i];
      ASSERT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z) << threads << " " << i;
    }
  }
}

// The passes over the cut cloud read every point off the floor's and the ceiling's bands,
// wherever the threads' shares begin and end: with cells far finer than the points'
// spacing, decimation keeps them all.
TEST(Preprocess, DecimationReadsEveryPointOfTheCutCloud) {
  auto room = testing::synthetic_room(8, 6, 3, 0.01, 0.002);
  PreprocessParams p;
  p.min_spacing = 1e-4;
  for (unsigned threads : {1u, 2u, 3u}) {
    p.threads = threads;
    const PreprocessResult r = preprocess(*room, p);
    ASSERT_GT(r.after_cut, 4 * 65536u) << threads;  // shares of at least 65 536 points
    EXPECT_EQ(r.cloud->size(), r.after_cut) << threads;
    EXPECT_EQ(distinct_cells(*r.cloud, 1e-4), r.after_cut) << threads;
  }
}

TEST(Preprocess, DecimatesToSpacingOrTargetCount) {
  const auto room = testing::synthetic_room(8, 6, 3, 0.01, 0.002);
  PreprocessParams p;
  p.target_points = 50000;
  const PreprocessResult r = preprocess(*room, p);
  EXPECT_GT(r.after_cut, 200000u);
  EXPECT_LE(r.output_points, 50000u);
  EXPECT_GE(r.output_points, 35000u);
  EXPECT_GT(r.decimation_spacing, 0.0);
  // One point per cell of the spacing used (world-aligned cells).
  EXPECT_EQ(distinct_cells(*r.cloud, r.decimation_spacing), r.cloud->size());
  EXPECT_EQ(decimate(*r.cloud, r.decimation_spacing)->size(), r.cloud->size());

  // A minimum spacing instead of a target count: again one point per cell of it, and
  // every cell of the cut cloud keeps one.
  PreprocessParams q;
  q.min_spacing = 0.05;
  const PreprocessResult m = preprocess(*room, q);
  EXPECT_DOUBLE_EQ(m.decimation_spacing, 0.05);
  EXPECT_EQ(m.output_points, m.cloud->size());
  EXPECT_EQ(distinct_cells(*m.cloud, 0.05), m.cloud->size());
  EXPECT_LT(m.output_points, m.after_cut / 10);  // 1 cm grid → 5 cm cells: ~1/25 on a plane
  EXPECT_GT(m.output_points, m.after_cut / 50);
}

// The search for the spacing stops at the first count within 3 % under the target, or at
// the first whose spacing is finer than one counted over the target while it is itself
// within it (the count no longer monotone: the cells' phase decides it), or after 13
// counts; it keeps the spacing that counted the most cells within the target. Checked on
// the trials it reports, for scans of a room from six positions, with 3 mm of noise and
// walls 7-18 m from the cells' origin: there the count jumps by ±10 % between spacings
// 0.5 % apart, as on the simulated lab.
TEST(Preprocess, SpacingSearchStopsInTheWindowOrWhereTheCountsContradict) {
  const double target = 50000;
  std::size_t in_window = 0, contradicted = 0;
  for (int k = 0; k < 6; ++k) {
    auto room = testing::scanned_open_room(8, 6, 3, 2.3 + 0.61 * k, 1.7 + 0.37 * k, 1.5, -60, 0.3);
    std::mt19937 rng(k);
    std::normal_distribution<float> noise(0.f, 0.003f);
    for (auto& q : *room) {
      q.x += 10.f + noise(rng);
      q.y += 7.f + noise(rng);
      q.z += noise(rng);
    }
    PreprocessParams p;
    p.target_points = std::size_t(target);
    const PreprocessResult r = preprocess(*room, p);
    const auto& trials = r.spacing_counts;
    ASSERT_FALSE(trials.empty()) << k;
    ASSERT_LE(trials.size(), 13u) << k;
    // Where it stopped, and that no earlier trial would have stopped it.
    double coarsest_over = 0, finest_within = 1e9, best_count = 0;
    for (std::size_t i = 0; i < trials.size(); ++i) {
      const auto [s, c] = trials[i];
      const bool within = double(c) <= target;
      if (within) best_count = std::max(best_count, double(c));
      const bool window = within && double(c) >= 0.97 * target;
      if (within)
        finest_within = std::min(finest_within, s);
      else
        coarsest_over = std::max(coarsest_over, s);
      const bool contradicts = i > 0 && best_count > 0 && finest_within < coarsest_over;
      const bool last = i + 1 == trials.size();
      if (!last) {
        EXPECT_FALSE(window) << k << " trial " << i;
        EXPECT_FALSE(contradicts && !window) << k << " trial " << i;
      } else if (trials.size() < 13) {
        EXPECT_TRUE(window || contradicts) << k;
        in_window += window;
        contradicted += !window && contradicts;
      }
    }
    // The spacing kept is the trial that counted the most cells within the target, and
    // the points kept are its cells.
    ASSERT_GT(best_count, 0) << k;
    const auto kept = std::find_if(trials.begin(), trials.end(),
                                   [&](const auto& t) { return t.first == r.decimation_spacing; });
    ASSERT_NE(kept, trials.end()) << k;
    EXPECT_EQ(double(kept->second), best_count) << k;
    EXPECT_EQ(r.output_points, kept->second) << k;
  }
  // Both ways of stopping occur among these rooms.
  EXPECT_GT(in_window, 0u);
  EXPECT_GT(contradicted, 0u);
}

// decimate keeps, of each cell, the point nearest its centre: checked against a plain
// map of every cell's points, on a noisy room and with points outside the cells' grid.
// Points 200 000 km out along x (a float's step is 16 m there), a few to a cell along y and
// z: at spacings finer than 0.09 m their cells' indices pass 2^31, where the cells are
// worked out one point at a time rather than in lanes (cell_keys' `wide`).
void add_far_points(Cloud& cloud, float y0) {
  for (const float x : {2e8f, 2e8f + 16.f, -2e8f, -2e8f - 32.f})
    for (int k = 0; k < 12; ++k)
      cloud.push_back(pcl::PointXYZ{x, y0 + 0.0031f * float(k), -40.f + 0.0067f * float(k)});
}

TEST(Preprocess, DecimateKeepsThePointNearestEachCellCentre) {
  auto room = testing::synthetic_room(4, 3, 2.5, 0.013, 0.004);
  room->push_back(pcl::PointXYZ{std::nanf(""), 0.f, 0.f});  // dropped
  room->push_back(pcl::PointXYZ{-3.3f, 2.1f, 0.7f});        // alone in its cell
  add_far_points(*room, 1.0f);
  for (double spacing : {0.021, 0.05, 0.3}) {
    std::map<std::tuple<long, long, long>, std::pair<double, pcl::PointXYZ>> nearest;
    for (const auto& q : *room) {
      if (!std::isfinite(q.x)) continue;
      const double t[3] = {q.x / spacing, q.y / spacing, q.z / spacing};
      double d2 = 0;
      for (double v : t) d2 += (v - std::floor(v) - 0.5) * (v - std::floor(v) - 0.5);
      const auto cell =
          std::make_tuple(long(std::floor(t[0])), long(std::floor(t[1])), long(std::floor(t[2])));
      auto it = nearest.find(cell);
      if (it == nearest.end() || d2 < it->second.first - 1e-9) nearest[cell] = {d2, q};
    }
    const Cloud::Ptr kept = decimate(*room, spacing);
    ASSERT_EQ(kept->size(), nearest.size()) << spacing;
    std::size_t matched = 0;
    for (const auto& q : *kept) {
      const auto cell =
          std::make_tuple(long(std::floor(q.x / spacing)), long(std::floor(q.y / spacing)),
                          long(std::floor(q.z / spacing)));
      const auto it = nearest.find(cell);
      ASSERT_NE(it, nearest.end()) << spacing;
      const pcl::PointXYZ& want = it->second.second;
      matched += q.x == want.x && q.y == want.y && q.z == want.z;
    }
    // Ties within float rounding may pick another point of the cell; nearly all match.
    EXPECT_GE(matched, kept->size() - kept->size() / 1000) << spacing;
    EXPECT_EQ(count_cells(*room, spacing, room->size()), kept->size()) << spacing;
  }
}

// CellThinning, a cloud at a time, keeps what decimate keeps of them all at once: the
// same points in the same order.
TEST(Preprocess, ThinningCloudByCloudEqualsDecimatingTheirUnion) {
  const auto a = testing::synthetic_room(5, 4, 2.6, 0.017, 0.003);
  auto b = testing::synthetic_room(5, 4, 2.6, 0.023, 0.003);
  for (auto& q : *b) q.x += 1.3f;  // overlaps a, and reaches past it
  add_far_points(*a, 1.0f);
  add_far_points(*b, 1.002f);  // the same far cells, other points in them
  Cloud both = *a;
  both += *b;
  const Cloud::Ptr at_once = decimate(both, 0.04);
  CellThinning thinning(0.04);
  thinning.add(*a);
  const std::size_t after_a = thinning.cloud().size();
  thinning.add(*b);
  ASSERT_EQ(thinning.cloud().size(), at_once->size());
  EXPECT_GT(thinning.cloud().size(), after_a);
  for (std::size_t i = 0; i < at_once->size(); ++i) {
    const auto &p = thinning.cloud()[i], &q = (*at_once)[i];
    ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z) << i;
  }
  EXPECT_THROW(CellThinning(0.0), std::invalid_argument);

  // A thinned cloud and then more points, in place (the survey's merged cloud): the same
  // points in the same order, some of the thinned cloud's replaced by nearer ones (and on
  // ties, kept: a point of b placed exactly on one of a's stays out), and b's new cells
  // after them.
  Cloud thinned_a = *decimate(*a, 0.04);
  Cloud b_ties = *b;
  for (std::size_t i = 0; i < thinned_a.size(); i += 9) b_ties.push_back(thinned_a[i]);
  Cloud both_ties = *a;
  both_ties += b_ties;
  const Cloud::Ptr union_thinned = decimate(both_ties, 0.04);
  CellThinning later(0.04);
  later.add(b_ties);
  const Cloud before = thinned_a;
  later.release_after(thinned_a);
  ASSERT_EQ(thinned_a.size(), union_thinned->size());
  std::size_t replaced = 0;
  for (std::size_t i = 0; i < thinned_a.size(); ++i) {
    const auto &p = thinned_a[i], &q = (*union_thinned)[i];
    ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z) << i;
    if (i < before.size()) replaced += !(p.x == before[i].x && p.y == before[i].y);
  }
  EXPECT_GT(replaced, 0u);
  EXPECT_GT(thinned_a.size(), before.size());
  EXPECT_EQ(thinned_a.width, thinned_a.size());
  EXPECT_TRUE(later.cloud().empty());
}

TEST(Preprocess, ClearErrors) {
  Cloud few;
  for (int i = 0; i < 10; ++i) few.push_back(pcl::PointXYZ{float(i), 0.f, 0.f});
  EXPECT_THROW(preprocess(few), PreprocessError);
  // Only a floor: no ceiling plane, and no point above the floor to take a height from.
  Cloud floor_only;
  for (double x = 0; x < 5; x += 0.02)
    for (double y = 0; y < 5; y += 0.02)
      floor_only.push_back(pcl::PointXYZ{float(x), float(y), -1.5f});
  try {
    preprocess(floor_only);
    FAIL();
  } catch (const PreprocessError& e) {
    EXPECT_NE(std::string(e.what()).find("ceiling"), std::string::npos) << e.what();
  }
}

TEST(Preprocess, RealScanFloorCeilingAndLevel) {
  const auto scans = read_scans(std::string(SEMIOCTREE_SOURCE_DIR) + "/tests/data/room_scan1.pcd");
  ASSERT_EQ(scans.size(), 1u);
  const PreprocessResult r = preprocess(*scans[0].points);
  EXPECT_GT(r.floor.plane_inliers, 1000u);
  EXPECT_GT(r.ceiling.plane_inliers, 1000u);
  EXPECT_GT(r.ceiling_height, 2.0);
  EXPECT_LT(r.ceiling_height, 5.0);
  // The levelled floor is flat to under 0.5°: fit a plane to the points near z = 0.
  Cloud floor;
  {
    Cloud levelled;
    pcl::transformPointCloud(*scans[0].points, levelled, r.transform.matrix().cast<float>());
    for (const auto& p : levelled)
      if (std::fabs(p.z) < 0.03) floor.push_back(p);
  }
  ASSERT_GT(floor.size(), 1000u);
  Eigen::Vector4f centroid;
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  pcl::computeMeanAndCovarianceMatrix(floor, cov, centroid);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> es(cov);
  const Eigen::Vector3f normal = es.eigenvectors().col(0);
  const double tilt = std::acos(std::fabs(normal.z())) * 180 / M_PI;
  EXPECT_LT(tilt, 0.5) << "levelled floor tilt";
  RecordProperty("floor_tilt_deg", std::to_string(tilt));
  std::printf(
      "room_scan1: alpha %.3f°, beta %.3f°, ceiling %.3f m, floor σ %.4f, ceiling σ %.4f, "
      "levelled floor tilt %.3f°, %zu → %zu points\n",
      r.alpha_deg, r.beta_deg, r.ceiling_height, r.floor.sigma, r.ceiling.sigma, tilt,
      r.input_points, r.output_points);
}

}  // namespace
}  // namespace semioctree
