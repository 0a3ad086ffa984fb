// The test scenes of the coverage tests (sim/scenes) and one scan from the robot's start.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"

namespace semioctree::testing {

// sim/scenes/<name>.scene.json.
inline sim::Scene load(const std::string& name) {
  return sim::load_scene_json(std::string(SEMIOCTREE_SOURCE_DIR "/sim/scenes/") + name +
                              ".scene.json");
}

// World-frame points of one full scan from the robot's start.
inline std::vector<Eigen::Vector3d> scan_from_start(const sim::GroundTruth& truth,
                                                    std::uint64_t seed = 1) {
  const sim::Scene& s = truth.scene();
  sim::ScanOptions o;
  o.seed = seed;
  const sim::Scan sc = sim::scan(truth.ray_caster(), s.scanner,
                                 {s.robot.start.x(), s.robot.start.y(), s.robot.start_yaw_deg}, o);
  std::vector<Eigen::Vector3d> out;
  out.reserve(sc.points.size());
  const Eigen::Isometry3d to_world = sc.sensor_to_world();
  for (const auto& p : sc.points) out.push_back(to_world * p.cast<double>());
  return out;
}

}  // namespace semioctree::testing
