// Generated scenes (sim/include/semioctree/sim/scene_generator.h): deterministic per seed,
// read back by the scene reader, within the documented ranges, openings clear and
// looking onto outside space, the start free, the standable floor reachable; and the
// `make-scene` command.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim/scene_generator.h"
#include "support/cli_run.h"
#include "support/sanitized.h"

namespace semioctree::sim {
namespace {

namespace fs = std::filesystem;
using semioctree::testing::CliRun;
using semioctree::testing::run_cli;
using semioctree::testing::scratch;
using semioctree::testing::slurp;

constexpr std::uint64_t kSeeds = 60;

TEST(SceneGenerator, SameSeedSameTextOtherSeedOtherText) {
  for (GeneratedKind k : {GeneratedKind::any, GeneratedKind::room, GeneratedKind::l_shape,
                          GeneratedKind::hall, GeneratedKind::floor}) {
    EXPECT_EQ(generate_scene_json(7, k), generate_scene_json(7, k)) << to_string(k);
    EXPECT_NE(generate_scene_json(7, k), generate_scene_json(8, k)) << to_string(k);
  }
  // `any` draws a kind and then makes that kind's scene.
  for (std::uint64_t seed = 1; seed <= 10; ++seed)
    EXPECT_EQ(generate_scene_json(seed),
              generate_scene_json(seed, resolve_generated_kind(seed, GeneratedKind::any)));
}

TEST(SceneGenerator, KindNames) {
  for (const std::string& name : generated_kind_names())
    EXPECT_EQ(to_string(generated_kind_from_string(name)), name);
  EXPECT_THROW(generated_kind_from_string("castle"), std::invalid_argument);
}

// The walls of the surveyed room: those with a survey-area corner near their centre line.
bool bounds_room(const Wall& w, const Scene& s) {
  for (const Eigen::Vector2d& p : *s.survey_area) {
    const Eigen::Vector2d d = w.direction();
    const double along = (p - w.from).dot(d);
    const double across = std::abs((p - w.from).dot(w.normal()));
    if (along > -1e-6 && along < w.length() + 1e-6 && across < 0.5 * w.thickness + 1e-3)
      return true;
  }
  return false;
}

TEST(SceneGenerator, ScenesKeepTheRanges) {
  std::set<std::string> kinds;
  int without_ceiling = 0, with_mezzanine = 0, doors = 0, windows = 0;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scene s = generate_scene(seed);  // throws if the reader rejects it
    kinds.insert(s.name.substr(4, s.name.rfind('-') - 4));
    ASSERT_TRUE(s.survey_area);
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (const auto& p : *s.survey_area) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const Eigen::Vector2d size = hi - lo;
    EXPECT_GE(size.minCoeff(), 4.0);
    EXPECT_LE(size.maxCoeff(), 20.0);
    const double height = s.walls.front().z1;
    EXPECT_GE(height, 2.4);
    EXPECT_LE(height, 6.0);
    bool ceiling = false;
    for (const Slab& slab : s.slabs) {
      ceiling = ceiling || std::abs(slab.z0 - height) < 1e-9;
      with_mezzanine += slab.z0 > 0.0 && slab.z1 < height;
    }
    without_ceiling += !ceiling;
    int room_doors = 0, room_windows = 0;
    for (const Wall& w : s.walls) {
      if (!bounds_room(w, s)) {
        EXPECT_TRUE(w.openings.empty());
        continue;
      }
      for (const Opening& o : w.openings) {
        if (o.kind == OpeningKind::door) {
          ++room_doors;
          EXPECT_GE(o.width, 0.8);
          EXPECT_LE(o.width, 1.8);
          EXPECT_GE(o.height, 2.0);
          EXPECT_LE(o.height, 2.4);
          EXPECT_EQ(o.sill, 0.0);
        } else {
          ++room_windows;
          EXPECT_GE(o.width, 0.6);
          EXPECT_LE(o.width, 2.5);
          EXPECT_GE(o.sill, 0.5);
          EXPECT_LE(o.sill, 1.2);
        }
        EXPECT_LE(o.sill + o.height, height - 0.29);  // a lintel above every opening
      }
    }
    EXPECT_LE(room_doors, 4);
    EXPECT_LE(room_windows, 4);
    doors += room_doors, windows += room_windows;
    EXPECT_GE(s.robot.radius, 0.25);
    EXPECT_LE(s.robot.radius, 0.8);
    EXPECT_GE(s.scanner.height, 1.0);
    EXPECT_LE(s.scanner.height, 2.0);
    EXPECT_GE(s.scanner.elevation_min_deg, -90.0);
    EXPECT_LE(s.scanner.elevation_min_deg, -30.0);
    EXPECT_GE(s.scanner.elevation_max_deg, 30.0);
    EXPECT_LE(s.scanner.elevation_max_deg, 90.0);
    EXPECT_GE(s.scanner.azimuth_step_deg, 0.1);
    EXPECT_LE(s.scanner.azimuth_step_deg, 0.15);
  }
  // The seeds vary what they should.
  EXPECT_EQ(kinds, (std::set<std::string>{"room", "l-shape", "hall"}));
  EXPECT_GT(without_ceiling, 0);
  EXPECT_LT(without_ceiling, int(kSeeds));
  EXPECT_GT(with_mezzanine, 0);
  EXPECT_GT(doors, int(kSeeds));
  EXPECT_GT(windows, int(kSeeds));
}

// The robot, 5 cm wider all round, stands at p: GroundTruth::standing_free's sparser rays
// can miss a thin leg, and the floor plan's 5 cm cells can be off by a few centimetres.
bool robot_fits(const GroundTruth& truth, const Eigen::Vector2d& p) {
  if (!truth.standing_free(p)) return false;
  const Scene& s = truth.scene();
  const double r = s.robot.radius + 0.05;
  for (double z : {0.02, 0.3, 0.6, 0.9, 1.2, s.scanner.height})
    for (int i = 0; i < 128; ++i) {
      const double a = 2 * M_PI * i / 128;
      const Eigen::Vector3d c(p.x(), p.y(), z);
      if (!truth.segment_free(c, c + r * Eigen::Vector3d(std::cos(a), std::sin(a), 0)))
        return false;
    }
  return true;
}

// Every opening is a clear hole with floor beyond it (outside space, or the next room of a
// floor), the start is free, and every point of a 0.5 m grid over the survey area where
// the robot can stand is reachable from the start (the passages between obstacles, and a
// floor's doors, are wide enough for it). Returns the floor plan.
FloorPlan expect_valid_layout(const Scene& s) {
  const GroundTruth truth(s);
  EXPECT_TRUE(truth.standing_free(s.robot.start));
  for (const OpeningRect& o : truth.openings()) {
    const Eigen::Vector3d c = 0.25 * (o.corners[0] + o.corners[1] + o.corners[2] + o.corners[3]);
    const Eigen::Vector3d n = o.normal;  // left of from → to
    // Through the hole, 0.5 m to the left and 1 m to the right, with floor there.
    EXPECT_TRUE(truth.segment_free(c + 0.5 * n, c - 1.0 * n)) << to_string(o.kind);
    const Eigen::Vector3d beyond = c - 1.0 * n;
    EXPECT_FALSE(truth.segment_free(beyond, beyond - Eigen::Vector3d(0, 0, c.z() + 0.1)))
        << "no floor beyond the " << to_string(o.kind);
  }
  FloorPlan plan = truth.floor_plan(0.05);
  std::size_t standable = 0, unreachable = 0;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& p : *s.survey_area) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (double x = lo.x() + 0.25; x < hi.x(); x += 0.5)
    for (double y = lo.y() + 0.25; y < hi.y(); y += 0.5) {
      const Eigen::Vector2d p(x, y);
      if (!point_in_polygon(*s.survey_area, p) || !robot_fits(truth, p)) continue;
      ++standable;
      if (!plan.reachable_near(p)) {
        ++unreachable;
        ADD_FAILURE() << "the robot fits at (" << x << ", " << y << ") but cannot get there";
      }
    }
  EXPECT_GT(standable, 0u);
  EXPECT_EQ(unreachable, 0u);
  return plan;
}

TEST(SceneGenerator, OpeningsClearStartFreeFloorReachable) {
  for (std::uint64_t seed = 1; seed <= kSeeds; seed += 3) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_valid_layout(generate_scene(seed));
  }
}

// The rooms of a floor's plan inside its survey area (the outside ring excluded).
std::set<int> rooms_inside(const FloorPlan& plan) {
  std::set<int> rooms;
  for (std::size_t i = 0; i < plan.room.size(); ++i)
    if (plan.survey[i] && plan.room[i] >= 0) rooms.insert(plan.room[i]);
  return rooms;
}

// Floors: as many rooms as drawn (3-10) or asked, each at least 3 m across, every one
// reachable through doors the robot passes, and the layout rules of single rooms.
TEST(SceneGenerator, FloorsHaveTheirRoomsJoinedByDoorsTheRobotPasses) {
  std::set<std::size_t> counts;
  int corridors = 0;
  // Sanitized (10× slower), every third: they still vary the count and the layout.
  const std::uint64_t step = testing::sanitized() ? 3 : 1;
  int floors = 0;
  for (std::uint64_t seed = 1; seed <= 12; seed += step) {
    ++floors;
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scene s = generate_scene(seed, GeneratedKind::floor);
    corridors += s.description.find("corridor") != std::string::npos;
    const FloorPlan plan = expect_valid_layout(s);
    const std::set<int> rooms = rooms_inside(plan);
    EXPECT_GE(rooms.size(), 3u);
    EXPECT_LE(rooms.size(), 10u);
    counts.insert(rooms.size());
    for (int r : rooms) EXPECT_GE(plan.room_area[std::size_t(r)], 9.0) << "room " << r;
    EXPECT_TRUE(plan.reachable_near(s.robot.start));
    for (const Wall& w : s.walls)
      for (const Opening& o : w.openings)
        if (o.kind == OpeningKind::door) {
          EXPECT_GE(o.width, 2 * s.robot.radius + 0.3 - 1e-3);
        }
  }
  EXPECT_GE(counts.size(), std::size_t(floors / 3));  // the seeds vary the count
  EXPECT_GT(corridors, 0);                            // and the layout
  EXPECT_LT(corridors, floors);
  for (int asked : {kMinFloorRooms, 5, 16}) {
    if (testing::sanitized() && asked == 16) continue;
    SCOPED_TRACE(std::to_string(asked) + " rooms asked");
    const Scene s = generate_scene(3, GeneratedKind::floor, {asked});
    EXPECT_EQ(rooms_inside(expect_valid_layout(s)).size(), std::size_t(asked));
  }
}

TEST(SceneGenerator, AFloorAskedForTheRoomsItsSeedDrawsIsTheSameButForItsName) {
  const Scene drawn = generate_scene(4, GeneratedKind::floor);
  const int count = int(rooms_inside(GroundTruth(drawn).floor_plan(0.05)).size());
  std::string asked = generate_scene_json(4, GeneratedKind::floor, {count});
  const std::string suffix = "-" + std::to_string(count) + "-rooms";
  const std::size_t at = asked.find(suffix);
  ASSERT_NE(at, std::string::npos);
  asked.erase(at, suffix.size());
  EXPECT_EQ(asked, generate_scene_json(4, GeneratedKind::floor));
  EXPECT_THROW(generate_scene_json(4, GeneratedKind::floor, {kMaxFloorRooms + 1}),
               std::invalid_argument);
  EXPECT_THROW(generate_scene_json(4, GeneratedKind::floor, {1}), std::invalid_argument);
  EXPECT_THROW(generate_scene_json(4, GeneratedKind::room, {5}), std::invalid_argument);
}

// A floor asked for by size: that rectangle inside the outer walls (the survey area), one
// room per 20 m², cut from it without a corridor, and the rules of every floor.
TEST(SceneGenerator, ASizedFloorIsThatRectangleCutIntoRooms) {
  EXPECT_EQ(floor_size_from_string("30x20"), std::make_pair(30.0, 20.0));
  EXPECT_EQ(floor_size_from_string("12.5X6"), std::make_pair(12.5, 6.0));
  for (const char* bad : {"", "30", "30x", "30x20x2", "3x20", "30x200", "ax20", "30x20 "})
    EXPECT_THROW(floor_size_from_string(bad), std::invalid_argument) << bad;
  const Scene s = generate_scene(5, GeneratedKind::floor, {0, 20, 15});
  EXPECT_EQ(s.name, "gen-floor-5-20x15m");
  EXPECT_EQ(s.description.find("corridor"), std::string::npos);
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  ASSERT_TRUE(s.survey_area.has_value());
  for (const Eigen::Vector2d& p : *s.survey_area)
    x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y()), x1 = std::max(x1, p.x()),
    y1 = std::max(y1, p.y());
  EXPECT_NEAR(x1 - x0, 20.0, 1e-9);
  EXPECT_NEAR(y1 - y0, 15.0, 1e-9);
  const FloorPlan plan = expect_valid_layout(s);
  EXPECT_EQ(rooms_inside(plan).size(), 15u);  // 300 m² / 20
  if (!testing::sanitized()) {
    const Scene seven = generate_scene(5, GeneratedKind::floor, {7, 20, 15});
    EXPECT_EQ(rooms_inside(expect_valid_layout(seven)).size(), 7u);
  }
  EXPECT_THROW(generate_scene_json(5, GeneratedKind::floor, {0, 30, 0}), std::invalid_argument);
  EXPECT_THROW(generate_scene_json(5, GeneratedKind::floor, {60, 10, 8}), std::invalid_argument);
}

TEST(MakeSceneCommand, WritesASceneThatSceneInfoAccepts) {
  const std::string out = (scratch() / "gen-12.scene.json").string();
  CliRun r = run_cli("make-scene --seed 12 --kind l-shape --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.all();
  EXPECT_EQ(slurp(out), generate_scene_json(12, GeneratedKind::l_shape));
  r = run_cli("scene-info " + out);
  EXPECT_EQ(r.exit_code, 0) << r.all();
  EXPECT_NE(r.out.find("gen-l-shape-12"), std::string::npos);
  // An existing file is not replaced without --force.
  r = run_cli("make-scene --seed 13 --out " + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("exists"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), generate_scene_json(12, GeneratedKind::l_shape));
  r = run_cli("make-scene --seed 13 --force --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.all();
  EXPECT_EQ(slurp(out), generate_scene_json(13));
}

TEST(MakeSceneCommand, BadOptionsExitNonZero) {
  const std::string out = (scratch() / "bad.scene.json").string();
  EXPECT_NE(run_cli("make-scene --seed 1 --kind castle --out " + out).exit_code, 0);
  EXPECT_NE(run_cli("make-scene --seed -1 --out " + out).exit_code, 0);
  EXPECT_NE(run_cli("make-scene --out " + out).exit_code, 0);  // no seed
  EXPECT_NE(run_cli("make-scene --seed 1").exit_code, 0);      // no output
  EXPECT_NE(run_cli("make-scene --seed 1 --out " + scratch().string()).exit_code, 0);
  const CliRun rooms = run_cli("make-scene --seed 1 --kind room --rooms 5 --out " + out);
  EXPECT_EQ(rooms.exit_code, 1);
  EXPECT_NE(rooms.err.find("--kind floor"), std::string::npos) << rooms.err;
  EXPECT_NE(run_cli("make-scene --seed 1 --kind floor --rooms 201 --out " + out).exit_code, 0);
  for (const char* size : {"60", "60x", "x45", "5x45", "60x121", "60x45m", "sixtyx45"}) {
    const CliRun r =
        run_cli(std::string("make-scene --seed 1 --kind floor --size ") + size + " --out " + out);
    EXPECT_EQ(r.exit_code, 1) << size;
    EXPECT_NE(r.err.find("--size"), std::string::npos) << size << ": " << r.err;
  }
  const CliRun crowded =
      run_cli("make-scene --seed 1 --kind floor --size 10x8 --rooms 12 --out " + out);
  EXPECT_EQ(crowded.exit_code, 1);
  EXPECT_NE(crowded.err.find("ask for fewer"), std::string::npos) << crowded.err;
  EXPECT_EQ(run_cli("make-scene --seed 1 --kind hall --size 30x20 --out " + out).exit_code, 1);
  EXPECT_FALSE(fs::exists(out));
  const CliRun help = run_cli("make-scene --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* option : {"--seed", "--kind", "--rooms", "--size", "--out", "--force"})
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
}

}  // namespace
}  // namespace semioctree::sim
