// The simulated robot: exact true pose, drifting reported pose with the scene's odometry
// noise, reproducible for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "semioctree/sim/robot.h"

namespace {

using namespace semioctree::sim;

RobotConfig config(double sigma_xy = 0.02, double sigma_yaw = 0.5) {
  RobotConfig c;
  c.start = {1.0, 2.0};
  c.start_yaw_deg = 0.0;
  c.odometry_sigma_xy = sigma_xy;
  c.odometry_sigma_yaw_deg = sigma_yaw;
  return c;
}

TEST(Robot, StartsWhereTheSceneSaysAndKnowsIt) {
  RobotConfig c = config();
  c.start_yaw_deg = 30;
  const Robot r(c, 1);
  EXPECT_EQ(r.true_pose().x, 1.0);
  EXPECT_EQ(r.true_pose().y, 2.0);
  EXPECT_EQ(r.true_pose().yaw_deg, 30.0);
  EXPECT_EQ(r.reported_pose().x, 1.0);
  EXPECT_EQ(r.reported_pose().yaw_deg, 30.0);
  EXPECT_EQ(r.moves(), 0);
}

TEST(Robot, ReachesTheCommandedPoseButReportsItWithNoise) {
  Robot r(config(), 7);
  r.move_to({4.0, 6.0, 90.0});
  EXPECT_EQ(r.true_pose().x, 4.0);
  EXPECT_EQ(r.true_pose().y, 6.0);
  EXPECT_EQ(r.true_pose().yaw_deg, 90.0);
  EXPECT_DOUBLE_EQ(r.distance_driven(), 5.0);
  const double error = std::hypot(r.reported_pose().x - 4.0, r.reported_pose().y - 6.0);
  EXPECT_GT(error, 0.0);
  EXPECT_LT(error, 5 * 0.02 * 5.0 * std::sqrt(2.0));  // 5σ of a 5 m drive
  EXPECT_NE(r.reported_pose().yaw_deg, 90.0);
}

TEST(Robot, WithoutNoiseTheReportIsExact) {
  Robot r(config(0.0, 0.0), 7);
  for (const Pose2& p : {Pose2{4, 6, 90}, Pose2{-2, 1, -170}, Pose2{0.5, 0.5, 10}}) {
    r.move_to(p);
    EXPECT_NEAR(r.reported_pose().x, p.x, 1e-12);
    EXPECT_NEAR(r.reported_pose().y, p.y, 1e-12);
    EXPECT_NEAR(r.reported_pose().yaw_deg, p.yaw_deg, 1e-12);
  }
}

TEST(Robot, SameSeedSameDrift) {
  Robot a(config(), 99), b(config(), 99), c(config(), 100);
  for (const Pose2& p : {Pose2{4, 6, 90}, Pose2{-2, 1, -170}}) {
    a.move_to(p);
    b.move_to(p);
    c.move_to(p);
  }
  EXPECT_EQ(a.reported_pose().x, b.reported_pose().x);
  EXPECT_EQ(a.reported_pose().y, b.reported_pose().y);
  EXPECT_EQ(a.reported_pose().yaw_deg, b.reported_pose().yaw_deg);
  EXPECT_NE(a.reported_pose().x, c.reported_pose().x);
}

// Over many robots, one 2 m drive gives errors of σ_xy·d per axis and σ_yaw·d in heading.
TEST(Robot, NoiseGrowsWithTheDistanceDriven) {
  const int n = 4000;
  const double d = 2.0;
  double sx = 0, sy = 0, syaw = 0;
  for (int seed = 0; seed < n; ++seed) {
    Robot r(config(), static_cast<std::uint64_t>(seed));
    r.move_to({1.0 + d, 2.0, 0.0});
    sx += std::pow(r.reported_pose().x - r.true_pose().x, 2);
    sy += std::pow(r.reported_pose().y - r.true_pose().y, 2);
    syaw += std::pow(r.reported_pose().yaw_deg - r.true_pose().yaw_deg, 2);
  }
  EXPECT_NEAR(std::sqrt(sx / n), 0.02 * d, 0.1 * 0.02 * d);
  EXPECT_NEAR(std::sqrt(sy / n), 0.02 * d, 0.1 * 0.02 * d);
  EXPECT_NEAR(std::sqrt(syaw / n), 0.5 * d, 0.1 * 0.5 * d);
}

TEST(Robot, TurningOnTheSpotAddsNoDrift) {
  Robot r(config(), 3);
  r.move_to({1.0, 2.0, 120.0});
  EXPECT_DOUBLE_EQ(r.reported_pose().x, 1.0);
  EXPECT_DOUBLE_EQ(r.reported_pose().y, 2.0);
  EXPECT_DOUBLE_EQ(r.reported_pose().yaw_deg, 120.0);
}

// A heading error makes later moves go astray in the reported frame: drift accumulates.
TEST(Robot, DriftAccumulatesOverMoves) {
  const int n = 2000;
  double after_one = 0, after_four = 0;
  for (int seed = 0; seed < n; ++seed) {
    Robot r(config(), static_cast<std::uint64_t>(seed));
    r.move_to({3.0, 2.0, 0.0});
    after_one += std::pow(r.reported_pose().x - 3.0, 2) + std::pow(r.reported_pose().y - 2.0, 2);
    r.move_to({5.0, 2.0, 0.0});
    r.move_to({3.0, 2.0, 0.0});
    r.move_to({5.0, 2.0, 0.0});
    after_four += std::pow(r.reported_pose().x - 5.0, 2) + std::pow(r.reported_pose().y - 2.0, 2);
  }
  EXPECT_GT(after_four / n, 3.0 * after_one / n);
}

TEST(Robot, HeadingsStayInMinus180To180) {
  Robot r(config(), 5);
  r.move_to({1.0, 2.0, 350.0});
  EXPECT_NEAR(r.true_pose().yaw_deg, -10.0, 1e-12);
  EXPECT_GE(r.reported_pose().yaw_deg, -180.0);
  EXPECT_LT(r.reported_pose().yaw_deg, 180.0);
}

}  // namespace
