// One synthetic scan of the built-in lab scene from the robot's start (or a
// given pose), in the world frame: the input of the lab tests and benchmarks.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "semioctree/scan_io.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"

namespace semioctree::testing {

struct LabScan {
  Cloud world;             // points, world frame
  Eigen::Vector3d origin;  // the scanner's optical centre, world frame
  std::size_t rays = 0;
};

// The lab's own scanner steps 0.1° (5.4 M rays); the tests whose checks do not
// depend on the sampling density scan at kTestStepDeg, 4× fewer rays (their
// figures were measured so), which keeps the sanitizer run within CI's time.
constexpr double kTestStepDeg = 0.2;

// `step_deg` > 0 replaces the scanner's azimuth and elevation steps.
inline LabScan scan_lab(std::uint64_t seed = 1, const std::optional<sim::Pose2>& pose = {},
                        double step_deg = 0.0) {
  sim::Scene scene =
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
  if (step_deg > 0) scene.scanner.azimuth_step_deg = scene.scanner.elevation_step_deg = step_deg;
  const auto caster = sim::make_ray_caster(sim::tessellate(scene));
  sim::ScanOptions options;
  options.seed = seed;
  const sim::Scan s = sim::scan(
      *caster, scene.scanner,
      pose.value_or(sim::Pose2{scene.robot.start.x(), scene.robot.start.y(), 0.0}), options);
  LabScan out;
  const Eigen::Isometry3d to_world = s.sensor_to_world();
  for (const auto& p : s.points) {
    const Eigen::Vector3d w = to_world * p.cast<double>();
    out.world.push_back(pcl::PointXYZ{float(w.x()), float(w.y()), float(w.z())});
  }
  out.origin = s.origin();
  out.rays = s.rays_cast;
  return out;
}

}  // namespace semioctree::testing
