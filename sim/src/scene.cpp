// Reading and validating scene files (docs/scene-format.md, version 1).
#include "semioctree/sim/scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/solids.h"

namespace semioctree::sim {

using nlohmann::json;
namespace fs = std::filesystem;

const char* to_string(OpeningKind kind) {
  return kind == OpeningKind::door ? "door" : "window";
}

Eigen::Vector3d MeshInstance::to_world(const Eigen::Vector3d& local) const {
  const Eigen::AngleAxisd yaw(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  return yaw * (scale * local) + position;
}

std::vector<Eigen::Vector3d> opening_corners(const Wall& w, const Opening& o) {
  const Eigen::Vector2d d = w.direction();
  const Eigen::Vector2d near = w.from + d * o.start;
  const Eigen::Vector2d far = w.from + d * (o.start + o.width);
  const double bottom = w.z0 + o.sill;
  const double top = bottom + o.height;
  return {{near.x(), near.y(), bottom},
          {far.x(), far.y(), bottom},
          {far.x(), far.y(), top},
          {near.x(), near.y(), top}};
}

namespace {

// Short rendering of a JSON value for "got ..." in messages.
std::string show(const json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string show(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

std::string join(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}

std::string at(const std::string& prefix, std::size_t i) {
  return prefix + "[" + std::to_string(i) + "]";
}

// Walks one scene document; every failure names the file and the JSON path.
class SceneReader {
 public:
  SceneReader(std::string file, std::string base_dir)
      : file_(std::move(file)), base_dir_(std::move(base_dir)) {}

  Scene read(const json& root);

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SceneError(file_ + ": " + (path.empty() ? std::string("(top level)") : path) + ": " +
                     what);
  }

  void require_object(const json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, "must be an object, got " + show(v));
  }

  // Rejects keys not in `allowed`, except comments (keys starting with '_').
  void check_keys(const json& obj, const std::string& path,
                  std::initializer_list<const char*> allowed) const {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      const std::string& key = it.key();
      if (!key.empty() && key[0] == '_') continue;
      if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; }) !=
          allowed.end())
        continue;
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      fail(join(path, key),
           "unknown key (expected one of: " + list + "; keys starting with _ are comments)");
    }
  }

  const json* find(const json& obj, const char* key) const {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  const json& required(const json& obj, const std::string& path, const char* key) const {
    const json* v = find(obj, key);
    if (!v) fail(join(path, key), "required, missing");
    return *v;
  }

  double as_number(const json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, "must be a number, got " + show(v));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(path, "must be a finite number, got " + show(v));
    if (std::abs(x) > kMaxSceneNumber)
      fail(path, "must be within ±" + show(json(kMaxSceneNumber)) + ", got " + show(v));
    return x;
  }

  double number(const json& obj, const std::string& path, const char* key, double fallback) const {
    const json* v = find(obj, key);
    return v ? as_number(*v, join(path, key)) : fallback;
  }

  double required_number(const json& obj, const std::string& path, const char* key) const {
    return as_number(required(obj, path, key), join(path, key));
  }

  std::string string(const json& obj, const std::string& path, const char* key,
                     const std::string& fallback) const {
    const json* v = find(obj, key);
    if (!v) return fallback;
    if (!v->is_string()) fail(join(path, key), "must be a string, got " + show(*v));
    return v->get<std::string>();
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vec(const json& v, const std::string& path,
                                  const char* shape = nullptr) const {
    if (!shape) shape = N == 2 ? "[x, y]" : "[x, y, z]";
    if (!v.is_array() || v.size() != N)
      fail(path,
           "must be an array of " + std::to_string(N) + " numbers " + shape + ", got " + show(v));
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = as_number(v[i], at(path, i));
    return out;
  }

  void positive(double x, const std::string& path) const {
    if (!(x > 0)) fail(path, "must be > 0, got " + show(x));
  }
  void non_negative(double x, const std::string& path) const {
    if (!(x >= 0)) fail(path, "must be >= 0, got " + show(x));
  }

  const json& array(const json& obj, const std::string& path, const char* key) const {
    static const json empty = json::array();
    const json* v = find(obj, key);
    if (!v) return empty;
    if (!v->is_array()) fail(join(path, key), "must be an array, got " + show(*v));
    return *v;
  }

  // z0 / z1 pair, z1 > z0.
  void z_range(const json& obj, const std::string& path, bool required_keys, double def0,
               double def1, double& z0, double& z1) const {
    z0 = required_keys ? required_number(obj, path, "z0") : number(obj, path, "z0", def0);
    z1 = required_keys ? required_number(obj, path, "z1") : number(obj, path, "z1", def1);
    if (!(z1 > z0)) fail(join(path, "z1"), "must be > z0 (" + show(z0) + "), got " + show(z1));
  }

  std::vector<Eigen::Vector2d> polygon(const json& v, const std::string& path) const;
  Wall wall(const json& v, const std::string& path) const;
  Opening opening(const json& v, const std::string& path, const Wall& w) const;
  Slab slab(const json& v, const std::string& path) const;
  Box box(const json& v, const std::string& path) const;
  Cylinder cylinder(const json& v, const std::string& path) const;
  MeshInstance mesh(const json& v, const std::string& path) const;
  RobotConfig robot(const json& v, const std::string& path) const;
  ScannerConfig scanner(const json& v, const std::string& path) const;
  void check_start(const Scene& scene) const;

  std::string file_;
  std::string base_dir_;
};

std::vector<Eigen::Vector2d> SceneReader::polygon(const json& v, const std::string& path) const {
  if (!v.is_array()) fail(path, "must be an array of [x, y] points, got " + show(v));
  if (v.size() < 3) fail(path, "must have at least 3 points, got " + std::to_string(v.size()));
  std::vector<Eigen::Vector2d> points;
  for (std::size_t i = 0; i < v.size(); ++i) {
    points.push_back(vec<2>(v[i], at(path, i)));
    if (i > 0 && (points[i] - points[i - 1]).norm() < 1e-9)
      fail(at(path, i), "must differ from the previous point, got " + show(v[i]));
  }
  if ((points.front() - points.back()).norm() < 1e-9)
    fail(at(path, v.size() - 1),
         "must differ from the first point (the polygon closes itself), got " + show(v.back()));
  const auto cross = first_self_intersection(points);
  if (cross[0] >= 0)
    fail(path, "must be a simple polygon, edges " + std::to_string(cross[0]) + " and " +
                   std::to_string(cross[1]) + " touch or cross");
  if (std::abs(signed_area(points)) < 1e-9) fail(path, "must enclose a non-zero area");
  return points;
}

Opening SceneReader::opening(const json& v, const std::string& path, const Wall& w) const {
  require_object(v, path);
  check_keys(v, path, {"kind", "start", "width", "sill", "height"});
  Opening o;
  const json& kind = required(v, path, "kind");
  if (kind == "door")
    o.kind = OpeningKind::door;
  else if (kind == "window")
    o.kind = OpeningKind::window;
  else
    fail(join(path, "kind"), "must be \"door\" or \"window\", got " + show(kind));
  o.start = required_number(v, path, "start");
  non_negative(o.start, join(path, "start"));
  o.width = required_number(v, path, "width");
  positive(o.width, join(path, "width"));
  if (o.start + o.width > w.length() + 1e-9)
    fail(join(path, "width"), "start + width must not exceed the wall length " + show(w.length()) +
                                  ", got " + show(o.start) + " + " + show(o.width) + " = " +
                                  show(o.start + o.width));
  o.sill = number(v, path, "sill", o.kind == OpeningKind::door ? 0.0 : 0.9);
  non_negative(o.sill, join(path, "sill"));
  o.height = required_number(v, path, "height");
  positive(o.height, join(path, "height"));
  const double wall_height = w.z1 - w.z0;
  if (o.sill + o.height > wall_height + 1e-9)
    fail(join(path, "height"), "sill + height must not exceed the wall height " +
                                   show(wall_height) + ", got " + show(o.sill) + " + " +
                                   show(o.height) + " = " + show(o.sill + o.height));
  return o;
}

Wall SceneReader::wall(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"from", "to", "thickness", "z0", "z1", "openings"});
  Wall w;
  w.from = vec<2>(required(v, path, "from"), join(path, "from"));
  w.to = vec<2>(required(v, path, "to"), join(path, "to"));
  if ((w.to - w.from).norm() < 1e-9)
    fail(join(path, "to"),
         "must differ from \"from\" (a wall needs a length), got " + show(v["to"]));
  w.thickness = number(v, path, "thickness", 0.2);
  positive(w.thickness, join(path, "thickness"));
  z_range(v, path, false, 0.0, 3.0, w.z0, w.z1);
  const json& openings = array(v, path, "openings");
  const std::string opath = join(path, "openings");
  for (std::size_t i = 0; i < openings.size(); ++i) {
    const Opening o = opening(openings[i], at(opath, i), w);
    for (std::size_t j = 0; j < w.openings.size(); ++j) {
      const Opening& p = w.openings[j];
      const double du = std::min(o.start + o.width, p.start + p.width) - std::max(o.start, p.start);
      const double dv = std::min(o.sill + o.height, p.sill + p.height) - std::max(o.sill, p.sill);
      if (du > 1e-9 && dv > 1e-9)
        fail(at(opath, i),
             "must not overlap " + at(opath, j) + " (openings of one wall are disjoint)");
    }
    w.openings.push_back(o);
  }
  return w;
}

Slab SceneReader::slab(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"polygon", "z0", "z1"});
  Slab s;
  s.polygon = polygon(required(v, path, "polygon"), join(path, "polygon"));
  z_range(v, path, true, 0, 0, s.z0, s.z1);
  return s;
}

Box SceneReader::box(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"center", "size", "yaw_deg", "name"});
  Box b;
  b.center = vec<3>(required(v, path, "center"), join(path, "center"));
  b.size = vec<3>(required(v, path, "size"), join(path, "size"));
  for (int i = 0; i < 3; ++i) positive(b.size[i], at(join(path, "size"), i));
  b.yaw_deg = number(v, path, "yaw_deg", 0.0);
  b.name = string(v, path, "name", "");
  return b;
}

Cylinder SceneReader::cylinder(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"center", "radius", "z0", "z1", "name"});
  Cylinder c;
  c.center = vec<2>(required(v, path, "center"), join(path, "center"));
  c.radius = required_number(v, path, "radius");
  positive(c.radius, join(path, "radius"));
  z_range(v, path, true, 0, 0, c.z0, c.z1);
  c.name = string(v, path, "name", "");
  return c;
}

MeshInstance SceneReader::mesh(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"file", "position", "yaw_deg", "scale"});
  MeshInstance m;
  const json& file = required(v, path, "file");
  if (!file.is_string() || file.get<std::string>().empty())
    fail(join(path, "file"), "must be a file name, got " + show(file));
  m.file = file.get<std::string>();
  if (const json* p = find(v, "position")) m.position = vec<3>(*p, join(path, "position"));
  m.yaw_deg = number(v, path, "yaw_deg", 0.0);
  m.scale = number(v, path, "scale", 1.0);
  positive(m.scale, join(path, "scale"));
  std::string ext = fs::path(m.file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".ply")
    fail(join(path, "file"), "must be an OBJ or PLY mesh (.obj, .ply), got " + show(file));
  const fs::path resolved =
      fs::path(m.file).is_absolute() ? fs::path(m.file) : fs::path(base_dir_) / m.file;
  try {
    m.mesh = read_mesh_file(resolved.string());
  } catch (const std::exception& e) {
    fail(join(path, "file"), std::string("cannot read the mesh: ") + e.what());
  }
  // The placed mesh, not only the numbers written here, must stay in range.
  double radius = 0;
  for (const Eigen::Vector3d& p : m.mesh.vertices) radius = std::max(radius, p.norm());
  if (radius * m.scale + m.position.norm() > kMaxSceneNumber)
    fail(path, "the placed mesh reaches " + show(json(radius * m.scale + m.position.norm())) +
                   " m from the origin (at most " + show(json(kMaxSceneNumber)) +
                   "): check scale and position");
  return m;
}

RobotConfig SceneReader::robot(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path, {"start", "start_yaw_deg", "radius", "odometry_noise"});
  RobotConfig r;
  r.start = vec<2>(required(v, path, "start"), join(path, "start"));
  r.start_yaw_deg = number(v, path, "start_yaw_deg", 0.0);
  r.radius = number(v, path, "radius", 0.5);
  positive(r.radius, join(path, "radius"));
  if (const json* n = find(v, "odometry_noise")) {
    const Eigen::Vector2d sigma =
        vec<2>(*n, join(path, "odometry_noise"), "[sigma_xy, sigma_yaw_deg]");
    non_negative(sigma[0], at(join(path, "odometry_noise"), 0));
    non_negative(sigma[1], at(join(path, "odometry_noise"), 1));
    r.odometry_sigma_xy = sigma[0];
    r.odometry_sigma_yaw_deg = sigma[1];
  }
  return r;
}

ScannerConfig SceneReader::scanner(const json& v, const std::string& path) const {
  require_object(v, path);
  check_keys(v, path,
             {"height", "azimuth_step_deg", "elevation_step_deg", "elevation_min_deg",
              "elevation_max_deg", "min_range", "max_range", "range_noise_sigma"});
  ScannerConfig s;
  s.height = number(v, path, "height", s.height);
  positive(s.height, join(path, "height"));
  s.azimuth_step_deg = number(v, path, "azimuth_step_deg", s.azimuth_step_deg);
  positive(s.azimuth_step_deg, join(path, "azimuth_step_deg"));
  s.elevation_step_deg = number(v, path, "elevation_step_deg", s.elevation_step_deg);
  positive(s.elevation_step_deg, join(path, "elevation_step_deg"));
  s.elevation_min_deg = number(v, path, "elevation_min_deg", s.elevation_min_deg);
  s.elevation_max_deg = number(v, path, "elevation_max_deg", s.elevation_max_deg);
  if (!(s.elevation_min_deg >= -90 && s.elevation_min_deg <= 90))
    fail(join(path, "elevation_min_deg"), "must be in [-90, 90], got " + show(s.elevation_min_deg));
  if (!(s.elevation_max_deg >= -90 && s.elevation_max_deg <= 90))
    fail(join(path, "elevation_max_deg"), "must be in [-90, 90], got " + show(s.elevation_max_deg));
  if (!(s.elevation_max_deg > s.elevation_min_deg))
    fail(join(path, "elevation_max_deg"), "must be > elevation_min_deg (" +
                                              show(s.elevation_min_deg) + "), got " +
                                              show(s.elevation_max_deg));
  s.min_range = number(v, path, "min_range", s.min_range);
  positive(s.min_range, join(path, "min_range"));
  s.max_range = number(v, path, "max_range", s.max_range);
  positive(s.max_range, join(path, "max_range"));
  if (!(s.max_range > s.min_range))
    fail(join(path, "max_range"),
         "must be > min_range (" + show(s.min_range) + "), got " + show(s.max_range));
  s.range_noise_sigma = number(v, path, "range_noise_sigma", s.range_noise_sigma);
  non_negative(s.range_noise_sigma, join(path, "range_noise_sigma"));
  return s;
}

// robot.start must be free floor: no solid in the scanner's column from just above the
// floor to the optical centre.
void SceneReader::check_start(const Scene& scene) const {
  const SolidModel solids(scene);
  const Eigen::Vector2d s = scene.robot.start;
  const int steps = std::max(2, static_cast<int>(std::ceil(scene.scanner.height / 0.01)));
  for (int i = 0; i <= steps; ++i) {
    const double z = 0.01 + (scene.scanner.height - 0.01) * i / steps;
    const std::string inside = solids.solid_containing({s.x(), s.y(), z});
    if (!inside.empty())
      fail("robot.start", "must be free floor up to the scanner height, got [" + show(s.x()) +
                              ", " + show(s.y()) + "], inside " + inside + " at z = " + show(z));
  }
  if (scene.survey_area && !point_in_polygon(*scene.survey_area, s))
    fail("robot.start",
         "must lie inside survey_area, got [" + show(s.x()) + ", " + show(s.y()) + "]");
}

Scene SceneReader::read(const json& root) {
  require_object(root, "");
  check_keys(root, "",
             {"format", "version", "name", "description", "walls", "slabs", "boxes", "cylinders",
              "meshes", "robot", "scanner", "survey_area"});
  Scene scene;
  scene.source_file = file_;
  const json& format = required(root, "", "format");
  if (format != "semioctree-scene")
    fail("format", "must be \"semioctree-scene\", got " + show(format));
  const json& version = required(root, "", "version");
  if (!version.is_number_integer() || version.get<long long>() != 1)
    fail("version", "must be the integer 1, got " + show(version));
  const json& name = required(root, "", "name");
  if (!name.is_string() || name.get<std::string>().empty())
    fail("name", "must be a non-empty string, got " + show(name));
  scene.name = name.get<std::string>();
  // The name goes into output file names: no path separators or control characters.
  for (char c : scene.name)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20)
      fail("name",
           "must not contain '/', '\\' or control characters (it is used in file names), got " +
               show(name));
  scene.description = string(root, "", "description", "");

  const json& walls = array(root, "", "walls");
  for (std::size_t i = 0; i < walls.size(); ++i)
    scene.walls.push_back(wall(walls[i], at("walls", i)));
  const json& slabs = array(root, "", "slabs");
  for (std::size_t i = 0; i < slabs.size(); ++i)
    scene.slabs.push_back(slab(slabs[i], at("slabs", i)));
  const json& boxes = array(root, "", "boxes");
  for (std::size_t i = 0; i < boxes.size(); ++i)
    scene.boxes.push_back(box(boxes[i], at("boxes", i)));
  const json& cylinders = array(root, "", "cylinders");
  for (std::size_t i = 0; i < cylinders.size(); ++i)
    scene.cylinders.push_back(cylinder(cylinders[i], at("cylinders", i)));
  const json& meshes = array(root, "", "meshes");
  for (std::size_t i = 0; i < meshes.size(); ++i)
    scene.meshes.push_back(mesh(meshes[i], at("meshes", i)));

  scene.robot = robot(required(root, "", "robot"), "robot");
  if (const json* s = find(root, "scanner")) scene.scanner = scanner(*s, "scanner");
  if (const json* a = find(root, "survey_area")) scene.survey_area = polygon(*a, "survey_area");
  check_start(scene);
  return scene;
}

std::string read_text(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw SceneError(path + ": is a directory, expected a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

Scene scene_of_mesh(const std::string& path, TriangleMesh mesh, const Eigen::Vector2d& start,
                    double start_yaw_deg) {
  Scene scene;
  scene.source_file = path;
  scene.name = fs::path(path).stem().string();
  MeshInstance m;
  m.file = path;
  m.mesh = std::move(mesh);
  scene.meshes.push_back(std::move(m));
  scene.robot.start = start;
  scene.robot.start_yaw_deg = start_yaw_deg;
  return scene;
}

}  // namespace

Scene parse_scene_json(const std::string& text, const std::string& file_name,
                       const std::string& base_dir) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    // Turn the byte offset into line and column, which is what a person looks for.
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    std::string what = e.what();
    const auto colon = what.find("syntax error");
    if (colon != std::string::npos) what = what.substr(colon);
    throw SceneError(file_name + ": invalid JSON at line " + std::to_string(line) + ", column " +
                     std::to_string(column) + ": " + what);
  } catch (const json::out_of_range& e) {
    // A number beyond a double (1e400); nlohmann gives no position for it.
    std::string what = e.what();
    const auto tail = what.find("number overflow");
    throw SceneError(file_name +
                     ": invalid JSON: " + (tail == std::string::npos ? what : what.substr(tail)));
  }
  SceneReader reader(file_name, base_dir);
  Scene scene = reader.read(root);
  return scene;
}

Scene load_scene_json(const std::string& path) {
  const std::string text = read_text(path);
  Scene scene = parse_scene_json(text, path, fs::path(path).parent_path().string());
  return scene;
}

Scene scene_from_mesh_file(const std::string& path, const Eigen::Vector2d& start,
                           double start_yaw_deg) {
  TriangleMesh mesh;
  try {
    mesh = read_mesh_file(path);
  } catch (const std::exception& e) {
    throw SceneError(e.what());
  }
  return scene_of_mesh(path, std::move(mesh), start, start_yaw_deg);
}

Scene scene_from_octomap_file(const std::string& path, const Eigen::Vector2d& start,
                              double start_yaw_deg) {
  TriangleMesh mesh;
  try {
    mesh = read_octomap_occupied(path);
  } catch (const std::exception& e) {
    throw SceneError(e.what());
  }
  return scene_of_mesh(path, std::move(mesh), start, start_yaw_deg);
}

Scene load_scene(const std::string& path, const std::optional<Eigen::Vector2d>& start,
                 double start_yaw_deg) {
  const std::string ext = lower_extension(path);
  if (ext == ".json") {
    Scene scene = load_scene_json(path);
    if (start) {
      scene.robot.start = *start;
      scene.robot.start_yaw_deg = start_yaw_deg;
    }
    return scene;
  }
  const Eigen::Vector2d s = start.value_or(Eigen::Vector2d::Zero());
  if (ext == ".obj" || ext == ".ply") return scene_from_mesh_file(path, s, start_yaw_deg);
  if (ext == ".bt") return scene_from_octomap_file(path, s, start_yaw_deg);
  throw SceneError(path + ": unknown scene type \"" + ext +
                   "\", expected a .scene.json file, an .obj or .ply mesh, or an OctoMap .bt file");
}

}  // namespace semioctree::sim
