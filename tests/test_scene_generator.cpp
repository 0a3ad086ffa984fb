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

namespace semioctree::sim {
namespace {

namespace fs = std::filesystem;
using semioctree::testing::CliRun;
using semioctree::testing::run_cli;
using semioctree::testing::scratch;
using semioctree::testing::slurp;

constexpr std::uint64_t kSeeds = 60;

TEST(SceneGenerator, SameSeedSameTextOtherSeedOtherText) {
  for (GeneratedKind k :
       {GeneratedKind::any, GeneratedKind::room, GeneratedKind::l_shape, GeneratedKind::hall}) {
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

// Every opening is a clear hole onto outside space, the start is free, and every point
// of a 0.5 m grid over the survey area where the robot can stand is reachable from the
// start (the passages between obstacles are wide enough for it).
TEST(SceneGenerator, OpeningsClearStartFreeFloorReachable) {
  for (std::uint64_t seed = 1; seed <= kSeeds; seed += 3) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scene s = generate_scene(seed);
    const GroundTruth truth(s);
    EXPECT_TRUE(truth.standing_free(s.robot.start));
    for (const OpeningRect& o : truth.openings()) {
      const Eigen::Vector3d c = 0.25 * (o.corners[0] + o.corners[1] + o.corners[2] + o.corners[3]);
      const Eigen::Vector3d n = o.normal;  // into the room (left of from → to)
      // Through the hole, 0.5 m either side, and 1 m on outside (the floor beyond).
      EXPECT_TRUE(truth.segment_free(c + 0.5 * n, c - 1.0 * n)) << to_string(o.kind);
      const Eigen::Vector3d outside = c - 1.0 * n;
      EXPECT_FALSE(truth.segment_free(outside, outside - Eigen::Vector3d(0, 0, c.z() + 0.1)))
          << "no floor outside the " << to_string(o.kind);
    }
    const FloorPlan plan = truth.floor_plan(0.05);
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
  }
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
  EXPECT_FALSE(fs::exists(out));
  const CliRun help = run_cli("make-scene --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* option : {"--seed", "--kind", "--out", "--force"})
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
}

}  // namespace
}  // namespace semioctree::sim
