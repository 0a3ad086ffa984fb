// Scene files: every rule of docs/scene-format.md and its message, defaults, mesh and
// .bt scenes, and the `semioctree scene-info` command.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/scene.h"
#include "support/cli_run.h"

namespace {

using nlohmann::json;
using namespace semioctree::sim;
namespace fs = std::filesystem;
using semioctree::testing::CliRun;
using semioctree::testing::run_cli;
using semioctree::testing::scratch;

const std::string kScenes = SEMIOCTREE_SOURCE_DIR "/sim/scenes";

// A small valid scene that each rule test breaks in one place.
json base_scene() {
  return json::parse(R"({
    "format": "semioctree-scene", "version": 1, "name": "t",
    "walls": [{"from": [0, 0], "to": [4, 0], "z1": 2.5,
               "openings": [{"kind": "door", "start": 0.5, "width": 0.9, "height": 2.0}]}],
    "slabs": [{"polygon": [[-1, -1], [5, -1], [5, 5], [-1, 5]], "z0": -0.2, "z1": 0}],
    "boxes": [{"center": [2, 2, 0.4], "size": [1, 0.5, 0.8]}],
    "cylinders": [{"center": [3, 3], "radius": 0.2, "z0": 0, "z1": 2.5}],
    "robot": {"start": [1, 2]},
    "scanner": {"height": 1.5}
  })");
}

std::string error_of(const json& scene, const std::string& base_dir = kScenes) {
  try {
    parse_scene_json(scene.dump(), "t.scene.json", base_dir);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string error_of_text(const std::string& text) {
  try {
    parse_scene_json(text, "t.scene.json", kScenes);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

struct Rule {
  std::string pointer;  // JSON pointer of the value to set
  std::string value;    // JSON text; "REMOVE" deletes the key
  std::string message;  // expected what() after "t.scene.json: "
};

// Names the generated test cases after the JSON pointer, e.g. "walls_0_thickness_3".
std::string rule_name(const ::testing::TestParamInfo<Rule>& info) {
  std::string name;
  for (char c : info.param.pointer) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name.substr(1) + "_" + std::to_string(info.index);
}

class RuleTest : public ::testing::TestWithParam<Rule> {};

TEST_P(RuleTest, MessageNamesFilePathAndExpectation) {
  const Rule& r = GetParam();
  json scene = base_scene();
  const json::json_pointer ptr(r.pointer);
  if (r.value == "REMOVE")
    scene[ptr.parent_pointer()].erase(ptr.back());
  else
    scene[ptr] = json::parse(r.value);
  EXPECT_EQ(error_of(scene), "t.scene.json: " + r.message);
}

const char* kTopKeys =
    "format, version, name, description, walls, slabs, boxes, cylinders, meshes, robot, scanner, "
    "survey_area";

INSTANTIATE_TEST_SUITE_P(
    Format, RuleTest,
    ::testing::Values(
        // Top level.
        Rule{"/format", "REMOVE", "format: required, missing"},
        Rule{"/format", R"("semioctree-scan")",
             R"(format: must be "semioctree-scene", got "semioctree-scan")"},
        Rule{"/version", "REMOVE", "version: required, missing"},
        Rule{"/version", "2", "version: must be the integer 1, got 2"},
        Rule{"/version", "1.0", "version: must be the integer 1, got 1.0"},
        Rule{"/name", "REMOVE", "name: required, missing"},
        Rule{"/name", "\"\"", "name: must be a non-empty string, got \"\""},
        Rule{"/name", "\"lab/2\"",
             "name: must not contain '/', '\\' or control characters (it is used in file names), "
             "got \"lab/2\""},
        Rule{"/description", "3", "description: must be a string, got 3"},
        Rule{"/walls", "{}", "walls: must be an array, got {}"},
        Rule{"/slabs", "1", "slabs: must be an array, got 1"},
        Rule{"/boxes", "\"x\"", "boxes: must be an array, got \"x\""},
        Rule{"/cylinders", "null", "cylinders: must be an array, got null"},
        Rule{"/meshes", "{}", "meshes: must be an array, got {}"},
        Rule{"/colour", "1",
             std::string("colour: unknown key (expected one of: ") + kTopKeys +
                 "; keys starting with _ are comments)"},
        // Wall.
        Rule{"/walls/0", "[]", "walls[0]: must be an object, got []"},
        Rule{"/walls/0/from", "REMOVE", "walls[0].from: required, missing"},
        Rule{"/walls/0/to", "REMOVE", "walls[0].to: required, missing"},
        Rule{"/walls/0/from", "[1]",
             "walls[0].from: must be an array of 2 numbers [x, y], got [1]"},
        Rule{"/walls/0/from", "[1, \"a\"]", "walls[0].from[1]: must be a number, got \"a\""},
        Rule{"/walls/0/to", "[0, 0]",
             "walls[0].to: must differ from \"from\" (a wall needs a length), got [0,0]"},
        Rule{"/walls/0/thickness", "0", "walls[0].thickness: must be > 0, got 0"},
        Rule{"/walls/0/thickness", "true", "walls[0].thickness: must be a number, got true"},
        Rule{"/walls/0/z0", "3", "walls[0].z1: must be > z0 (3), got 2.5"},
        Rule{"/walls/0/thikness", "0.1",
             "walls[0].thikness: unknown key (expected one of: from, to, thickness, z0, z1, "
             "openings; keys "
             "starting with _ are comments)"},
        Rule{"/walls/0/openings", "{}", "walls[0].openings: must be an array, got {}"},
        // Opening.
        Rule{"/walls/0/openings/0/kind", "REMOVE", "walls[0].openings[0].kind: required, missing"},
        Rule{"/walls/0/openings/0/kind", "\"hatch\"",
             "walls[0].openings[0].kind: must be \"door\" or \"window\", got \"hatch\""},
        Rule{"/walls/0/openings/0/start", "REMOVE",
             "walls[0].openings[0].start: required, missing"},
        Rule{"/walls/0/openings/0/start", "-0.1",
             "walls[0].openings[0].start: must be >= 0, got -0.1"},
        Rule{"/walls/0/openings/0/width", "REMOVE",
             "walls[0].openings[0].width: required, missing"},
        Rule{"/walls/0/openings/0/width", "-0.9",
             "walls[0].openings[0].width: must be > 0, got -0.9"},
        Rule{"/walls/0/openings/0/width", "3.6",
             "walls[0].openings[0].width: start + width must not exceed the wall length 4, got 0.5 "
             "+ 3.6 = 4.1"},
        Rule{"/walls/0/openings/0/sill", "-1", "walls[0].openings[0].sill: must be >= 0, got -1"},
        Rule{"/walls/0/openings/0/height", "REMOVE",
             "walls[0].openings[0].height: required, missing"},
        Rule{"/walls/0/openings/0/height", "0", "walls[0].openings[0].height: must be > 0, got 0"},
        Rule{"/walls/0/openings/0/height", "2.6",
             "walls[0].openings[0].height: sill + height must not exceed the wall height 2.5, got "
             "0 + 2.6 = 2.6"},
        // A window's default sill (0.9) counts in that rule.
        Rule{"/walls/0/openings/0/kind", "\"window\"",
             "walls[0].openings[0].height: sill + height must not exceed the wall height 2.5, got "
             "0.9 + 2 = 2.9"},
        Rule{"/walls/0/openings/1", R"({"kind": "window", "start": 1.2, "width": 1, "height": 1})",
             "walls[0].openings[1]: must not overlap walls[0].openings[0] (openings of one wall "
             "are disjoint)"},
        Rule{"/walls/0/openings/0/glass", "true",
             "walls[0].openings[0].glass: unknown key (expected one of: kind, start, width, sill, "
             "height; keys "
             "starting with _ are comments)"},
        // Slab.
        Rule{"/slabs/0/polygon", "REMOVE", "slabs[0].polygon: required, missing"},
        Rule{"/slabs/0/polygon", "[[0, 0], [1, 0]]",
             "slabs[0].polygon: must have at least 3 points, got 2"},
        Rule{"/slabs/0/polygon", "{}",
             "slabs[0].polygon: must be an array of [x, y] points, got {}"},
        Rule{"/slabs/0/polygon/1", "[1, 2, 3]",
             "slabs[0].polygon[1]: must be an array of 2 numbers [x, y], got [1,2,3]"},
        Rule{"/slabs/0/polygon/1", "[-1, -1]",
             "slabs[0].polygon[1]: must differ from the previous point, got [-1,-1]"},
        Rule{"/slabs/0/polygon/4", "[-1, -1]",
             "slabs[0].polygon[4]: must differ from the first point (the polygon closes itself), "
             "got [-1,-1]"},
        Rule{"/slabs/0/polygon", "[[0, 0], [2, 2], [2, 0], [0, 2]]",
             "slabs[0].polygon: must be a simple polygon, edges 0 and 2 touch or cross"},
        Rule{"/slabs/0/polygon", "[[0, 0], [2, 0], [1, 0]]",
             "slabs[0].polygon: must be a simple polygon, edges 0 and 1 touch or cross"},
        Rule{"/slabs/0/z0", "REMOVE", "slabs[0].z0: required, missing"},
        Rule{"/slabs/0/z1", "REMOVE", "slabs[0].z1: required, missing"},
        Rule{"/slabs/0/z1", "-0.2", "slabs[0].z1: must be > z0 (-0.2), got -0.2"},
        Rule{"/slabs/0/height", "1",
             "slabs[0].height: unknown key (expected one of: polygon, z0, z1; keys starting with _ "
             "are comments)"},
        // Box.
        Rule{"/boxes/0/center", "REMOVE", "boxes[0].center: required, missing"},
        Rule{"/boxes/0/center", "[1, 2]",
             "boxes[0].center: must be an array of 3 numbers [x, y, z], got [1,2]"},
        Rule{"/boxes/0/size", "REMOVE", "boxes[0].size: required, missing"},
        Rule{"/boxes/0/size/1", "0", "boxes[0].size[1]: must be > 0, got 0"},
        Rule{"/boxes/0/yaw_deg", "\"15\"", "boxes[0].yaw_deg: must be a number, got \"15\""},
        Rule{"/boxes/0/name", "7", "boxes[0].name: must be a string, got 7"},
        Rule{"/boxes/0/colour", "1",
             "boxes[0].colour: unknown key (expected one of: center, size, yaw_deg, name; keys "
             "starting with _ are "
             "comments)"},
        // Cylinder.
        Rule{"/cylinders/0/center", "REMOVE", "cylinders[0].center: required, missing"},
        Rule{"/cylinders/0/radius", "REMOVE", "cylinders[0].radius: required, missing"},
        Rule{"/cylinders/0/radius", "-0.2", "cylinders[0].radius: must be > 0, got -0.2"},
        Rule{"/cylinders/0/z0", "REMOVE", "cylinders[0].z0: required, missing"},
        Rule{"/cylinders/0/z1", "0", "cylinders[0].z1: must be > z0 (0), got 0"},
        Rule{"/cylinders/0/name", "false", "cylinders[0].name: must be a string, got false"},
        Rule{"/cylinders/0/height", "2",
             "cylinders[0].height: unknown key (expected one of: center, radius, z0, z1, name; "
             "keys starting with "
             "_ are comments)"},
        // Mesh.
        Rule{"/meshes", R"([{"position": [0, 0, 0]}])", "meshes[0].file: required, missing"},
        Rule{"/meshes", R"([{"file": 3}])", "meshes[0].file: must be a file name, got 3"},
        Rule{"/meshes", R"([{"file": "chair.stl"}])",
             "meshes[0].file: must be an OBJ or PLY mesh (.obj, .ply), got \"chair.stl\""},
        Rule{"/meshes", R"([{"file": "meshes/chair.obj", "scale": 0}])",
             "meshes[0].scale: must be > 0, got 0"},
        Rule{"/meshes", R"([{"file": "meshes/chair.obj", "position": [1, 2]}])",
             "meshes[0].position: must be an array of 3 numbers [x, y, z], got [1,2]"},
        Rule{"/meshes", R"([{"file": "meshes/chair.obj", "yaw": 3}])",
             "meshes[0].yaw: unknown key (expected one of: file, position, yaw_deg, scale; keys "
             "starting with _ "
             "are comments)"},
        // Robot.
        Rule{"/robot", "REMOVE", "robot: required, missing"},
        Rule{"/robot", "[1, 2]", "robot: must be an object, got [1,2]"},
        Rule{"/robot/start", "REMOVE", "robot.start: required, missing"},
        Rule{"/robot/start_yaw_deg", "null", "robot.start_yaw_deg: must be a number, got null"},
        Rule{"/robot/radius", "0", "robot.radius: must be > 0, got 0"},
        Rule{"/robot/odometry_noise", "[0.02]",
             "robot.odometry_noise: must be an array of 2 numbers [sigma_xy, sigma_yaw_deg], got "
             "[0.02]"},
        Rule{"/robot/odometry_noise", "[-0.02, 0.5]",
             "robot.odometry_noise[0]: must be >= 0, got -0.02"},
        Rule{"/robot/odometry_noise", "[0.02, -0.5]",
             "robot.odometry_noise[1]: must be >= 0, got -0.5"},
        Rule{"/robot/start", "[2, 2]",
             "robot.start: must be free floor up to the scanner height, got [2, 2], inside "
             "boxes[0] at z = 0.01"},
        Rule{"/robot/start", "[2, 0]",
             "robot.start: must be free floor up to the scanner height, got [2, 0], inside "
             "walls[0] at z = 0.01"},
        Rule{"/robot/speed", "1",
             "robot.speed: unknown key (expected one of: start, start_yaw_deg, radius, "
             "odometry_noise; keys "
             "starting with _ are comments)"},
        // Scanner.
        Rule{"/scanner", "3", "scanner: must be an object, got 3"},
        Rule{"/scanner/height", "0", "scanner.height: must be > 0, got 0"},
        Rule{"/scanner/azimuth_step_deg", "-0.2",
             "scanner.azimuth_step_deg: must be > 0, got -0.2"},
        Rule{"/scanner/elevation_step_deg", "0", "scanner.elevation_step_deg: must be > 0, got 0"},
        Rule{"/scanner/elevation_min_deg", "-91",
             "scanner.elevation_min_deg: must be in [-90, 90], got -91"},
        Rule{"/scanner/elevation_max_deg", "95",
             "scanner.elevation_max_deg: must be in [-90, 90], got 95"},
        Rule{"/scanner/elevation_max_deg", "-70",
             "scanner.elevation_max_deg: must be > elevation_min_deg (-60), got -70"},
        Rule{"/scanner/min_range", "0", "scanner.min_range: must be > 0, got 0"},
        Rule{"/scanner/max_range", "-1", "scanner.max_range: must be > 0, got -1"},
        Rule{"/scanner/max_range", "0.5", "scanner.max_range: must be > min_range (0.6), got 0.5"},
        Rule{"/scanner/range_noise_sigma", "-0.001",
             "scanner.range_noise_sigma: must be >= 0, got -0.001"},
        Rule{"/scanner/fov", "360",
             "scanner.fov: unknown key (expected one of: height, azimuth_step_deg, "
             "elevation_step_deg, "
             "elevation_min_deg, elevation_max_deg, min_range, max_range, range_noise_sigma; keys "
             "starting with _ "
             "are comments)"},
        // Survey area.
        Rule{"/survey_area", "[[0, 0], [1, 1]]", "survey_area: must have at least 3 points, got 2"},
        Rule{"/survey_area", "[[0, 0], [3, 3], [3, 0], [0, 3]]",
             "survey_area: must be a simple polygon, edges 0 and 2 touch or cross"},
        Rule{"/survey_area", "[[3, 3], [4, 3], [4, 4]]",
             "robot.start: must lie inside survey_area, got [1, 2]"}),
    rule_name);

TEST(SceneFormat, TheFormatPagesExampleMessage) {
  json scene = json::parse(std::ifstream(kScenes + "/lab.scene.json"));
  scene["walls"][3]["openings"] =
      json::parse(R"([{"kind": "door", "start": 1, "width": -0.9, "height": 2}])");
  try {
    parse_scene_json(scene.dump(), "lab.scene.json", kScenes);
    FAIL() << "accepted a negative width";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "lab.scene.json: walls[3].openings[0].width: must be > 0, got -0.9");
  }
}

TEST(SceneFormat, CommentKeysAreIgnoredAtEveryLevel) {
  json scene = base_scene();
  scene["_note"] = "top";
  scene["walls"][0]["_"] = "wall";
  scene["walls"][0]["openings"][0]["_why"] = json::object();
  scene["robot"]["_"] = 1;
  scene["scanner"]["_"] = 1;
  EXPECT_EQ(error_of(scene), "(no error)");
}

TEST(SceneFormat, RootMustBeAnObject) {
  EXPECT_EQ(error_of_text("[1, 2]"), "t.scene.json: (top level): must be an object, got [1,2]");
}

TEST(SceneFormat, MalformedJsonGivesLineAndColumn) {
  const std::string msg =
      error_of_text("{\n  \"format\": \"semioctree-scene\",\n  \"version\": 1,,\n}");
  EXPECT_EQ(msg.rfind("t.scene.json: invalid JSON at line 3, column 16: syntax error", 0), 0u)
      << msg;
}

TEST(SceneFormat, MissingFileIsAClearError) {
  try {
    load_scene_json("/nonexistent/room.scene.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/room.scene.json: cannot open: No such file or directory");
  }
}

TEST(SceneFormat, UnreadableMeshNamesTheMeshAndTheScene) {
  const fs::path dir = scratch() / "semioctree_test_scene_mesh";
  fs::create_directories(dir);
  std::ofstream(dir / "broken.ply")
      << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n";
  json scene = base_scene();
  scene["meshes"] = json::parse(R"([{"file": "broken.ply"}])");
  const std::string msg = error_of(scene, dir.string());
  EXPECT_EQ(msg.rfind("t.scene.json: meshes[0].file: cannot read the mesh: " +
                          (dir / "broken.ply").string() + ": ",
                      0),
            0u)
      << msg;
  scene["meshes"] = json::parse(R"([{"file": "missing.obj"}])");
  EXPECT_EQ(error_of(scene, dir.string()), "t.scene.json: meshes[0].file: cannot read the mesh: " +
                                               (dir / "missing.obj").string() + ": no such file");
  fs::remove_all(dir);
}

TEST(SceneFormat, DefaultsOfTheFormat) {
  const Scene s = parse_scene_json(R"({
    "format": "semioctree-scene", "version": 1, "name": "d",
    "walls": [{"from": [0, 0], "to": [4, 0],
               "openings": [{"kind": "door", "start": 0.5, "width": 0.9, "height": 2.0},
                            {"kind": "window", "start": 2, "width": 1, "height": 1}]}],
    "boxes": [{"center": [2, 2, 0.4], "size": [1, 0.5, 0.8]}],
    "meshes": [{"file": "meshes/chair.obj"}],
    "robot": {"start": [1, 1]}
  })",
                                   "d.scene.json", kScenes);
  const Wall& w = s.walls.at(0);
  EXPECT_DOUBLE_EQ(w.thickness, 0.2);
  EXPECT_DOUBLE_EQ(w.z0, 0.0);
  EXPECT_DOUBLE_EQ(w.z1, 3.0);
  EXPECT_DOUBLE_EQ(w.openings.at(0).sill, 0.0);
  EXPECT_DOUBLE_EQ(w.openings.at(1).sill, 0.9);
  EXPECT_DOUBLE_EQ(s.boxes.at(0).yaw_deg, 0.0);
  EXPECT_EQ(s.boxes.at(0).name, "");
  EXPECT_EQ(s.meshes.at(0).position, Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(s.meshes.at(0).yaw_deg, 0.0);
  EXPECT_DOUBLE_EQ(s.meshes.at(0).scale, 1.0);
  EXPECT_DOUBLE_EQ(s.robot.start_yaw_deg, 0.0);
  EXPECT_DOUBLE_EQ(s.robot.radius, 0.5);
  EXPECT_DOUBLE_EQ(s.robot.odometry_sigma_xy, 0.02);
  EXPECT_DOUBLE_EQ(s.robot.odometry_sigma_yaw_deg, 0.5);
  const ScannerConfig& c = s.scanner;
  EXPECT_DOUBLE_EQ(c.height, 1.5);
  EXPECT_DOUBLE_EQ(c.azimuth_step_deg, 0.2);
  EXPECT_DOUBLE_EQ(c.elevation_step_deg, 0.2);
  EXPECT_DOUBLE_EQ(c.elevation_min_deg, -60);
  EXPECT_DOUBLE_EQ(c.elevation_max_deg, 90);
  EXPECT_DOUBLE_EQ(c.min_range, 0.6);
  EXPECT_DOUBLE_EQ(c.max_range, 60);
  EXPECT_DOUBLE_EQ(c.range_noise_sigma, 0.002);
  EXPECT_FALSE(s.survey_area.has_value());
  EXPECT_TRUE(s.slabs.empty());
  EXPECT_TRUE(s.cylinders.empty());
}

TEST(SceneFormat, EveryKeyIsRead) {
  const Scene s = parse_scene_json(R"({
    "format": "semioctree-scene", "version": 1, "name": "all", "description": "every key",
    "walls": [{"from": [-0.5, 0], "to": [5, 0], "thickness": 0.3, "z0": -0.1, "z1": 2.7,
               "openings": [{"kind": "window", "start": 1, "width": 1.2, "sill": 1.1, "height": 0.8}]}],
    "slabs": [{"polygon": [[0, 0], [5, 0], [5, 5]], "z0": 2.7, "z1": 2.9}],
    "boxes": [{"center": [2, 2, 0.4], "size": [1, 0.5, 0.8], "yaw_deg": 30, "name": "crate"}],
    "cylinders": [{"center": [3, 3], "radius": 0.2, "z0": 0.1, "z1": 1, "name": "bin"}],
    "meshes": [{"file": "meshes/waste_bin.ply", "position": [4, 1, 0], "yaw_deg": 45, "scale": 2}],
    "robot": {"start": [1, 2], "start_yaw_deg": 90, "radius": 0.3, "odometry_noise": [0.01, 0.2]},
    "scanner": {"height": 1.2, "azimuth_step_deg": 0.5, "elevation_step_deg": 0.4, "elevation_min_deg": -45,
                "elevation_max_deg": 80, "min_range": 0.3, "max_range": 30, "range_noise_sigma": 0.001},
    "survey_area": [[0.5, 0.5], [4.5, 0.5], [4.5, 4.5], [0.5, 4.5]]
  })",
                                   "all.scene.json", kScenes);
  // Values differ from the defaults (wall from, cylinder z0), so a key that is
  // not read shows.
  EXPECT_EQ(s.name, "all");
  EXPECT_EQ(s.description, "every key");
  ASSERT_EQ(s.walls.size(), 1u);
  EXPECT_EQ(s.walls[0].from, Eigen::Vector2d(-0.5, 0));
  EXPECT_EQ(s.walls[0].to, Eigen::Vector2d(5, 0));
  EXPECT_DOUBLE_EQ(s.walls[0].thickness, 0.3);
  EXPECT_DOUBLE_EQ(s.walls[0].z0, -0.1);
  EXPECT_DOUBLE_EQ(s.walls[0].z1, 2.7);
  ASSERT_EQ(s.walls[0].openings.size(), 1u);
  EXPECT_EQ(s.walls[0].openings[0].kind, OpeningKind::window);
  EXPECT_DOUBLE_EQ(s.walls[0].openings[0].start, 1);
  EXPECT_DOUBLE_EQ(s.walls[0].openings[0].width, 1.2);
  EXPECT_DOUBLE_EQ(s.walls[0].openings[0].sill, 1.1);
  EXPECT_DOUBLE_EQ(s.walls[0].openings[0].height, 0.8);
  ASSERT_EQ(s.slabs.size(), 1u);
  ASSERT_EQ(s.slabs[0].polygon.size(), 3u);
  EXPECT_EQ(s.slabs[0].polygon[0], Eigen::Vector2d(0, 0));
  EXPECT_EQ(s.slabs[0].polygon[1], Eigen::Vector2d(5, 0));
  EXPECT_EQ(s.slabs[0].polygon[2], Eigen::Vector2d(5, 5));
  EXPECT_DOUBLE_EQ(s.slabs[0].z0, 2.7);
  EXPECT_DOUBLE_EQ(s.slabs[0].z1, 2.9);
  ASSERT_EQ(s.boxes.size(), 1u);
  EXPECT_EQ(s.boxes[0].center, Eigen::Vector3d(2, 2, 0.4));
  EXPECT_EQ(s.boxes[0].size, Eigen::Vector3d(1, 0.5, 0.8));
  EXPECT_EQ(s.boxes[0].name, "crate");
  EXPECT_DOUBLE_EQ(s.boxes[0].yaw_deg, 30);
  ASSERT_EQ(s.cylinders.size(), 1u);
  EXPECT_EQ(s.cylinders[0].center, Eigen::Vector2d(3, 3));
  EXPECT_DOUBLE_EQ(s.cylinders[0].radius, 0.2);
  EXPECT_DOUBLE_EQ(s.cylinders[0].z0, 0.1);
  EXPECT_DOUBLE_EQ(s.cylinders[0].z1, 1);
  EXPECT_EQ(s.cylinders[0].name, "bin");
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].file, "meshes/waste_bin.ply");
  EXPECT_DOUBLE_EQ(s.meshes[0].scale, 2);
  EXPECT_DOUBLE_EQ(s.meshes[0].yaw_deg, 45);
  EXPECT_EQ(s.meshes[0].position, Eigen::Vector3d(4, 1, 0));
  EXPECT_EQ(s.meshes[0].mesh.triangles.size(), 28u);
  EXPECT_EQ(s.robot.start, Eigen::Vector2d(1, 2));
  EXPECT_DOUBLE_EQ(s.robot.start_yaw_deg, 90);
  EXPECT_DOUBLE_EQ(s.robot.radius, 0.3);
  EXPECT_DOUBLE_EQ(s.robot.odometry_sigma_xy, 0.01);
  EXPECT_DOUBLE_EQ(s.robot.odometry_sigma_yaw_deg, 0.2);
  EXPECT_DOUBLE_EQ(s.scanner.height, 1.2);
  EXPECT_DOUBLE_EQ(s.scanner.azimuth_step_deg, 0.5);
  EXPECT_DOUBLE_EQ(s.scanner.elevation_step_deg, 0.4);
  EXPECT_DOUBLE_EQ(s.scanner.elevation_min_deg, -45);
  EXPECT_DOUBLE_EQ(s.scanner.elevation_max_deg, 80);
  EXPECT_DOUBLE_EQ(s.scanner.min_range, 0.3);
  EXPECT_DOUBLE_EQ(s.scanner.max_range, 30);
  EXPECT_DOUBLE_EQ(s.scanner.range_noise_sigma, 0.001);
  ASSERT_TRUE(s.survey_area.has_value());
  ASSERT_EQ(s.survey_area->size(), 4u);
  EXPECT_EQ((*s.survey_area)[0], Eigen::Vector2d(0.5, 0.5));
  EXPECT_EQ((*s.survey_area)[1], Eigen::Vector2d(4.5, 0.5));
  EXPECT_EQ((*s.survey_area)[2], Eigen::Vector2d(4.5, 4.5));
  EXPECT_EQ((*s.survey_area)[3], Eigen::Vector2d(0.5, 4.5));
}

TEST(SceneFiles, ShippedScenesLoad) {
  const Scene lab = load_scene_json(kScenes + "/lab.scene.json");
  EXPECT_EQ(lab.name, "lab");
  int doors = 0, windows = 0;
  for (const Wall& w : lab.walls)
    for (const Opening& o : w.openings) (o.kind == OpeningKind::door ? doors : windows)++;
  EXPECT_EQ(doors, 3);
  EXPECT_EQ(windows, 1);
  EXPECT_FALSE(lab.cylinders.empty());
  EXPECT_FALSE(lab.meshes.empty());

  const Scene box = load_scene_json(kScenes + "/box-room.scene.json");
  EXPECT_TRUE(box.boxes.empty() && box.cylinders.empty() && box.meshes.empty());
  for (const Wall& w : box.walls) EXPECT_TRUE(w.openings.empty());

  const Scene odw = load_scene_json(kScenes + "/one-door-window.scene.json");
  doors = windows = 0;
  for (const Wall& w : odw.walls)
    for (const Opening& o : w.openings) (o.kind == OpeningKind::door ? doors : windows)++;
  EXPECT_EQ(doors, 1);
  EXPECT_EQ(windows, 1);
  EXPECT_EQ(odw.boxes.size(), 1u);

  // The open office has no ceiling: its one slab is the floor.
  const Scene office = load_scene_json(kScenes + "/open-office.scene.json");
  EXPECT_EQ(office.name, "open-office");
  ASSERT_EQ(office.slabs.size(), 1u);
  EXPECT_DOUBLE_EQ(office.slabs[0].z1, 0.0);
  EXPECT_FALSE(office.boxes.empty());
}

TEST(SceneFiles, LoadSceneDispatchesOnTheExtension) {
  EXPECT_EQ(load_scene(kScenes + "/box-room.scene.json").name, "box-room");
  const Scene chair = load_scene(kScenes + "/meshes/chair.obj", Eigen::Vector2d(2, 3));
  ASSERT_EQ(chair.meshes.size(), 1u);
  EXPECT_EQ(chair.meshes[0].mesh.triangles.size(), 72u);  // 6 boxes x 6 quads x 2
  EXPECT_EQ(chair.robot.start, Eigen::Vector2d(2, 3));
  try {
    load_scene("room.stl");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(),
                 "room.stl: unknown scene type \".stl\", expected a .scene.json file, an .obj or "
                 ".ply mesh, or an "
                 "OctoMap .bt file");
  }
}

TEST(MeshFiles, BinaryPlyIsRead) {
  const fs::path file = scratch() / "semioctree_test_tetra.ply";
  {
    std::ofstream out(file, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty "
           "float y\n"
           "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    out.write(reinterpret_cast<const char*>(v), sizeof v);
    const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (const auto& face : f) {
      const unsigned char n = 3;
      out.write(reinterpret_cast<const char*>(&n), 1);
      out.write(reinterpret_cast<const char*>(face), sizeof face);
    }
  }
  const TriangleMesh m = read_mesh_file(file.string());
  EXPECT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.triangles[3], Eigen::Vector3i(1, 2, 3));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1));
  fs::remove(file);
}

TEST(MeshFiles, ObjQuadsAreSplitIntoTriangles) {
  const TriangleMesh m = read_mesh_file(kScenes + "/meshes/chair.obj");
  EXPECT_EQ(m.vertices.size(), 48u);
  EXPECT_EQ(m.triangles.size(), 72u);
  EXPECT_NEAR(m.max_corner().z(), 0.97, 1e-6);
  EXPECT_NEAR(m.min_corner().z(), 0.0, 1e-6);
}

class BrokenMeshTest : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(BrokenMeshTest, IsRejectedWithTheFileName) {
  const fs::path file = scratch() / ("semioctree_test_broken" + GetParam().first);
  std::ofstream(file, std::ios::binary) << GetParam().second;
  try {
    read_mesh_file(file.string());
    FAIL() << "accepted " << GetParam().second;
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ": ", 0), 0u) << e.what();
  }
  fs::remove(file);
}

INSTANTIATE_TEST_SUITE_P(
    MeshFiles, BrokenMeshTest,
    ::testing::Values(
        std::make_pair(".obj", "this is not a mesh\n"), std::make_pair(".obj", "v 0 0\nf 1 2 3\n"),
        std::make_pair(".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
        std::make_pair(".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n"),
        std::make_pair(".obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"), std::make_pair(".obj", ""),
        std::make_pair(".ply", "this is not a mesh\n"),
        std::make_pair(".ply", "ply\nformat ascii 1.0\nelement vertex 3\n"),
        std::make_pair(
            ".ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
        std::make_pair(".ply",
                       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list uchar int vertex_indices\nend_header\n\x01\x02"),
        std::make_pair(
            ".ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n")));

TEST(MeshFiles, MissingFileIsRejected) {
  try {
    read_mesh_file("/nonexistent/chair.obj");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/chair.obj: no such file");
  }
}

TEST(OctomapScenes, OccupiedVoxelsBecomeAClosedSurface) {
  const fs::path file = scratch() / "semioctree_test_two_voxels.bt";
  {
    octomap::OcTree tree(0.1);
    tree.updateNode(octomap::point3d(0.05f, 0.05f, 0.05f), true);
    tree.updateNode(octomap::point3d(0.15f, 0.05f, 0.05f), true);   // next to the first along x
    tree.updateNode(octomap::point3d(0.55f, 0.55f, 0.55f), false);  // free space is left out
    ASSERT_TRUE(tree.writeBinary(file.string()));
  }
  const Scene s = scene_from_octomap_file(file.string(), Eigen::Vector2d(1, 1));
  ASSERT_EQ(s.meshes.size(), 1u);
  const TriangleMesh& m = s.meshes[0].mesh;
  // Two cubes sharing a face: 10 outer faces, 2 triangles each, 12 distinct corners.
  EXPECT_EQ(m.triangles.size(), 20u);
  EXPECT_EQ(m.vertices.size(), 12u);
  EXPECT_NEAR(m.min_corner().x(), 0.0, 1e-9);
  EXPECT_NEAR(m.max_corner().x(), 0.2, 1e-9);
  EXPECT_NEAR(m.max_corner().z(), 0.1, 1e-9);
  // Every edge is shared by exactly two triangles: the surface is closed.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  for (const auto& [edge, count] : edges) EXPECT_EQ(count, 2);
  fs::remove(file);
}

TEST(OctomapScenes, ABadFileIsRejected) {
  const fs::path file = scratch() / "semioctree_test_bad.bt";
  std::ofstream(file) << "# Octomap OcTree binary file\nnonsense\n";
  EXPECT_THROW(scene_from_octomap_file(file.string(), Eigen::Vector2d(0, 0)), SceneError);
  fs::remove(file);
}

// --- the command line ------------------------------------------------------------------

TEST(SceneInfoCommand, SummarisesTheLab) {
  const CliRun r = run_cli("scene-info " + kScenes + "/lab.scene.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scene:       lab"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("openings:    4"), std::string::npos);
  EXPECT_NE(r.out.find("rooms:       4 enclosed by walls"), std::string::npos);
  EXPECT_NE(r.out.find("room 0: 88.40 m²  (robot start)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("triangles:"), std::string::npos);
  EXPECT_NE(r.out.find("extent:"), std::string::npos);
}

TEST(SceneInfoCommand, MissingFileExitsNonZero) {
  const CliRun r = run_cli("scene-info /nonexistent/x.scene.json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(
      r.err,
      "semioctree: error: /nonexistent/x.scene.json: cannot open: No such file or directory\n");
}

TEST(SceneInfoCommand, InvalidScenesExitNonZeroWithTheMessage) {
  const fs::path dir = scratch() / "semioctree_test_cli_scenes";
  fs::create_directories(dir);
  json unknown = base_scene();
  unknown["walls"][0]["thikness"] = 0.1;
  std::ofstream(dir / "unknown.scene.json") << unknown.dump();
  std::ofstream(dir / "malformed.scene.json") << "{\"format\": \"semioctree-scene\",";
  json bad_mesh = base_scene();
  bad_mesh["meshes"] = json::parse(R"([{"file": "broken.obj"}])");
  std::ofstream(dir / "bad-mesh.scene.json") << bad_mesh.dump();
  std::ofstream(dir / "broken.obj") << "v 0 0\nf 1 2 3\n";

  CliRun r = run_cli("scene-info " + (dir / "unknown.scene.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("semioctree: error: " + (dir / "unknown.scene.json").string() +
                            ": walls[0].thikness: unknown key",
                        0),
            0u)
      << r.err;
  r = run_cli("scene-info " + (dir / "malformed.scene.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("semioctree: error: " + (dir / "malformed.scene.json").string() +
                            ": invalid JSON at line 1",
                        0),
            0u)
      << r.err;
  r = run_cli("scene-info " + (dir / "bad-mesh.scene.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("semioctree: error: " + (dir / "bad-mesh.scene.json").string() +
                            ": meshes[0].file: cannot read the mesh: ",
                        0),
            0u)
      << r.err;
  fs::remove_all(dir);
}

// The points of a binary PCD as `semioctree scan` writes it (x y z first, 4-byte
// floats), read without PCL, and its VIEWPOINT line.
struct PcdPoints {
  std::vector<Eigen::Vector3d> points;
  std::string viewpoint;
};

PcdPoints read_binary_pcd(const std::string& bytes) {
  PcdPoints out;
  std::istringstream in(bytes);
  std::size_t record = 0, count = 0;
  std::vector<std::string> fields;
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "FIELDS") {
      for (std::string f; words >> f;) fields.push_back(f);
    } else if (key == "SIZE") {
      for (std::size_t n; words >> n;) record += n;
    } else if (key == "POINTS") {
      words >> count;
    } else if (key == "VIEWPOINT") {
      out.viewpoint = line.substr(std::strlen("VIEWPOINT "));
    } else if (key == "DATA") {
      if (line != "DATA binary") throw std::runtime_error("not binary: " + line);
      break;
    }
  }
  if (fields.size() < 3 || fields[0] != "x" || fields[1] != "y" || fields[2] != "z")
    throw std::runtime_error("fields do not start with x y z");
  const std::size_t start = static_cast<std::size_t>(in.tellg());
  // PCL's writer may pad the file after the data.
  if (bytes.size() < start + count * record)
    throw std::runtime_error("data shorter than POINTS x the record size");
  for (std::size_t i = 0; i < count; ++i) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + start + i * record, sizeof xyz);
    out.points.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  return out;
}

TEST(SceneInfoCommand, MeshAndOctomapFilesAreScenesToo) {
  CliRun r = run_cli("scene-info " + kScenes + "/meshes/chair.obj --at 2,2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("triangles:   72\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("start (2.00, 2.00)"), std::string::npos) << r.out;

  const fs::path bt = scratch() / "wall.bt";
  // The wall's voxels (leaf keys) and its box [lo, hi], from the tree written.
  std::set<std::array<int, 3>> voxels;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  {
    octomap::OcTree tree(0.1);
    for (float y = -1.0f; y < 1.0f; y += 0.1f)
      for (float z = 0.05f; z < 2.0f; z += 0.1f)
        tree.updateNode(octomap::point3d(3.05f, y + 0.05f, z), true);
    ASSERT_TRUE(tree.writeBinary(bt.string()));
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      ASSERT_EQ(it.getDepth(), tree.getTreeDepth()) << "one voxel thick: nothing to prune";
      const octomap::OcTreeKey k = it.getKey();
      voxels.insert({int(k[0]), int(k[1]), int(k[2])});
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], tree.keyToCoord(k[a]) - 0.05);
        hi[a] = std::max(hi[a], tree.keyToCoord(k[a]) + 0.05);
      }
    }
  }
  ASSERT_GE(voxels.size(), 400u);
  // Its closed surface: each voxel face without a voxel behind it, as 2 triangles.
  std::size_t faces = 0;
  for (const auto& v : voxels)
    for (int a = 0; a < 3; ++a)
      for (int step : {-1, 1}) {
        auto n = v;
        n[a] += step;
        faces += voxels.count(n) == 0;
      }
  r = run_cli("scene-info " + bt.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("triangles:   " + std::to_string(2 * faces) + "\n"), std::string::npos)
      << r.out;
  std::ostringstream extent;
  extent << std::fixed << std::setprecision(2) << "extent:      (" << lo.x() << ", " << lo.y()
         << ", " << lo.z() << ") to (" << hi.x() << ", " << hi.y() << ", " << hi.z() << ")";
  EXPECT_NE(r.out.find(extent.str()), std::string::npos) << extent.str() << "\n" << r.out;

  const fs::path out = scratch() / "wall.pcd";
  r = run_cli("scan --scene " + bt.string() +
              " --at 0,0 --azimuth-step 1 --elevation-step 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out));
  const PcdPoints pcd = read_binary_pcd(semioctree::testing::slurp(out.string()));
  EXPECT_NE(
      r.out.find("wrote " + out.string() + ": " + std::to_string(pcd.points.size()) + " points"),
      std::string::npos)
      << r.out;
  // The scanner stands at (0, 0) facing +x at the default height; nothing but
  // the wall's face x = lo.x, the one facing it, is in view (no floor).
  const ScannerConfig config;
  const Eigen::Vector3d origin(0, 0, config.height);
  std::ostringstream viewpoint;
  viewpoint << "0 0 " << config.height << " 1 0 0 0";  // position, then quaternion w x y z
  EXPECT_EQ(pcd.viewpoint, viewpoint.str());
  const double tol = 7 * config.range_noise_sigma + 1e-4;
  for (const Eigen::Vector3d& p : pcd.points) {
    const Eigen::Vector3d w = origin + p;
    ASSERT_NEAR(w.x(), lo.x(), tol) << w.transpose();
    ASSERT_GE(w.y(), lo.y() - tol) << w.transpose();
    ASSERT_LE(w.y(), hi.y() + tol) << w.transpose();
    ASSERT_GE(w.z(), lo.z() - tol) << w.transpose();
    ASSERT_LE(w.z(), hi.z() + tol) << w.transpose();
  }
  // One point per ray of the 1° grid that meets the face: at least those that
  // meet it 1 mm inside its edges, at most those that meet it within 1 mm outside.
  std::size_t inside = 0, near = 0;
  const double el_min = config.elevation_min_deg, el_max = config.elevation_max_deg;
  for (double el = el_min; el <= el_max + 1e-9; el += 1.0)
    for (int az = 0; az < 360; ++az) {
      const double e = el * M_PI / 180, a = az * M_PI / 180;
      const Eigen::Vector3d d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      if (d.x() <= 1e-9) continue;
      const Eigen::Vector3d hit = origin + d * ((lo.x() - origin.x()) / d.x());
      auto within = [&](double m) {
        return hit.y() >= lo.y() + m && hit.y() <= hi.y() - m && hit.z() >= lo.z() + m &&
               hit.z() <= hi.z() - m;
      };
      inside += within(1e-3);
      near += within(-1e-3);
    }
  EXPECT_GT(inside, 100u);
  EXPECT_GE(pcd.points.size(), inside);
  EXPECT_LE(pcd.points.size(), near);
}

TEST(SceneInfoCommand, HelpExplainsTheOptions) {
  const CliRun r = run_cli("scene-info --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--at"), std::string::npos);
  EXPECT_NE(r.out.find("--cell"), std::string::npos);
}

}  // namespace
