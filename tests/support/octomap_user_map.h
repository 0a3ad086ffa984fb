// A map made the way OctoMap users make theirs (octomap_server): a sparse scanner's
// scans from a few positions along a path through the robot's room, each put into an
// octomap::OcTree with insertPointCloud, in a frame whose floor is not at z = 0.
#pragma once

#include <octomap/OcTree.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"

namespace semioctree::testing {

struct OctomapUserMapOptions {
  double resolution = 0.08;  // the OcTree's leaf, m
  double step_deg = 0.75;    // the scanner's azimuth and elevation step (sparse carving)
  double floor_z = -0.15;    // the floor's height in the map's frame, m
  int positions = 3;         // scan positions along the path (≥ 1)
};

struct OctomapUserMap {
  std::unique_ptr<octomap::OcTree> tree;
  std::vector<Eigen::Vector3d> scanners;  // optical centres in the map's frame, in scan order
};

// The path: the robot's start, then cells of its room spread from it: the farthest from
// the start the robot reaches with its radius to spare, and between them the such cell
// nearest each even split of the leg. `plan` is truth.floor_plan(…).
inline std::vector<Eigen::Vector2d> scan_path(const sim::Scene& scene, const sim::FloorPlan& plan,
                                              int positions) {
  const Eigen::Vector2d start = scene.robot.start;
  // Cells of the room a robot reaches with a margin of its radius to spare (every cell
  // within that distance reachable too): where an operator would drive it to scan.
  const int margin = int(std::ceil(scene.robot.radius / plan.cell));
  auto reachable_in_room = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= plan.nx || y >= plan.ny) return false;
    const std::size_t i = std::size_t(y) * std::size_t(plan.nx) + std::size_t(x);
    return plan.reachable[i] && plan.room[i] == plan.start_room;
  };
  std::vector<Eigen::Vector2d> cells;
  for (int y = 0; y < plan.ny; ++y)
    for (int x = 0; x < plan.nx; ++x) {
      bool clear = true;
      for (int dy = -margin; dy <= margin && clear; ++dy)
        for (int dx = -margin; dx <= margin && clear; ++dx)
          clear = dx * dx + dy * dy > margin * margin || reachable_in_room(x + dx, y + dy);
      if (clear) cells.push_back(plan.origin + plan.cell * Eigen::Vector2d(x + 0.5, y + 0.5));
    }
  std::vector<Eigen::Vector2d> path{start};
  if (positions <= 1 || cells.empty()) return path;
  const Eigen::Vector2d far = *std::max_element(
      cells.begin(), cells.end(), [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
        return (a - start).squaredNorm() < (b - start).squaredNorm();
      });
  for (int k = 1; k < positions; ++k) {
    const Eigen::Vector2d want = start + (far - start) * (double(k) / (positions - 1));
    path.push_back(*std::min_element(cells.begin(), cells.end(),
                                     [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
                                       return (a - want).squaredNorm() < (b - want).squaredNorm();
                                     }));
  }
  return path;
}

inline OctomapUserMap make_octomap_user_map(const sim::Scene& scene, const sim::GroundTruth& truth,
                                            const OctomapUserMapOptions& o) {
  sim::ScannerConfig config = scene.scanner;
  config.azimuth_step_deg = config.elevation_step_deg = o.step_deg;
  OctomapUserMap out;
  out.tree = std::make_unique<octomap::OcTree>(o.resolution);
  const sim::FloorPlan plan = truth.floor_plan(0.05);
  std::uint64_t seed = 1;
  for (const Eigen::Vector2d& at : scan_path(scene, plan, o.positions)) {
    sim::ScanOptions so;
    so.seed = seed++;
    so.with_intensity = false;
    const sim::Scan s = sim::scan(truth.ray_caster(), config, sim::Pose2{at.x(), at.y(), 0.0}, so);
    const Eigen::Isometry3d to_world = s.sensor_to_world();
    const Eigen::Vector3d shift(0.0, 0.0, o.floor_z);
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : s.points) {
      const Eigen::Vector3d w = to_world * p.cast<double>() + shift;
      cloud.push_back(float(w.x()), float(w.y()), float(w.z()));
    }
    const Eigen::Vector3d origin = s.origin() + shift;
    out.tree->insertPointCloud(
        cloud, octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z())));
    out.scanners.push_back(origin);
  }
  return out;
}

}  // namespace semioctree::testing
