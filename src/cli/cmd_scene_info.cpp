// `semioctree scene-info FILE`: validate a scene and summarise it.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "option_checks.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "sim_input.h"

namespace semioctree::cli {

namespace {

struct SceneInfoArgs {
  std::string file;
  std::vector<double> at;  // robot start for mesh and .bt scenes
  double cell = 0.05;
};

std::string xyz(const Eigen::Vector3d& p) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return os.str();
}

void run_scene_info(const SceneInfoArgs& a) {
  std::optional<Eigen::Vector2d> start;
  if (!a.at.empty()) {
    if (a.at.size() != 2) throw std::runtime_error("--at: expected X,Y (2 numbers)");
    start = Eigen::Vector2d(a.at[0], a.at[1]);
  }
  const sim::Scene scene = sim::load_scene(a.file, start);
  const sim::GroundTruth truth(scene);
  const sim::SceneTriangles& tri = truth.triangles();

  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& v : tri.vertices) {
    lo = lo.cwiseMin(v.cast<double>());
    hi = hi.cwiseMax(v.cast<double>());
  }
  std::cout << "scene:       " << scene.name << "  (" << a.file << ": valid)\n";
  if (!scene.description.empty()) std::cout << "description: " << scene.description << "\n";
  if (tri.vertices.empty())
    std::cout << "extent:      none (the scene has no geometry)\n";
  else
    std::cout << "extent:      " << xyz(lo) << " to " << xyz(hi) << "  = " << std::fixed
              << std::setprecision(2) << hi.x() - lo.x() << " x " << hi.y() - lo.y() << " x "
              << hi.z() - lo.z() << " m\n";
  std::cout << "elements:    " << scene.walls.size() << " walls, " << scene.slabs.size()
            << " slabs, " << scene.boxes.size() << " boxes, " << scene.cylinders.size()
            << " cylinders, " << scene.meshes.size() << " meshes\n";
  std::cout << "triangles:   " << tri.triangles.size() << "\n";

  const auto openings = truth.openings();
  std::cout << "openings:    " << openings.size() << "\n";
  for (const auto& o : openings) {
    std::cout << "  " << std::left << std::setw(7) << sim::to_string(o.kind) << std::right
              << "walls[" << o.wall << "].openings[" << o.index << "]  " << std::setprecision(2)
              << o.width << " x " << o.height << " m, from " << xyz(o.corners[0]) << " to "
              << xyz(o.corners[2]) << "\n";
  }

  std::cout << std::flush;
  std::cerr << "scene-info: computing the floor plan (" << a.cell << " m cells)...\n";
  const sim::FloorPlan plan = truth.floor_plan(a.cell);
  if (scene.walls.empty()) {
    std::cout << "rooms:       not computed (rooms are the regions enclosed by walls; this scene "
                 "has none)\n";
  } else {
    std::cout << "rooms:       " << plan.room_area.size() << " enclosed by walls (floor area, ±"
              << a.cell << " m cells)\n";
    for (std::size_t r = 0; r < plan.room_area.size(); ++r)
      std::cout << "  room " << r << ": " << std::setprecision(2) << plan.room_area[r] << " m²"
                << (static_cast<int>(r) == plan.start_room ? "  (robot start)" : "") << "\n";
  }
  std::cout << "survey area: " << std::setprecision(2) << plan.survey_area_m2
            << " m² where the robot may stand ("
            << (scene.survey_area ? "survey_area polygon" : "free floor reachable from the start")
            << ")\n";
  std::cout << "robot:       start (" << scene.robot.start.x() << ", " << scene.robot.start.y()
            << "), yaw " << scene.robot.start_yaw_deg << "°, radius " << scene.robot.radius
            << " m, odometry noise " << std::setprecision(3) << scene.robot.odometry_sigma_xy
            << " m/m, " << scene.robot.odometry_sigma_yaw_deg << " °/m\n";
  const auto& s = scene.scanner;
  std::cout << "scanner:     height " << std::setprecision(2) << s.height << " m, steps "
            << s.azimuth_step_deg << "° x " << s.elevation_step_deg << "°, elevation "
            << s.elevation_min_deg << "° to " << s.elevation_max_deg << "°, range " << s.min_range
            << " to " << s.max_range << " m, noise σ " << std::setprecision(4)
            << s.range_noise_sigma << " m\n";
  // The scene format requires the start on free floor; `survey` checks the same.
  std::cout << std::flush;
  try {
    check_robot_start(scene, truth, plan, a.file);
    std::cout << "start:       on free floor, clear of obstacles by the robot's radius\n";
  } catch (const std::invalid_argument& e) {
    if (has_extension(a.file, ".json")) throw;
    // A mesh or .bt (an object, a map) has no start of its own: inspecting it
    // is fine; say what a survey of it would need.
    std::cout << "start:       not usable for a survey: " << e.what() << "\n";
  }
}

}  // namespace

void add_scene_info_command(CLI::App& app) {
  auto args = std::make_shared<SceneInfoArgs>();
  CLI::App* cmd = app.add_subcommand("scene-info",
                                     "Validate a scene and print a summary: extent, elements, "
                                     "triangles, openings, rooms' floor area, survey "
                                     "area, robot and scanner settings. Exits with 1 and a message "
                                     "naming the file, the JSON path and what "
                                     "was expected if the scene is not valid.");
  cmd->add_option("file", args->file,
                  "scene: a .scene.json file, an .obj/.ply mesh or an OctoMap .bt file")
      ->required();
  cmd->add_option("--at", args->at,
                  "robot start X,Y for a mesh or .bt scene (default 0,0); replaces robot.start")
      ->delimiter(',')
      ->expected(2)
      ->check(finite_in(-sim::kMaxSceneNumber, sim::kMaxSceneNumber));
  cmd->add_option("--cell", args->cell, "cell size of the floor plan in metres (default 0.05)")
      ->check(finite_in(0.005, 10));
  cmd->callback([args] { run_scene_info(*args); });
}

}  // namespace semioctree::cli
