// Survey coverage: the reference of visible surface samples (what it leaves out and why),
// the measure against a scan, and the per-scene cache.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>

#include "semioctree/sim/coverage.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"

namespace {

using namespace semioctree::sim;
namespace fs = std::filesystem;

const std::string kScenes = SEMIOCTREE_SOURCE_DIR "/sim/scenes";

Scene load(const std::string& name) {
  return load_scene_json(kScenes + "/" + name + ".scene.json");
}

bool sanitized() {
  return std::getenv("SEMIOCTREE_SANITIZED") != nullptr;
}

// A directory of this test process's own, removed at exit.
const fs::path& scratch() {
  static const struct Dir {
    fs::path path =
        fs::temp_directory_path() / ("semioctree_test_coverage_" + std::to_string(::getpid()));
    Dir() { fs::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } dir;
  return dir.path;
}

// Membership of every sample in the reference.
std::vector<bool> visible_flags(const CoverageReference& ref) {
  std::vector<bool> in(ref.sample_count, false);
  for (std::uint32_t i : ref.visible) in[i] = true;
  return in;
}

// World-frame points of one full scan from the robot's start.
std::vector<Eigen::Vector3d> scan_from_start(const GroundTruth& truth, std::uint64_t seed = 1) {
  const Scene& s = truth.scene();
  ScanOptions o;
  o.seed = seed;
  const Scan sc = scan(truth.ray_caster(), s.scanner,
                       {s.robot.start.x(), s.robot.start.y(), s.robot.start_yaw_deg}, o);
  std::vector<Eigen::Vector3d> out;
  out.reserve(sc.points.size());
  const Eigen::Isometry3d to_world = sc.sensor_to_world();
  for (const auto& p : sc.points) out.push_back(to_world * p.cast<double>());
  return out;
}

bool in_rect(const Eigen::Vector3d& p, double x0, double x1, double y0, double y1,
             double eps = 1e-6) {
  return p.x() >= x0 - eps && p.x() <= x1 + eps && p.y() >= y0 - eps && p.y() <= y1 + eps;
}

// one-door-window with a facade 2.4 m in front of the window (boxes[1]) and a shed wall
// 1.1 m beyond the door (boxes[2]): surfaces outside the room that the grid positions
// see through the openings and only through them.
Scene with_neighbours() {
  Scene scene = load("one-door-window");
  Box facade;  // x 0.15 .. 5.15, y -2.8 .. -2.4, z 0 .. 3: its north face looks at the window
  facade.center = {2.65, -2.6, 1.5};
  facade.size = {5.0, 0.4, 3.0};
  facade.name = "facade";
  Box shed;  // x 7.3 .. 7.7, y -0.15 .. 2.85, z 0 .. 2.4: its west face looks at the door
  shed.center = {7.5, 1.35, 1.2};
  shed.size = {0.4, 3.0, 2.4};
  shed.name = "shed";
  scene.boxes.push_back(facade);
  scene.boxes.push_back(shed);
  return scene;
}

// True if the sample lies on a jamb, the sill or the lintel of an opening: inside the
// opening's box (its rectangle across the wall's thickness), facing across the hole.
bool on_opening_surface(const GroundTruth& truth, const std::vector<OpeningRect>& openings,
                        const SurfaceSample& s) {
  if (s.part.kind != PartKind::wall) return false;
  constexpr double eps = 1e-6;
  for (const OpeningRect& r : openings) {
    if (r.wall != s.part.index || std::abs(s.normal.dot(r.normal)) > 0.5) continue;
    const Eigen::Vector3d q = s.position - r.corners[0];
    const Eigen::Vector3d along = (r.corners[1] - r.corners[0]).normalized();
    const double u = q.dot(along), z = q.z();
    const double half = truth.scene().walls[static_cast<std::size_t>(r.wall)].thickness / 2;
    if (u > -eps && u < r.width + eps && z > -eps && z < r.height + eps &&
        std::abs(q.dot(r.normal)) < half + eps)
      return true;
  }
  return false;
}

// The scanner's own rule, openings or not: some position has a line of sight.
bool seen_by_scanner(const GroundTruth& truth, const SurfaceSample& s,
                     const std::vector<Eigen::Vector3d>& positions) {
  for (const auto& c : positions)
    if (sample_in_line_of_sight(truth, s, c)) return true;
  return false;
}

// --- the reference ------------------------------------------------------------------

TEST(CoverageReference, BoxRoomHoldsTheInnerWallFacesAndNotTheOuterOnes) {
  const GroundTruth truth(load("box-room"));
  const auto samples = truth.surface_samples(0.02);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  std::cout << "box-room reference: " << ref.visible.size() << " of " << ref.sample_count
            << " samples from " << ref.positions.size() << " positions, " << ref.segment_queries
            << " segment queries, " << ref.seconds << " s\n";
  ASSERT_EQ(ref.sample_count, samples.size());
  ASSERT_EQ(ref.points.size(), ref.visible.size());
  // Interior 6 x 4 m, robot radius 0.5: positions every 0.5 m from the start (2, 1.5),
  // centres within [0.5, 5.5] x [0.5, 3.5], at scanner height.
  ASSERT_GE(ref.positions.size(), 20u);
  for (const auto& c : ref.positions) {
    EXPECT_TRUE(in_rect(c, 0.5, 5.5, 0.5, 3.5)) << c.transpose();
    EXPECT_DOUBLE_EQ(c.z(), truth.scene().scanner.height);
    EXPECT_NEAR(std::remainder(c.x() - 2.0, 0.5), 0.0, 1e-9);
    EXPECT_NEAR(std::remainder(c.y() - 1.5, 0.5), 0.0, 1e-9);
  }
  const std::vector<bool> in = visible_flags(ref);
  std::size_t inner = 0, inner_seen = 0, outer = 0, outer_seen = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (in_rect(samples[i].position, 0, 6, 0, 4)) {
      ++inner;
      inner_seen += in[i];
    } else {
      ++outer;
      outer_seen += in[i];
      EXPECT_FALSE(in[i]) << "outer face sample " << samples[i].position.transpose();
    }
  }
  EXPECT_GT(outer, 100000u);  // 2 x (6.4 + 4.4) x 2.8 m² at 2 cm
  EXPECT_EQ(outer_seen, 0u);
  // Every inner point lies within the scanner's limits of some grid position.
  EXPECT_GE(inner_seen, inner * 999 / 1000) << inner_seen << " of " << inner;
  EXPECT_EQ(ref.visible.size(), inner_seen + outer_seen);
}

// On a scene with surfaces seen through the openings, so that the reference's shortcuts
// (samples hidden from every position, segments into a wall) meet the plain rule.
TEST(CoverageReference, AgreesWithTheVisibilityRuleSampleBySample) {
  const GroundTruth truth(with_neighbours());
  const auto samples = truth.surface_samples(0.05);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.05, 2);
  const CoverageReference one_thread = compute_coverage_reference(truth, 0.5, 0.05, 1);
  EXPECT_EQ(ref.visible, one_thread.visible);  // independent of the number of threads
  const std::vector<bool> in = visible_flags(ref);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < samples.size(); i += 17, ++checked) {
    bool any = false;
    for (const auto& c : ref.positions) any = any || sample_visible_from(truth, samples[i], c);
    EXPECT_EQ(any, in[i]) << samples[i].position.transpose();
  }
  EXPECT_GT(checked, 500u);
}

TEST(CoverageReference, ASegmentPassesThroughAnOpeningWhenItCrossesBothFacesOfTheHole) {
  const Scene scene = load("one-door-window");
  // The window: south wall y -0.2 .. 0, x 1.9 .. 3.4, z 0.9 .. 2.1. The door: east wall
  // x 6.0 .. 6.2, y 0.9 .. 1.8, z 0 .. 2.05.
  const Eigen::Vector3d c(2.65, 2.0, 1.5);
  auto through = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const bool ab = segment_through_opening(scene, a, b);
    EXPECT_EQ(ab, segment_through_opening(scene, b, a)) << a.transpose() << " | " << b.transpose();
    return ab;
  };
  EXPECT_TRUE(through(c, {2.65, -3.0, 1.5}));  // straight out of the window
  EXPECT_TRUE(through(c, {1.0, -3.0, 1.0}));   // slanting: x 1.99 at y = 0, 1.92 at y = -0.2
  EXPECT_TRUE(through({5.0, 1.35, 1.0}, {8.0, 1.35, 1.0}));  // out of the door
  EXPECT_TRUE(through({5.0, 1.0, 1.8}, {9.0, 1.7, 2.0}));
  // Through the wall beside, above or below the hole: not through the opening.
  EXPECT_FALSE(through(c, {2.65, -3.0, 4.0}));                // y = 0 at z 2.5
  EXPECT_FALSE(through(c, {-1.0, -3.0, 1.5}));                // y = 0 at x 1.19
  EXPECT_FALSE(through(c, {2.65, -3.0, -0.5}));               // y = 0 at z 0.7
  EXPECT_FALSE(through({5.0, 1.35, 1.0}, {8.0, 1.35, 4.0}));  // in at z 2.0, out at 2.2: lintel
  // Ends inside the hole: on the west jamb (x 1.9, normal +x), the sill, the lintel; or
  // short of the wall.
  EXPECT_FALSE(through(c, {1.905, -0.1, 1.5}));
  EXPECT_FALSE(through(c, {1.905, -0.195, 1.0}));
  EXPECT_FALSE(through(c, {2.65, -0.15, 0.905}));
  EXPECT_FALSE(through(c, {2.65, -0.199, 2.095}));
  EXPECT_FALSE(through({5.0, 1.35, 1.0}, {6.1, 0.905, 1.0}));  // door jamb
  EXPECT_FALSE(through(c, {2.65, 0.5, 1.5}));
  // Ends on a face plane of the wall cross one face only.
  EXPECT_FALSE(through(c, {2.65, -0.2, 1.5}));
  EXPECT_FALSE(through({2.65, 0.0, 1.5}, {2.65, -3.0, 1.5}));
  // Both ends on the same side, the segment parallel to the wall inside the hole.
  EXPECT_FALSE(through({2.0, -0.1, 1.5}, {3.0, -0.1, 1.5}));
  EXPECT_FALSE(through(c, {5.0, 3.0, 1.0}));
}

TEST(CoverageReference, RuleHonoursRangeElevationAndFacing) {
  Scene scene = load("box-room");
  const GroundTruth truth(scene);
  // A sample on the south wall's inner face (normal +y) at (3, 0, z).
  SurfaceSample s;
  s.normal = Eigen::Vector3d::UnitY();
  s.position = {3.0, 0.0, 1.0};
  EXPECT_TRUE(sample_visible_from(truth, s, {3.0, 2.0, 1.5}));
  // Behind the face: not facing.
  SurfaceSample back = s;
  back.normal = -back.normal;
  EXPECT_FALSE(sample_visible_from(truth, back, {3.0, 2.0, 1.5}));
  // Closer than min_range (0.6 m).
  EXPECT_FALSE(sample_visible_from(truth, s, {3.0, 0.5, 1.2}));
  // Below elevation_min_deg (-60°): the wall foot 0.5 m away, 1.5 m down (-71.6°).
  s.position.z() = 0.01;
  EXPECT_FALSE(sample_visible_from(truth, s, {3.0, 0.5, 1.5}));
  EXPECT_TRUE(sample_visible_from(truth, s, {3.0, 1.0, 1.5}));  // -56°
  // Beyond max_range.
  scene.scanner.max_range = 1.5;
  const GroundTruth short_range(scene);
  EXPECT_FALSE(sample_visible_from(short_range, s, {3.0, 2.0, 1.5}));
}

// The box room with a closed closet in its north-east corner (no door) and a cabinet
// standing 2 cm off the west wall: the closet's inside and the gap behind the cabinet are
// pockets no scan position sees.
TEST(CoverageReference, LeavesOutHiddenPockets) {
  Scene scene = load("box-room");
  Wall a;  // x 4.75 .. 4.85, from y 2.75 into the north wall
  a.from = {4.8, 2.75};
  a.to = {4.8, 4.05};
  a.thickness = 0.1;
  a.z1 = 2.8;
  Wall b;  // y 2.75 .. 2.85, from x 4.75 into the east wall
  b.from = {4.75, 2.8};
  b.to = {6.05, 2.8};
  b.thickness = 0.1;
  b.z1 = 2.8;
  scene.walls.push_back(a);
  scene.walls.push_back(b);
  Box cabinet;  // x 0.02 .. 0.62, y 1.5 .. 2.5, z 0 .. 2
  cabinet.center = {0.32, 2.0, 1.0};
  cabinet.size = {0.6, 1.0, 2.0};
  cabinet.name = "cabinet";
  scene.boxes.push_back(cabinet);
  const GroundTruth truth(scene);
  const auto samples = truth.surface_samples(0.02);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<bool> in = visible_flags(ref);

  std::size_t closet = 0, gap = 0, front = 0, front_seen = 0, room_walls = 0, room_walls_seen = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Eigen::Vector3d& p = samples[i].position;
    if (in_rect(p, 4.85, 6.0, 2.85, 4.0)) {  // inside the closet
      ++closet;
      EXPECT_FALSE(in[i]) << "closet " << p.transpose();
    }
    // West wall behind the cabinet and the cabinet's back, away from the gap's ends.
    if (p.x() > -1e-6 && p.x() < 0.02 + 1e-6 && p.y() > 1.65 && p.y() < 2.35 && p.z() < 1.85) {
      ++gap;
      EXPECT_FALSE(in[i]) << "gap " << p.transpose();
    }
    if (std::abs(p.x() - 0.62) < 1e-6 && samples[i].normal.x() > 0.5) {  // cabinet front
      ++front;
      front_seen += in[i];
    }
    // The room's own walls where nothing stands in front of them.
    if (samples[i].part.kind == PartKind::wall && samples[i].part.index < 4 &&
        in_rect(p, 0.0, 4.7, 0.0, 4.0) && !in_rect(p, 0.0, 0.7, 1.4, 2.6)) {
      ++room_walls;
      room_walls_seen += in[i];
    }
  }
  EXPECT_GT(closet, 10000u);  // 2 x (1.15 + 1.15) x 2.8 m² at 2 cm
  EXPECT_GT(gap, 4000u);      // 2 x 0.7 x 1.85 m² at 2 cm
  EXPECT_GT(front, 4000u);
  EXPECT_EQ(front_seen, front);
  EXPECT_GE(room_walls_seen, room_walls * 999 / 1000);
}

// A survey area the robot fits in but cannot drive into: a counter (1 m high, too high
// to drive over, low enough to see over) across the whole room. The reference is what a
// survey could see, so it holds no position east of the counter nor what only those
// positions see: the counter's east face. Before the positions had to be reachable, the
// lab's reference held 3 such positions (two between bench-3 and the south wall, one
// between the cabinets) and 1.2 % more samples.
TEST(CoverageReference, LeavesOutPositionsTheRobotCannotDriveTo) {
  Scene scene = load("box-room");
  Box counter;  // x 3.9 .. 4.1, the room's whole width, z 0 .. 1
  counter.center = {4.0, 2.0, 0.5};
  counter.size = {0.2, 4.0, 1.0};
  counter.name = "counter";
  scene.boxes.push_back(counter);
  scene.survey_area = std::vector<Eigen::Vector2d>{{0, 0}, {6, 0}, {6, 4}, {0, 4}};
  const GroundTruth truth(scene);

  const FloorPlan plan = truth.floor_plan(0.05);
  EXPECT_TRUE(plan.in_survey_area({5.0, 2.0}));
  EXPECT_TRUE(truth.standing_free({5.0, 2.0}));
  EXPECT_FALSE(plan.reachable_near({5.0, 2.0}));
  EXPECT_TRUE(plan.reachable_near(scene.robot.start));
  EXPECT_TRUE(plan.reachable_near({3.3, 3.4}));  // 0.6 m from the counter and the wall

  const std::vector<Eigen::Vector3d> grid = coverage_grid_positions(truth, 0.5);
  ASSERT_FALSE(grid.empty());
  for (const auto& p : grid) EXPECT_LT(p.x(), 3.9 - 0.5) << p.transpose();
  EXPECT_EQ(grid.size(), 6u * 7u);  // x 0.5 .. 3.0, y 0.5 .. 3.5 (start 2.0, 1.5)

  const auto samples = truth.surface_samples(0.02);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<bool> in = visible_flags(ref);
  std::size_t east_face = 0, west_face = 0, west_seen = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].part.kind != PartKind::box) continue;
    if (samples[i].normal.x() > 0.5) {
      ++east_face;
      EXPECT_FALSE(in[i]) << samples[i].position.transpose();
    } else if (samples[i].normal.x() < -0.5) {
      ++west_face;
      west_seen += in[i];
    }
  }
  EXPECT_GT(east_face, 9000u);  // 4 x 1 m² at 2 cm
  EXPECT_EQ(west_seen, west_face);
}

TEST(CoverageReference, OneDoorWindowSeesTheSillButNoOuterFace) {
  const Scene scene = load("one-door-window");
  const GroundTruth truth(scene);
  const auto samples = truth.surface_samples(0.02);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  std::cout << "one-door-window reference: " << ref.visible.size() << " of " << ref.sample_count
            << " samples from " << ref.positions.size() << " positions, " << ref.seconds << " s\n";
  // The door (0.9 m) is narrower than the robot (1 m): every position is in the room.
  ASSERT_GT(ref.positions.size(), 10u);
  for (const auto& c : ref.positions) EXPECT_TRUE(in_rect(c, 0.5, 5.5, 0.5, 3.5)) << c.transpose();
  const std::vector<bool> in = visible_flags(ref);
  std::size_t outer = 0, sill = 0, sill_seen = 0, table_top = 0, table_top_seen = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const SurfaceSample& s = samples[i];
    const Eigen::Vector3d& p = s.position;
    // Outer faces of the exterior walls: 0.2 m outside the interior, normal pointing away.
    const Eigen::Vector3d from_centre(p.x() - 3.0, p.y() - 2.0, 0.0);
    if (!in_rect(p, -0.01, 6.01, -0.01, 4.01) && s.normal.dot(from_centre) > 0 &&
        std::abs(s.normal.z()) < 0.5 &&
        (std::abs(p.x() + 0.2) < 1e-6 || std::abs(p.x() - 6.2) < 1e-6 ||
         std::abs(p.y() + 0.2) < 1e-6 || std::abs(p.y() - 4.2) < 1e-6)) {
      ++outer;
      EXPECT_FALSE(in[i]) << "outer face " << p.transpose();
    }
    // The window's sill: z = 0.9, across the south wall's thickness (y -0.2 .. 0).
    if (s.part.kind == PartKind::wall && s.part.index == 0 && s.normal.z() > 0.5) {
      ++sill;
      sill_seen += in[i];
    }
    if (s.part.kind == PartKind::box && s.normal.z() > 0.5) {
      ++table_top;
      table_top_seen += in[i];
    }
  }
  EXPECT_GT(outer, 100000u);
  EXPECT_GT(sill, 500u);  // 1.5 x 0.2 m² at 2 cm
  EXPECT_GE(sill_seen, sill * 99 / 100) << sill_seen << " of " << sill;
  EXPECT_GT(table_top, 2500u);
  EXPECT_EQ(table_top_seen, table_top);
}

TEST(CoverageReference, LeavesOutWhatIsSeenOnlyThroughAnOpening) {
  const GroundTruth truth(with_neighbours());
  const auto samples = truth.surface_samples(0.05);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.05);
  const std::vector<bool> in = visible_flags(ref);
  const std::vector<OpeningRect> openings = truth.openings();
  std::size_t outside = 0, outside_scanned = 0, outside_in = 0, opening = 0, opening_scanned = 0,
              opening_in = 0, scanned = 0, mismatches = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const SurfaceSample& s = samples[i];
    const bool is_outside = s.part.kind == PartKind::box && s.part.index >= 1;
    const bool is_opening = on_opening_surface(truth, openings, s);
    const bool by_scanner = seen_by_scanner(truth, s, ref.positions);
    scanned += by_scanner;
    if (is_outside) {
      ++outside;
      outside_scanned += by_scanner;
      outside_in += in[i];
      // Every line of sight to it goes through the window or the door.
      if (by_scanner) {
        for (const auto& c : ref.positions) {
          if (!sample_in_line_of_sight(truth, s, c)) continue;
          EXPECT_TRUE(segment_through_opening(truth.scene(), c,
                                              s.position + kCoverageSampleOffset * s.normal))
              << s.position.transpose() << " from " << c.transpose();
        }
      }
    }
    if (is_opening) {
      ++opening;
      opening_scanned += by_scanner;
      opening_in += in[i];
    }
    // The rule takes away exactly what lies outside the room.
    if (in[i] != (by_scanner && !is_outside)) ++mismatches;
    // Nothing beyond the openings' outer planes: the reference is the room's inner faces
    // and, within the walls' thickness (y -0.2 .. 0 and x 6.0 .. 6.2), the openings' faces.
    if (in[i] && !in_rect(s.position, 0, 6, 0, 4)) {
      EXPECT_TRUE(in_rect(s.position, -0.2, 6.2, -0.2, 4.2)) << s.position.transpose();
      EXPECT_TRUE(is_opening) << s.position.transpose();
    }
  }
  std::cout << "with neighbours (5 cm): reference " << ref.visible.size() << ", scanner's rule "
            << scanned << "; outside " << outside_scanned << " of " << outside
            << " seen through the openings; opening faces " << opening_in << " of " << opening
            << " (" << opening_scanned << " by the scanner's rule)\n";
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(outside, 20000u);  // the two boxes' 55 m² at 5 cm
  // The facade's north face through the window, the shed's west face through the door:
  // 15 + 7.2 m² at 5 cm.
  EXPECT_GT(outside_scanned, 8000u);
  EXPECT_EQ(outside_in, 0u);
  EXPECT_EQ(ref.visible.size() + outside_scanned, scanned);
  // Jambs, sill and lintel of the window and the door stay: 1.5 x 0.2 (sill and lintel),
  // 2 x 1.2 x 0.2 (window jambs), 0.9 x 0.2 + 2 x 2.05 x 0.2 m² (door) at 5 cm.
  EXPECT_GT(opening, 500u);
  EXPECT_EQ(opening_in, opening_scanned);
  EXPECT_GE(opening_in, opening * 99 / 100) << opening_in << " of " << opening;
}

// --- the measure --------------------------------------------------------------------

TEST(Coverage, CountsSamplesWithAPointWithinTheTolerance) {
  CoverageReference ref;
  for (double x : {-1.0, -0.0149, 0.0, 0.0151, 2.0}) ref.points.emplace_back(x, -0.5, 10.0);
  ref.points.emplace_back(5.0, 5.0, 5.0);
  const Coverage none = measure_coverage(ref, std::vector<Eigen::Vector3d>{});
  EXPECT_EQ(none.reference_points, 6u);
  EXPECT_EQ(none.covered, 0u);
  EXPECT_EQ(none.percent, 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Eigen::Vector3d> measured = {
      {-1.0 + 0.029, -0.5, 10.0},               // 2.9 cm from -1.0, in the next cell
      {2.0, -0.5 + 0.031, 10.0},                // 3.1 cm from 2.0
      {0.0, -0.5, 10.0},                        // 1.49, 0 and 1.51 cm from three samples
      {5.0 + 0.017, 5.0 + 0.017, 5.0 + 0.017},  // 2.94 cm from (5, 5, 5)
      {nan, -0.5, 10.0}};
  const Coverage c = measure_coverage(ref, measured);
  // Everything but 2.0 is covered.
  EXPECT_EQ(c.covered, 5u);
  EXPECT_NEAR(c.percent, 500.0 / 6.0, 1e-9);
  // At 2.85 cm, -1.0 (2.9 cm) and (5, 5, 5) (2.94 cm) drop out too.
  EXPECT_EQ(measure_coverage(ref, measured, 0.0285).covered, 3u);
  std::vector<Eigen::Vector3f> as_float;
  for (const auto& p : measured) as_float.push_back(p.cast<float>());
  EXPECT_EQ(measure_coverage(ref, as_float, 0.0285).covered, 3u);
  // The flags behind those counts, sample by sample.
  EXPECT_EQ(covered_samples(ref, as_float),
            (std::vector<bool>{true, true, true, true, false, true}));
  EXPECT_EQ(count_covered(covered_samples(ref, as_float)).covered, c.covered);
  EXPECT_EQ(covered_samples(ref, as_float, 0.0285),
            (std::vector<bool>{false, true, true, true, false, false}));
  EXPECT_EQ(measure_coverage(CoverageReference{}, measured).percent, 0.0);
}

TEST(Coverage, AFullScanOfTheEmptyBoxRoomCoversItsReference) {
  // box-room: walls, floor and ceiling only (no furniture), a convex room: one scan
  // from the start sees every inner wall face the reference holds.
  const GroundTruth truth(load("box-room"));
  ASSERT_TRUE(truth.scene().boxes.empty() && truth.scene().cylinders.empty() &&
              truth.scene().meshes.empty());
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<Eigen::Vector3d> points = scan_from_start(truth);
  ASSERT_GT(points.size(), 100000u);
  const Coverage full = measure_coverage(ref, points);
  std::cout << "box-room, one scan from the start: " << full.covered << " of "
            << full.reference_points << " = " << full.percent << " %\n";
  EXPECT_EQ(full.reference_points, ref.visible.size());
  EXPECT_GE(full.percent, 99.0);

  EXPECT_EQ(measure_coverage(ref, std::vector<Eigen::Vector3f>{}).percent, 0.0);

  // 5 cm along x: the points of the east and west walls leave their faces by 5 cm,
  // those of the north and south walls slide along them (about 60 % of the walls' area).
  std::vector<Eigen::Vector3d> shifted = points;
  for (auto& p : shifted) p.x() += 0.05;
  const Coverage along_x = measure_coverage(ref, shifted);
  EXPECT_LT(along_x.percent, full.percent - 30.0) << along_x.percent;
  // 5 cm diagonally in the xy-plane: every wall's points are 3.5 cm off its face.
  shifted = points;
  const Eigen::Vector3d diagonal = Eigen::Vector3d(1, 1, 0).normalized() * 0.05;
  for (auto& p : shifted) p += diagonal;
  const Coverage diag = measure_coverage(ref, shifted);
  std::cout << "shifted 5 cm: along x " << along_x.percent << " %, diagonally " << diag.percent
            << " %\n";
  EXPECT_LT(diag.percent, 5.0);
}

TEST(Coverage, MissedSamplesAreSplitIntoSparselySampledAndHidden) {
  // box-room with a crate east of the start: its east face looks away from the scanner.
  Scene scene = load("box-room");
  Box crate;  // x 3.7 .. 4.3, y 1.7 .. 2.3, z 0 .. 1
  crate.center = {4.0, 2.0, 0.5};
  crate.size = {0.6, 0.6, 1.0};
  crate.name = "crate";
  scene.boxes.push_back(crate);
  const GroundTruth truth(scene);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<SurfaceSample> samples = truth.surface_samples(0.02);
  const Eigen::Vector3d centre(scene.robot.start.x(), scene.robot.start.y(), scene.scanner.height);
  const std::vector<Eigen::Vector3d> points = scan_from_start(truth);
  std::vector<Eigen::Vector3f> measured;
  for (const auto& p : points) measured.push_back(p.cast<float>());
  const std::vector<bool> covered = covered_samples(ref, measured);
  const std::size_t n_covered = std::size_t(std::count(covered.begin(), covered.end(), true));

  const MissedSamples full = explain_missed_samples(truth, ref, covered, {centre}, 2);
  EXPECT_EQ(full.in_view + full.hidden, ref.visible.size() - n_covered);
  // The crate's east face, away from its edges (a point on the top or a side face can lie
  // within 3 cm of a sample near an edge): faces away from the scanner, so hidden.
  std::size_t east_face = 0;
  for (std::uint32_t i : ref.visible) {
    const SurfaceSample& s = samples[i];
    if (s.part.kind == PartKind::box && s.normal.x() > 0.99 && s.position.z() < 0.95 &&
        s.position.y() > 1.75 && s.position.y() < 2.25)
      ++east_face;
  }
  ASSERT_GT(east_face, 500u);  // 0.4 x 0.95 m at 2 cm
  ASSERT_FALSE(full.parts.empty());
  const auto crate_part =
      std::find_if(full.parts.begin(), full.parts.end(),
                   [](const MissedPart& p) { return p.label == "boxes[0] (crate)"; });
  ASSERT_NE(crate_part, full.parts.end());
  EXPECT_GE(crate_part->hidden, east_face);
  for (std::size_t k = 1; k < full.parts.size(); ++k)
    EXPECT_GE(full.parts[k - 1].in_view + full.parts[k - 1].hidden,
              full.parts[k].in_view + full.parts[k].hidden);
  std::size_t by_part = 0;
  for (const MissedPart& p : full.parts) by_part += p.in_view + p.hidden;
  EXPECT_EQ(by_part, full.in_view + full.hidden);
  // A small convex room at 0.2°: what the scan sees it samples densely enough.
  EXPECT_LT(full.in_view, full.hidden / 10) << full.in_view << " in view, " << full.hidden;

  // One point in 25 kept: the same view, sampled five times more sparsely each way.
  std::vector<Eigen::Vector3f> sparse;
  for (std::size_t i = 0; i < measured.size(); i += 25) sparse.push_back(measured[i]);
  const std::vector<bool> covered_sparse = covered_samples(ref, sparse);
  const MissedSamples thin = explain_missed_samples(truth, ref, covered_sparse, {centre}, 1);
  EXPECT_GT(thin.in_view, 10 * full.in_view + ref.visible.size() / 10);
  EXPECT_GE(thin.hidden, full.hidden);
  EXPECT_LT(thin.hidden, full.hidden + ref.visible.size() / 100);

  // Without any scan position every missed sample is hidden.
  const MissedSamples none = explain_missed_samples(truth, ref, covered, {});
  EXPECT_EQ(none.in_view, 0u);
  EXPECT_EQ(none.hidden, ref.visible.size() - n_covered);

  EXPECT_THROW(explain_missed_samples(truth, ref, std::vector<bool>(3), {centre}),
               std::invalid_argument);
  EXPECT_THROW(explain_missed_samples(GroundTruth(load("box-room")), ref, covered, {centre}),
               std::invalid_argument);
  EXPECT_EQ(part_label(scene, {PartKind::wall, 1}), "walls[1]");
  EXPECT_EQ(part_label(scene, {PartKind::box, 0}), "boxes[0] (crate)");
}

// --- the cache ----------------------------------------------------------------------

// Six samples; from the first position nothing is seen. Greedy takes A (4 new)
// then B (1 new; C too, B comes first) and covers 5; swapping A for C covers all.
TEST(CoveragePlan, GreedyThenLocalSearch) {
  auto set = [](std::initializer_list<int> members) {
    std::vector<bool> s(6, false);
    for (int i : members) s[std::size_t(i)] = true;
    return s;
  };
  const std::vector<std::vector<bool>> covered = {set({}), set({0, 1, 2, 3}), set({0, 1, 4}),
                                                  set({2, 3, 5})};
  const CoveragePlan greedy = greedy_coverage_plan(covered, 0, 3);
  EXPECT_EQ(greedy.views, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_NEAR(greedy.percent, 500.0 / 6.0, 1e-9);
  const CoveragePlan best = improve_coverage_plan(covered, greedy);
  EXPECT_EQ(best.views, (std::vector<std::size_t>{0, 3, 2}));
  EXPECT_NEAR(best.percent, 100.0, 1e-9);
  // One scan: the first position alone.
  EXPECT_NEAR(greedy_coverage_plan(covered, 1, 1).percent, 400.0 / 6.0, 1e-9);
  EXPECT_THROW(greedy_coverage_plan(covered, 4, 2), std::invalid_argument);
  EXPECT_THROW(greedy_coverage_plan({set({0}), std::vector<bool>(3)}, 0, 2), std::invalid_argument);
}

TEST(CoverageCache, RoundTripsAndIsKeyedByTheScene) {
  const fs::path dir = scratch() / "roundtrip";
  const GroundTruth truth(load("box-room"));
  const CoverageReference first = load_or_compute_coverage_reference(truth, dir.string());
  EXPECT_FALSE(first.from_cache);
  ASSERT_FALSE(first.cache_file.empty());
  EXPECT_TRUE(fs::exists(first.cache_file));
  EXPECT_EQ(fs::path(first.cache_file).parent_path(), dir);
  // Only the final file is left (the temporary was renamed).
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);

  const CoverageReference second = load_or_compute_coverage_reference(truth, dir.string());
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.cache_file, first.cache_file);
  EXPECT_EQ(second.visible, first.visible);
  EXPECT_EQ(second.positions, first.positions);
  EXPECT_EQ(second.points, first.points);
  EXPECT_EQ(second.sample_count, first.sample_count);
  EXPECT_EQ(second.segment_queries, 0u);
  EXPECT_LT(second.seconds, first.seconds);
  std::cout << "box-room reference: computed in " << first.seconds << " s, loaded in "
            << second.seconds << " s\n";
  // The computed and the cached results equal a plain computation.
  EXPECT_EQ(compute_coverage_reference(truth).visible, first.visible);

  // Same scene, same key; any parameter the reference depends on changes it.
  const std::string key = coverage_cache_key(truth);
  EXPECT_EQ(key, first.key);
  EXPECT_EQ(key, coverage_cache_key(GroundTruth(load("box-room"))));
  EXPECT_NE(key, coverage_cache_key(truth, 0.25));
  EXPECT_NE(key, coverage_cache_key(truth, 0.5, 0.05));
  Scene changed = load("box-room");
  changed.scanner.height = 1.4;
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.robot.radius = 0.4;
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.walls[2].z1 = 2.7;  // geometry
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.scanner.elevation_min_deg = -10;
  const CoverageReference other =
      load_or_compute_coverage_reference(GroundTruth(changed), dir.string());
  EXPECT_FALSE(other.from_cache);
  EXPECT_NE(other.cache_file, first.cache_file);
  // Wall feet are more than 10° below every position within the room's 7.2 m diagonal.
  EXPECT_LT(other.visible.size(), first.visible.size());
}

TEST(CoverageCache, ACorruptOrTruncatedFileIsRecomputed) {
  const fs::path dir = scratch() / "corrupt";
  const GroundTruth truth(load("one-door-window"));
  const CoverageReference good = load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05);
  ASSERT_FALSE(good.cache_file.empty());
  const auto size = fs::file_size(good.cache_file);
  ASSERT_GT(size, 100u);
  std::string bytes;
  {
    std::ifstream in(good.cache_file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_EQ(bytes.size(), size);
  auto write = [&](const std::string& data) {
    std::ofstream out(good.cache_file, std::ios::binary | std::ios::trunc);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  };
  const std::string flipped = [&] {
    std::string b = bytes;
    b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 0x10);  // one bit in the indices
    return b;
  }();
  for (const std::string& bad :
       {bytes.substr(0, bytes.size() - 4), bytes.substr(0, bytes.size() / 2), flipped,
        std::string(), std::string("not a cache file"), bytes + "x"}) {
    write(bad);
    const CoverageReference again =
        load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05);
    EXPECT_FALSE(again.from_cache) << "a damaged file of " << bad.size() << " bytes was trusted";
    EXPECT_EQ(again.visible, good.visible);
    EXPECT_EQ(again.cache_file, good.cache_file);
    // The file was rewritten whole.
    EXPECT_EQ(fs::file_size(good.cache_file), size);
    EXPECT_TRUE(load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05).from_cache);
  }
}

TEST(CoverageCache, AnUnwritableOrEmptyCacheDirectoryOnlyCostsTheCache) {
  const fs::path blocker = scratch() / "not-a-directory";
  std::ofstream(blocker) << "a file where the cache directory should be";
  const GroundTruth truth(load("box-room"));
  const CoverageReference plain = compute_coverage_reference(truth, 0.5, 0.05);
  const CoverageReference unwritable =
      load_or_compute_coverage_reference(truth, (blocker / "cache").string(), 0.5, 0.05);
  EXPECT_FALSE(unwritable.from_cache);
  EXPECT_TRUE(unwritable.cache_file.empty());
  EXPECT_EQ(unwritable.visible, plain.visible);
  const CoverageReference none = load_or_compute_coverage_reference(truth, "", 0.5, 0.05);
  EXPECT_FALSE(none.from_cache);
  EXPECT_TRUE(none.cache_file.empty());
  EXPECT_EQ(none.visible, plain.visible);
  EXPECT_EQ(none.key, plain.key);
}

TEST(CoverageCache, DefaultDirectoryFollowsXdgThenHome) {
  const char* old_xdg = std::getenv("XDG_CACHE_HOME");
  const std::string saved = old_xdg ? old_xdg : "";
  ::setenv("XDG_CACHE_HOME", "/some/cache", 1);
  EXPECT_EQ(default_cache_dir(), "/some/cache/semioctree");
  ::unsetenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  if (home && home[0]) {
    EXPECT_EQ(default_cache_dir(), std::string(home) + "/.cache/semioctree");
  }
  if (old_xdg) ::setenv("XDG_CACHE_HOME", saved.c_str(), 1);
}

// --- the lab (measured, reported) ---------------------------------------------------

TEST(CoverageLab, ReferenceAndOneScanFromTheStart) {
  if (sanitized()) GTEST_SKIP() << "the lab reference is heavy under sanitizers";
  const GroundTruth truth(load("lab"));
  const CoverageReference ref = compute_coverage_reference(truth);
  std::cout << "lab reference (grid " << ref.grid_spacing << " m, samples " << ref.sample_spacing
            << " m): " << ref.visible.size() << " of " << ref.sample_count << " samples from "
            << ref.positions.size() << " positions, " << ref.segment_queries << " segment queries, "
            << ref.seconds << " s\n";
  RecordProperty("reference_seconds", std::to_string(ref.seconds));
  ASSERT_GT(ref.positions.size(), 50u);
  for (const auto& c : ref.positions) EXPECT_TRUE(in_rect(c, 0.0, 10.4, 0.0, 8.5));
  // The main room alone: the corridor, the two small rooms and what stands outside the
  // window (the tree, the neighbouring building) are seen only through the doors and the
  // window, the outer faces of the building never.
  const Scene& scene = truth.scene();
  const auto samples = truth.surface_samples(ref.sample_spacing);
  ASSERT_EQ(samples.size(), ref.sample_count);
  const std::vector<bool> in = visible_flags(ref);
  const std::vector<OpeningRect> openings = truth.openings();
  auto box_named = [&](const std::string& name) {
    for (std::size_t i = 0; i < scene.boxes.size(); ++i)
      if (scene.boxes[i].name == name) return static_cast<int>(i);
    ADD_FAILURE() << "no box " << name;
    return -1;
  };
  const int building = box_named("neighbouring-building");
  const std::vector<int> beyond_doors = {box_named("corridor-lockers"), box_named("room-a-shelf"),
                                         box_named("room-b-desk")};
  int tree = -1;
  for (std::size_t i = 0; i < scene.cylinders.size(); ++i)
    if (scene.cylinders[i].name == "tree") tree = static_cast<int>(i);
  ASSERT_GE(tree, 0);
  std::size_t building_samples = 0, outside_samples = 0, outside_in = 0, opening = 0,
              opening_in = 0, opening_scanned = 0, room_walls = 0, room_walls_in = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const SurfaceSample& s = samples[i];
    const bool is_building = s.part.kind == PartKind::box && s.part.index == building;
    const bool outside =
        is_building || (s.part.kind == PartKind::cylinder && s.part.index == tree) ||
        (s.part.kind == PartKind::box &&
         std::find(beyond_doors.begin(), beyond_doors.end(), s.part.index) != beyond_doors.end());
    building_samples += is_building;
    outside_samples += outside;
    outside_in += outside && in[i];
    if (on_opening_surface(truth, openings, s)) {
      ++opening;
      opening_in += in[i];
      opening_scanned += seen_by_scanner(truth, s, ref.positions);
    } else if (in[i]) {
      EXPECT_TRUE(in_rect(s.position, 0.0, 10.4, 0.0, 8.5)) << s.position.transpose();
    }
    // The inner faces of the main room's walls (walls 0, 1, 2 and 4), away from the
    // furniture that stands against them (cabinets west and north, the dewar).
    if (s.part.kind == PartKind::wall && std::abs(s.normal.z()) < 0.5 &&
        in_rect(s.position, 0.0, 10.4, 0.0, 8.5) && s.position.z() > 2.3) {
      ++room_walls;
      room_walls_in += in[i];
    }
  }
  std::cout << "lab: " << outside_in << " of " << outside_samples
            << " samples outside the room in the reference (the neighbouring building "
            << building_samples << "), opening faces " << opening_in << " of " << opening << " ("
            << opening_scanned << " by the scanner's rule), the room's walls above 2.3 m "
            << room_walls_in << " of " << room_walls << "\n";
  EXPECT_GT(building_samples, 600000u);
  EXPECT_EQ(outside_in, 0u);
  // Jambs, sills and lintels of the window and the three doors (about 4.6 m² at 2 cm).
  EXPECT_GT(opening, 10000u);
  EXPECT_EQ(opening_in, opening_scanned);
  EXPECT_GE(opening_in, opening * 99 / 100) << opening_in << " of " << opening;
  EXPECT_GE(room_walls_in, room_walls * 999 / 1000) << room_walls_in << " of " << room_walls;
  // The room's own surfaces: about a seventh of the scene's samples.
  EXPECT_LT(ref.visible.size(), ref.sample_count / 5);
  EXPECT_GT(ref.visible.size(), 350000u);
  // The reference's shortcuts agree with the plain rule on a spread of samples.
  std::size_t checked = 0;
  for (std::size_t i = 0; i < samples.size(); i += 997, ++checked) {
    bool any = false;
    for (const auto& c : ref.positions) {
      any = sample_visible_from(truth, samples[i], c);
      if (any) break;
    }
    EXPECT_EQ(any, in[i]) << samples[i].position.transpose();
  }
  EXPECT_GT(checked, 2500u);
  const auto t0 = std::chrono::steady_clock::now();
  const Coverage c = measure_coverage(ref, scan_from_start(truth));
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "lab, one scan from the start: " << c.covered << " of " << c.reference_points
            << " = " << c.percent << " % (scan + measure " << t << " s)\n";
  // One scan from the middle of the room sees most of it (the street and the rooms it
  // sees through the openings are not in the reference, as the pipeline labels them out)...
  EXPECT_GT(c.percent, 60.0);
  EXPECT_LT(c.percent, 90.0);  // ... but benches, cabinets and the column hide part of it
}

}  // namespace
