// Scan pairs without a pose, for the global registration test and benchmark.
// Lab pairs: scans from free positions on a grid over the lab's main room, each
// preprocessed (levelled) in its own frame; a pair joins two positions 2-4 m
// apart, the source turned about its scanner by 30-180° (either way) so that
// nothing of the true heading is left. Turning the levelled scan stands for
// scanning with another heading: the simulated scanner sweeps the full turn
// about its own vertical axis, so only the azimuth phase of its rays differs.
#pragma once

#include <pcl/common/transforms.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "semioctree/preprocess.h"
#include "semioctree/registration.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "support/lab_scan.h"

namespace semioctree::testing {

struct LabPosition {
  sim::Pose2 pose;
  Cloud::Ptr levelled;                  // preprocessed, levelled frame
  Eigen::Isometry3d levelled_to_world;  // the truth
};

struct LabPair {
  std::size_t target = 0, source = 0;  // indices into the positions
  double distance_m = 0, turn_deg = 0;
  Cloud::Ptr source_cloud;         // the source's levelled scan, turned by turn_deg
  Eigen::Isometry3d truth;         // source_cloud's frame → target's levelled frame
  Eigen::Vector3d source_scanner;  // the scanner in source_cloud's frame
};

// Free positions (the robot fits, GroundTruth::standing_free) of the main room on a
// grid of `step` m, scanned at `scan_step_deg` and preprocessed like the survey does.
inline std::vector<LabPosition> lab_positions(double step, double scan_step_deg) {
  sim::Scene scene =
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
  scene.scanner.azimuth_step_deg = scene.scanner.elevation_step_deg = scan_step_deg;
  const sim::GroundTruth truth(scene);
  const sim::FloorPlan plan = truth.floor_plan();
  const int main_room = plan.start_room;
  const auto caster = sim::make_ray_caster(sim::tessellate(scene));
  PreprocessParams pp;
  pp.target_points = 400000;
  std::vector<LabPosition> out;
  std::uint64_t seed = 1;
  for (double x = step / 2; x < 10.4; x += step)
    for (double y = step / 2; y < 8.5; y += step) {
      const Eigen::Vector2d p(x, y);
      if (!truth.standing_free(p) || plan.room_at(p) != main_room) continue;
      sim::ScanOptions options;
      options.seed = seed++;
      options.with_intensity = false;
      const sim::Pose2 pose{x, y, 0.0};
      const sim::Scan s = sim::scan(*caster, scene.scanner, pose, options);
      Cloud sensor;
      sensor.reserve(s.points.size());
      for (const auto& q : s.points) sensor.push_back(pcl::PointXYZ{q.x(), q.y(), q.z()});
      const PreprocessResult pre = preprocess(sensor, pp);
      out.push_back({pose, pre.cloud, s.sensor_to_world() * pre.transform.inverse()});
    }
  return out;
}

// Up to `count` pairs 2-4 m apart, spread over all such pairs, with turns spread
// over ±[30°, 180°].
inline std::vector<LabPair> lab_pairs(const std::vector<LabPosition>& positions,
                                      std::size_t count) {
  std::vector<std::pair<std::size_t, std::size_t>> near;
  for (std::size_t i = 0; i < positions.size(); ++i)
    for (std::size_t j = 0; j < positions.size(); ++j) {
      if (i == j) continue;
      const double d = std::hypot(positions[i].pose.x - positions[j].pose.x,
                                  positions[i].pose.y - positions[j].pose.y);
      if (d >= 2.0 && d <= 4.0) near.emplace_back(i, j);
    }
  std::vector<LabPair> out;
  const std::size_t n = std::min(count, near.size());
  for (std::size_t k = 0; k < n; ++k) {
    const auto [i, j] = near[k * near.size() / n];
    LabPair pair;
    pair.target = i;
    pair.source = j;
    pair.distance_m = std::hypot(positions[i].pose.x - positions[j].pose.x,
                                 positions[i].pose.y - positions[j].pose.y);
    const double magnitude = n > 1 ? 30.0 + 150.0 * double(k) / double(n - 1) : 90.0;
    pair.turn_deg = k % 2 ? -magnitude : magnitude;
    const Eigen::Isometry3d turn = planar_pose(0.0, 0.0, pair.turn_deg);
    pair.source_cloud.reset(new Cloud);
    pcl::transformPointCloud(*positions[j].levelled, *pair.source_cloud,
                             turn.matrix().cast<float>());
    pair.truth =
        positions[i].levelled_to_world.inverse() * positions[j].levelled_to_world * turn.inverse();
    // The scanner is at the sensor origin: levelled frame = pre.transform · sensor.
    const Eigen::Vector3d sensor_in_world(positions[j].pose.x, positions[j].pose.y, 0.0);
    const Eigen::Vector3d in_levelled = positions[j].levelled_to_world.inverse() * sensor_in_world;
    pair.source_scanner = turn * in_levelled;
    out.push_back(pair);
  }
  return out;
}

// Pose error of an estimated source → target transform: how far the source's scanner
// lands from where it should (x, y) and the yaw between the two, degrees.
struct PlanarError {
  double translation_m, yaw_deg;
};
inline PlanarError planar_error(const Eigen::Isometry3d& estimated, const Eigen::Isometry3d& truth,
                                const Eigen::Vector3d& scanner) {
  const Eigen::Vector3d a = estimated * scanner, b = truth * scanner;
  const Eigen::Vector3d xe = estimated.rotation().col(0), xt = truth.rotation().col(0);
  const double yaw = std::remainder(
      (std::atan2(xe.y(), xe.x()) - std::atan2(xt.y(), xt.x())) * 180.0 / M_PI, 360.0);
  return {(a - b).head<2>().norm(), yaw};
}

// A copy of a levelled scan as a second scan of the same room: `drop` of its
// points removed at random, Gaussian noise of `noise_m` on every coordinate, then
// moved by `moved` (source_cloud's frame → the original is truth).
inline LabPair moved_copy(const Cloud& levelled, const Eigen::Vector3d& scanner,
                          const Eigen::Isometry3d& moved, double drop, double noise_m,
                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, noise_m);
  Cloud copy;
  copy.reserve(levelled.size());
  for (const auto& p : levelled) {
    if (u(rng) < drop) continue;
    copy.push_back(pcl::PointXYZ{float(p.x + n(rng)), float(p.y + n(rng)), float(p.z + n(rng))});
  }
  LabPair pair;
  pair.source_cloud.reset(new Cloud);
  pcl::transformPointCloud(copy, *pair.source_cloud, moved.matrix().cast<float>());
  pair.truth = moved.inverse();
  pair.source_scanner = moved * scanner;
  const Eigen::Vector3d t = moved.translation();
  pair.distance_m = t.head<2>().norm();
  const Eigen::Vector3d x = moved.rotation().col(0);
  pair.turn_deg = std::atan2(x.y(), x.x()) * 180.0 / M_PI;
  return pair;
}

}  // namespace semioctree::testing
