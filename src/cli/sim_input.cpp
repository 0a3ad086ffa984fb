#include "sim_input.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

PreparedCloud scan_scene_at_start(const std::string& scene_path, std::uint64_t seed,
                                  const PreprocessParams& params) {
  const auto t0 = Clock::now();
  const sim::Scene scene = sim::load_scene(scene_path);
  const auto caster = sim::make_ray_caster(sim::tessellate(scene));
  const sim::Pose2 start{scene.robot.start.x(), scene.robot.start.y(), scene.robot.start_yaw_deg};
  sim::ScanOptions so;
  so.seed = seed;
  so.with_intensity = false;
  so.with_grid_indices = false;
  const sim::Scan s = sim::scan(*caster, scene.scanner, start, so);
  std::printf("scanned %s from (%.2f, %.2f): %llu rays, %zu points [%.2f s]\n", scene_path.c_str(),
              start.x, start.y, static_cast<unsigned long long>(s.rays_cast), s.points.size(),
              seconds_since(t0));
  // Into the pipeline's types: points in the scanner frame, pose scanner → world.
  Cloud cloud;
  cloud.reserve(s.points.size());
  const Eigen::Isometry3d to_world = s.sensor_to_world();
  for (const Eigen::Vector3f& p : s.points) {
    const Eigen::Vector3d w = to_world * p.cast<double>();
    cloud.push_back(pcl::PointXYZ{float(w.x()), float(w.y()), float(w.z())});
  }
  PreparedCloud out;
  out.raw_points = s.points.size();
  const auto t1 = Clock::now();
  out.pre = preprocess(cloud, params);
  const Eigen::Vector3d o = out.pre.transform * s.origin();
  out.scanners.emplace_back(o.x(), o.y(), o.z());
  Cloud seen;  // the same returns, from the optical centre
  seen.reserve(cloud.size());
  for (const auto& p : cloud)
    seen.push_back(pcl::PointXYZ{float(p.x - s.origin().x()), float(p.y - s.origin().y()),
                                 float(p.z - s.origin().z())});
  out.returns.push_back(return_directions(
      seen, out.pre.transform.linear(),
      returns_options(sim_platform::scanner_limits(scene), !out.pre.ceiling_found)));
  std::printf(
      "preprocess: floor σ %.1f mm, %s, %zu → %zu points [%.2f s]\n", 1000 * out.pre.floor.sigma,
      describe_room_height(out.pre.ceiling_found, out.pre.height_from, out.pre.ceiling_height)
          .c_str(),
      out.pre.input_points, out.pre.output_points, seconds_since(t1));
  return out;
}

void check_robot_start(const sim::Scene& scene, const sim::GroundTruth& truth,
                       const sim::FloorPlan& plan, const std::string& scene_path) {
  const Eigen::Vector2d start = scene.robot.start;
  char where[96];
  std::snprintf(where, sizeof where, "the robot's start (%.2f, %.2f)", start.x(), start.y());
  if (!plan.in_survey_area(start))
    throw std::invalid_argument(std::string(where) + " in " + scene_path +
                                " is outside the floor the robot can reach (the survey area, " +
                                std::to_string(int(std::round(plan.survey_area_m2))) +
                                " m²): no reachable start");
  if (!truth.standing_free(start)) {
    char radius[32];
    std::snprintf(radius, sizeof radius, "%.2f m", scene.robot.radius);
    throw std::invalid_argument(std::string(where) + " in " + scene_path +
                                " is inside an obstacle or closer than the robot's radius (" +
                                radius + ") to one");
  }
}

}  // namespace semioctree::cli
