// Scene model of the synthetic scanner: the in-memory form of a `*.scene.json`
// file (format version 1, see docs/scene-format.md), or of a triangle mesh /
// OctoMap .bt file given as a scene.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "semioctree/sim/mesh.h"

namespace semioctree::sim {

// Thrown for any scene that cannot be read or breaks a rule of the format. what() is
// "<file>: <json path>: <expectation>, got <value>" or "<file>: <problem>".
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class OpeningKind { door, window };
const char* to_string(OpeningKind kind);

struct Opening {
  OpeningKind kind = OpeningKind::door;
  double start = 0.0;  // along the wall from `from` to the near edge
  double width = 0.0;  // along the wall
  double sill = 0.0;   // bottom of the hole above the wall's z0
  double height = 0.0;
};

struct Wall {
  Eigen::Vector2d from = Eigen::Vector2d::Zero();
  Eigen::Vector2d to = Eigen::Vector2d::Zero();
  double thickness = 0.2;
  double z0 = 0.0;
  double z1 = 3.0;
  std::vector<Opening> openings;

  double length() const { return (to - from).norm(); }
  Eigen::Vector2d direction() const { return (to - from).normalized(); }
  // Unit normal in the xy-plane, to the left of from→to.
  Eigen::Vector2d normal() const {
    const Eigen::Vector2d d = direction();
    return {-d.y(), d.x()};
  }
};

struct Slab {
  std::vector<Eigen::Vector2d> polygon;
  double z0 = 0.0;
  double z1 = 0.0;
};

struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
  double yaw_deg = 0.0;
  std::string name;
};

struct Cylinder {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius = 0.0;
  double z0 = 0.0;
  double z1 = 0.0;
  std::string name;
};

// Largest magnitude of any number in a scene, and of positions given for one
// (metres, degrees): beyond it a value is a typo, and it would reach the ray
// caster (Embree rejects coordinates beyond ~1e18) or size grids by the extent.
constexpr double kMaxSceneNumber = 1e5;

struct MeshInstance {
  std::string file;  // as written in the scene (relative to the scene file)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw_deg = 0.0;
  double scale = 1.0;
  TriangleMesh mesh;  // loaded, in the mesh's own frame (before scale, yaw, position)

  Eigen::Vector3d to_world(const Eigen::Vector3d& local) const;
};

struct RobotConfig {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  double start_yaw_deg = 0.0;
  double radius = 0.5;
  double odometry_sigma_xy = 0.02;      // metres per metre driven
  double odometry_sigma_yaw_deg = 0.5;  // degrees per metre driven
};

struct ScannerConfig {
  double height = 1.5;
  double azimuth_step_deg = 0.2;
  double elevation_step_deg = 0.2;
  double elevation_min_deg = -60.0;
  double elevation_max_deg = 90.0;
  double min_range = 0.6;
  double max_range = 60.0;
  double range_noise_sigma = 0.002;
};

struct Scene {
  std::string source_file;  // the path it was read from, for messages
  std::string name;
  std::string description;
  std::vector<Wall> walls;
  std::vector<Slab> slabs;
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<MeshInstance> meshes;
  RobotConfig robot;
  ScannerConfig scanner;
  std::optional<std::vector<Eigen::Vector2d>> survey_area;
};

// Reads and validates a `*.scene.json` file. Throws SceneError.
Scene load_scene_json(const std::string& path);
// Same from text; `file_name` is used in messages and `base_dir` resolves mesh paths.
Scene parse_scene_json(const std::string& text, const std::string& file_name,
                       const std::string& base_dir);

// A triangle mesh (OBJ or PLY) or an OctoMap .bt file taken as the whole scene, with the
// robot starting at `start` (these files carry no robot). Default scanner settings.
Scene scene_from_mesh_file(const std::string& path, const Eigen::Vector2d& start,
                           double start_yaw_deg = 0.0);
Scene scene_from_octomap_file(const std::string& path, const Eigen::Vector2d& start,
                              double start_yaw_deg = 0.0);

// Dispatches on the file name: *.json → scene file, *.obj/*.ply → mesh, *.bt → OctoMap.
// `start` replaces robot.start of a JSON scene if given, and is the start of a mesh or
// .bt scene (the origin if not given).
Scene load_scene(const std::string& path, const std::optional<Eigen::Vector2d>& start = {},
                 double start_yaw_deg = 0.0);

// The four corners of opening `o` of wall `w` in world coordinates, on the wall's centre
// plane: bottom-near, bottom-far, top-far, top-near ("near" = closer to `from`).
std::vector<Eigen::Vector3d> opening_corners(const Wall& w, const Opening& o);

}  // namespace semioctree::sim
