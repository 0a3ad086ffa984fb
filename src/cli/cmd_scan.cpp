// `semioctree scan`: one synthetic 360° scan of a scene, written as PCD or PLY.
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cloud_input.h"
#include "commands.h"
#include "option_checks.h"
#include "progress_line.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/point_io.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim/solids.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

namespace {

struct ScanArgs {
  std::string scene;
  std::string at;
  std::string out;
  std::uint64_t seed = 1;
  double azimuth_step = 0;    // 0: the scene's
  double elevation_step = 0;  // 0: the scene's
  unsigned threads = 0;
  bool no_intensity = false;
};

// "X,Y" or "X,Y,YAW_DEG" → pose.
sim::Pose2 parse_at(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v) || std::abs(v) > sim::kMaxSceneNumber)
      throw std::runtime_error(
          "--at: expected X,Y or X,Y,YAW_DEG (numbers within ±100000, metres and degrees), got "
          "\"" +
          text + "\"");
    values.push_back(v);
  }
  if (values.size() != 2 && values.size() != 3)
    throw std::runtime_error("--at: expected X,Y or X,Y,YAW_DEG (2 or 3 numbers), got \"" + text +
                             "\"");
  return {values[0], values[1], values.size() == 3 ? values[2] : 0.0};
}

void run_scan(const ScanArgs& a) {
  const sim::Pose2 pose = parse_at(a.at);
  std::string ext = a.out.size() >= 4 ? a.out.substr(a.out.size() - 4) : "";
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".pcd" && ext != ".ply")
    throw std::runtime_error("--out: expected a file name ending in .pcd or .ply, got \"" + a.out +
                             "\"");
  check_outputs_spare_inputs({{"--scene", a.scene}}, {{"--out", a.out}});

  sim::Scene scene = sim::load_scene(a.scene, Eigen::Vector2d(pose.x, pose.y), pose.yaw_deg);
  if (a.azimuth_step > 0) scene.scanner.azimuth_step_deg = a.azimuth_step;
  if (a.elevation_step > 0) scene.scanner.elevation_step_deg = a.elevation_step;

  // The scanner must stand in free space.
  const sim::SolidModel solids(scene);
  const std::string inside = solids.solid_containing({pose.x, pose.y, scene.scanner.height});
  if (!inside.empty())
    throw std::runtime_error("--at: the scanner at (" + std::to_string(pose.x) + ", " +
                             std::to_string(pose.y) + ") would be inside " + inside + " of " +
                             a.scene);

  const auto t0 = Clock::now();
  const sim::SceneTriangles triangles = sim::tessellate(scene);
  // A scanner farther from every solid than its maximum range gets no return:
  // refused before casting (a scan from outside the scene but within range is fine).
  Eigen::AlignedBox3f solids_box;
  for (const Eigen::Vector3f& v : triangles.vertices) solids_box.extend(v);
  const Eigen::Vector3f centre(float(pose.x), float(pose.y), float(scene.scanner.height));
  const double distance = solids_box.isEmpty() ? HUGE_VAL : solids_box.exteriorDistance(centre);
  if (distance > scene.scanner.max_range) {
    std::ostringstream why;
    why << "--at: the scanner at (" << pose.x << ", " << pose.y << ") is " << distance
        << " m from the scene " << a.scene << " (its solids span x " << solids_box.min().x()
        << " to " << solids_box.max().x() << ", y " << solids_box.min().y() << " to "
        << solids_box.max().y() << "), beyond the scanner's maximum range of "
        << scene.scanner.max_range << " m: it would get no return";
    throw std::runtime_error(why.str());
  }
  const std::unique_ptr<sim::RayCaster> caster = sim::make_ray_caster(triangles);
  const sim::ScanGrid grid = sim::scan_grid(scene.scanner);
  std::cerr << "scan: " << scene.name << " (" << triangles.triangles.size() << " triangles), "
            << grid.rows << " x " << grid.cols << " = "
            << static_cast<std::uint64_t>(grid.rows) * grid.cols << " rays from (" << pose.x << ", "
            << pose.y << ", " << scene.scanner.height << ") yaw " << pose.yaw_deg << "°\n";
  sim::ScanOptions options;
  options.seed = a.seed;
  options.threads = a.threads;
  options.with_intensity = !a.no_intensity;
  int last_percent = -1;
  ProgressLine progress(stderr);
  options.progress = [&](std::uint32_t done, std::uint32_t rows) {
    const int percent = static_cast<int>(100.0 * done / rows);
    if (percent / 10 != last_percent / 10) {
      progress.update("scan: " + std::to_string(percent) + " %");
      last_percent = percent;
    }
  };
  const sim::Scan scan = sim::scan(*caster, scene.scanner, pose, options);
  progress.finish();
  if (scan.points.empty()) {
    std::ostringstream why;
    why << "--at: the scan from (" << pose.x << ", " << pose.y << ") has no return: nothing of "
        << a.scene << " lies within the scanner's range (" << scene.scanner.min_range << " to "
        << scene.scanner.max_range << " m) and elevation limits; nothing written";
    throw std::runtime_error(why.str());
  }
  remove_stale_temporaries(std::filesystem::path(a.out).parent_path().string());
  sim::write_scan(a.out, scan);
  const double seconds = seconds_since(t0);
  std::cout << "wrote " << a.out << ": " << scan.points.size() << " points of " << scan.rays_cast
            << " rays (scanner frame; pose x=" << pose.x << " y=" << pose.y
            << " z=" << scan.sensor_height << " yaw_deg=" << pose.yaw_deg
            << " in the file's viewpoint), " << seconds << " s\n";
  // PCL before 1.14 drops a PLY file's viewpoint on reading (PCL issue #5761).
  if (has_extension(a.out, ".ply"))
    std::cout << "note: PCL 1.13 (Debian 12) does not read a PLY viewpoint back; give this "
                 "scan's pose to classify/nbv with --pose "
              << pose.x << "," << pose.y << "," << scan.sensor_height << "," << pose.yaw_deg
              << ", or write .pcd\n";
}

}  // namespace

void add_scan_command(CLI::App& app) {
  auto args = std::make_shared<ScanArgs>();
  CLI::App* cmd = app.add_subcommand("scan",
                                     "Simulate one 360° terrestrial laser scan of a scene and "
                                     "write the points (in the scanner's frame, with "
                                     "intensity, row and column) as binary PCD or PLY. The scanner "
                                     "pose goes into the file's viewpoint.");
  cmd->add_option(
         "--scene", args->scene,
         "scene to scan: a .scene.json file, an .obj/.ply triangle mesh or an OctoMap .bt file "
         "(occupied voxels are solid)")
      ->required();
  cmd->add_option("--at", args->at,
                  "scanner position on the floor and heading: X,Y or X,Y,YAW_DEG (metres, degrees; "
                  "the optical centre is at the scene's scanner height)")
      ->required();
  cmd->add_option("--out", args->out, "output file, FILE.pcd or FILE.ply (binary)")->required();
  cmd->add_option("--seed", args->seed,
                  "seed of the range noise; the same seed gives the same file (default 1)")
      ->check(seed_value());
  cmd->add_option("--azimuth-step", args->azimuth_step,
                  "azimuth step in degrees (default: the scene's scanner.azimuth_step_deg, 0.2)")
      ->check(finite_in(0.001, 90));
  cmd->add_option(
         "--elevation-step", args->elevation_step,
         "elevation step in degrees (default: the scene's scanner.elevation_step_deg, 0.2)")
      ->check(finite_in(0.001, 90));
  cmd->add_option("--threads", args->threads,
                  "worker threads (default 0: one per core; at most 256); the output does not "
                  "depend on it")
      ->check(thread_count());
  cmd->add_flag("--no-intensity", args->no_intensity, "leave the intensity field out");
  cmd->callback([args] { run_scan(*args); });
}

}  // namespace semioctree::cli
