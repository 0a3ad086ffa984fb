#include "semioctree/sim/robot.h"

#include <cmath>

namespace semioctree::sim {

namespace {

double normal(std::mt19937_64& rng) {
  // Box–Muller written out so a seed gives the same noise with any standard library.
  const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53;
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

double wrap_deg(double a) {
  a = std::fmod(a + 180.0, 360.0);
  if (a < 0) a += 360.0;
  return a - 180.0;
}

}  // namespace

Robot::Robot(const RobotConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  true_pose_ = {config.start.x(), config.start.y(), config.start_yaw_deg};
  reported_pose_ = true_pose_;  // odometry starts at the first scan position
}

void Robot::move_to(const Pose2& target) {
  const double dx = target.x - true_pose_.x, dy = target.y - true_pose_.y;
  const double d = std::hypot(dx, dy);
  // True motion in the frame of the robot before the move.
  const double yaw0 = true_pose_.yaw_deg * M_PI / 180.0;
  const double fwd = std::cos(yaw0) * dx + std::sin(yaw0) * dy;
  const double left = -std::sin(yaw0) * dx + std::cos(yaw0) * dy;
  const double turn = wrap_deg(target.yaw_deg - true_pose_.yaw_deg);

  // Odometry measures that motion with errors growing with the distance driven.
  const double m_fwd = fwd + config_.odometry_sigma_xy * d * normal(rng_);
  const double m_left = left + config_.odometry_sigma_xy * d * normal(rng_);
  const double m_turn = turn + config_.odometry_sigma_yaw_deg * d * normal(rng_);

  // ... and accumulates it onto the pose it believes it had.
  const double ryaw = reported_pose_.yaw_deg * M_PI / 180.0;
  reported_pose_.x += std::cos(ryaw) * m_fwd - std::sin(ryaw) * m_left;
  reported_pose_.y += std::sin(ryaw) * m_fwd + std::cos(ryaw) * m_left;
  reported_pose_.yaw_deg = wrap_deg(reported_pose_.yaw_deg + m_turn);

  true_pose_ = target;
  true_pose_.yaw_deg = wrap_deg(target.yaw_deg);
  distance_driven_ += d;
  ++moves_;
}

}  // namespace semioctree::sim
