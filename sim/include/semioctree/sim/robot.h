// Simulated robot platform: it drives to commanded poses; the pose it reports is its
// odometry, which drifts (seeded noise proportional to the distance driven, as in the
// scene's robot.odometry_noise). Only the simulator knows the true pose.
#pragma once

#include <cstdint>
#include <random>

#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"

namespace semioctree::sim {

class Robot {
 public:
  Robot(const RobotConfig& config, std::uint64_t seed);

  // Drives to `target` (reached exactly). The reported pose is updated by the measured
  // motion: the true relative motion plus Gaussian noise of σ_xy·d on each translation
  // axis and σ_yaw·d on the heading, d = distance driven.
  void move_to(const Pose2& target);

  const Pose2& true_pose() const { return true_pose_; }
  const Pose2& reported_pose() const { return reported_pose_; }
  double distance_driven() const { return distance_driven_; }
  int moves() const { return moves_; }
  const RobotConfig& config() const { return config_; }

 private:
  RobotConfig config_;
  std::mt19937_64 rng_;
  Pose2 true_pose_;
  Pose2 reported_pose_;
  double distance_driven_ = 0.0;
  int moves_ = 0;
};

}  // namespace semioctree::sim
