// map-nbv on maps made the way OctoMap users make them (tests/support/octomap_user_map.h):
// sparse scans from a few positions along a path, insertPointCloud into an OcTree, the
// floor not at z = 0. Candidates must be found, the NBV must stand on free floor in the
// room with the robot's clearance, and the doors and windows must match the scene's.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim/scene_generator.h"
#include "semioctree/sim_platform/opening_match.h"
#include "support/cli_run.h"
#include "support/octomap_user_map.h"

namespace semioctree {
namespace {

using testing::CliRun;
using testing::run_cli;
using testing::scratch;

std::vector<DetectedOpening> read_openings(const std::string& path) {
  std::ifstream in(path);
  const auto j = nlohmann::json::parse(in);
  std::vector<DetectedOpening> out;
  for (const auto& o : j["openings"]) {
    DetectedOpening d;
    d.kind = o["kind"] == "door" ? OpeningKind::kDoor : OpeningKind::kWindow;
    for (int k = 0; k < 4; ++k)
      d.corners[std::size_t(k)] =
          Eigen::Vector3d(o["corners"][k][0], o["corners"][k][1], o["corners"][k][2]);
    const Eigen::Vector3d along = d.corners[1] - d.corners[0];
    d.wall_normal = Eigen::Vector3d(-along.y(), along.x(), 0.0).normalized();
    d.width = o["width"], d.height = o["height"], d.sill = o["sill"];
    out.push_back(d);
  }
  return out;
}

struct MapCase {
  std::string scene;  // a generated room "room-<seed>", or a built-in scene's file name
  double resolution;
  int positions = 3;  // scan positions along the path the map was made from
  // The NBV lies in the room the map was made in. A map of a corridor holds its offices
  // too, seen through their doors, and nothing tells map-nbv that only the corridor is
  // to be surveyed: there the NBV may lie in any room the robot reaches.
  bool nbv_in_start_room = true;
  // The sanitizer run (SEMIOCTREE_SANITIZED, several times slower) takes the rooms only:
  // the corridor goes through the same code, on 8 scans of 38 m, for minutes.
  bool under_sanitizers = true;
};
// How ctest and gtest name a case in their output ("room-1 at 0.08 m").
void PrintTo(const MapCase& c, std::ostream* os) {
  *os << c.scene << " at " << c.resolution << " m";
}

sim::Scene scene_of(const MapCase& c) {
  if (c.scene.rfind("room-", 0) == 0)
    return sim::generate_scene(std::stoull(c.scene.substr(5)), sim::GeneratedKind::room);
  return sim::load_scene_json(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/" + c.scene);
}

class MapNbvOnUserMaps : public ::testing::TestWithParam<MapCase> {};

TEST_P(MapNbvOnUserMaps, FindsCandidatesAndTheOpenings) {
  const MapCase c = GetParam();
  if (!c.under_sanitizers && std::getenv("SEMIOCTREE_SANITIZED"))
    GTEST_SKIP() << "skipped when sanitized: the rooms take the same code";
  const sim::Scene scene = scene_of(c);
  const sim::GroundTruth truth(scene);
  testing::OctomapUserMapOptions uo;
  uo.resolution = c.resolution;
  uo.positions = c.positions;
  const testing::OctomapUserMap map = testing::make_octomap_user_map(scene, truth, uo);
  const std::string name = c.scene + "-" + std::to_string(int(std::lround(1000 * c.resolution)));
  const std::string bt = (scratch() / (name + ".bt")).string();
  ASSERT_TRUE(map.tree->writeBinary(bt));

  // The user's robot and scanner: its radius and the scanner's limits, as the scene has them.
  const sim::ScannerConfig& sc = scene.scanner;
  std::string args = "map-nbv --map " + bt + " --out " + (scratch() / name).string() +
                     " --robot-radius " + std::to_string(scene.robot.radius) + " --min-range " +
                     std::to_string(sc.min_range) + " --max-range " + std::to_string(sc.max_range) +
                     " --elevation-min " + std::to_string(sc.elevation_min_deg) +
                     " --elevation-max " + std::to_string(sc.elevation_max_deg);
  char xyz[96];
  for (const Eigen::Vector3d& s : map.scanners) {
    std::snprintf(xyz, sizeof xyz, " --scanner %.3f,%.3f,%.3f", s.x(), s.y(), s.z());
    args += xyz;
  }
  const CliRun r = run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << r.all();
  std::ifstream in(scratch() / name / "nbv.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_GT(j["candidates"].get<int>(), 0) << r.all();
  ASSERT_FALSE(j["nbv"].is_null()) << r.all();
  // The NBV, in the map's frame: at the scanner's height above the shifted floor, on
  // floor the robot can reach in its room (the scene's own floor plan says so).
  const Eigen::Vector3d nbv(j["nbv"]["x"], j["nbv"]["y"], j["nbv"]["z"]);
  EXPECT_NEAR(nbv.z() - uo.floor_z, scene.scanner.height, 0.5 * c.resolution) << r.all();
  const sim::FloorPlan plan = truth.floor_plan(0.05);
  EXPECT_TRUE(plan.reachable_near(nbv.head<2>())) << nbv.transpose() << "\n" << r.all();
  if (c.nbv_in_start_room) {
    EXPECT_EQ(plan.room_at(nbv.head<2>()), plan.start_room) << nbv.transpose();
  }

  const auto found = read_openings((scratch() / name / "openings.json").string());
  const auto truths = sim_platform::openings_of_room(truth, plan, plan.start_room);
  const Eigen::Isometry3d world_to_map(Eigen::Translation3d(0.0, 0.0, uo.floor_z));
  const auto m = sim_platform::match_openings(found, truths, world_to_map);
  // Precision against every opening of the scene: a window of an office seen through its
  // door is a window, though not one of the room the map was made in.
  const auto m_all = sim_platform::match_openings(found, truth.openings(), world_to_map);
  std::printf(
      "%s: %d candidates, nbv (%.2f, %.2f, %.2f), openings %zu found / %zu true, P %.2f R %.2f\n",
      name.c_str(), j["candidates"].get<int>(), nbv.x(), nbv.y(), nbv.z(), found.size(),
      truths.size(), m_all.precision, m.recall);
  for (std::size_t i = 0; i < found.size(); ++i)
    std::printf("  found %s %.2f x %.2f sill %.2f at (%.2f, %.2f) IoU %.2f\n",
                to_string(found[i].kind), found[i].width, found[i].height, found[i].sill,
                found[i].corners[0].x(), found[i].corners[0].y(), m.detection_iou[i]);
  for (std::size_t i = 0; i < truths.size(); ++i)
    std::printf("  true %s %.2f x %.2f at (%.2f, %.2f) IoU %.2f\n",
                truths[i].kind == sim::OpeningKind::door ? "door" : "window", truths[i].width,
                truths[i].height, truths[i].corners[0].x(), truths[i].corners[0].y(),
                m.truth_iou[i]);
  EXPECT_GE(m_all.precision, 0.9) << r.all();
  EXPECT_GE(m.recall, 0.9) << r.all();
}

INSTANTIATE_TEST_SUITE_P(Maps, MapNbvOnUserMaps,
                         ::testing::Values(MapCase{"room-1", 0.08}, MapCase{"room-3", 0.08},
                                           MapCase{"room-4", 0.1}, MapCase{"room-8", 0.08},
                                           // A 38 m corridor with 16 office doors, scanned
                                           // every 5 m or so as a robot drives along it.
                                           MapCase{"office-corridor.scene.json", 0.08, 8, false,
                                                   false}),
                         [](const auto& info) {
                           std::string n =
                               info.param.scene.substr(0, info.param.scene.find('.')) + "_" +
                               std::to_string(int(std::lround(1000 * info.param.resolution)));
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace semioctree
