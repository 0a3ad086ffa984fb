// Doors and windows (paper 2.2.2): holes in RANSAC walls confirmed by line of
// sight. Analytic rooms check sizes and the LOS rejection of a shadow; the lab
// scene checks detection against the scene's ground truth for 5 scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <random>
#include <string>

#include "semioctree/discretize.h"
#include "semioctree/octomap_ext/import.h"
#include "semioctree/openings.h"
#include "semioctree/preprocess.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/opening_match.h"
#include "support/lab_scan.h"

namespace semioctree {
namespace {

// The lab's scanner at the tests' step (support/lab_scan.h): 4× fewer rays.
sim::ScannerConfig test_scanner(const sim::Scene& scene) {
  sim::ScannerConfig c = scene.scanner;
  c.azimuth_step_deg = c.elevation_step_deg = testing::kTestStepDeg;
  return c;
}

using Vec3 = Eigen::Vector3d;
using Skip = std::function<bool(const Vec3&)>;

// Points on a grid of `spacing` over origin + [0, len1]·e1 + [0, len2]·e2, with
// 1 mm of noise along the normal, except where `skip` says so.
void add_rect(Cloud& cloud, const Vec3& origin, const Vec3& e1, double len1, const Vec3& e2,
              double len2, double spacing, std::mt19937& rng, const Skip& skip = nullptr) {
  std::normal_distribution<double> noise(0.0, 0.001);
  const Vec3 n = e1.cross(e2).normalized();
  for (double a = spacing / 2; a < len1; a += spacing)
    for (double b = spacing / 2; b < len2; b += spacing) {
      const Vec3 p = origin + a * e1 + b * e2 + noise(rng) * n;
      if (skip && skip(p)) continue;
      cloud.push_back(pcl::PointXYZ{float(p.x()), float(p.y()), float(p.z())});
    }
}

// A 6 × depth × 3 m room without floor and ceiling (preprocess removes them);
// `south_skip` cuts holes into the wall y = 0.
Cloud make_room(double depth, std::mt19937& rng, const Skip& south_skip) {
  Cloud c;
  const double h = 3.0, s = 0.02;
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
  add_rect(c, Vec3(0, 0, 0), X, 6.0, Z, h, s, rng, south_skip);
  add_rect(c, Vec3(0, depth, 0), X, 6.0, Z, h, s, rng);
  add_rect(c, Vec3(0, 0, 0), Y, depth, Z, h, s, rng);
  add_rect(c, Vec3(6.0, 0, 0), Y, depth, Z, h, s, rng);
  return c;
}

// Extent of an opening along `u` (a unit horizontal direction) and in z.
struct Rect2 {
  double u0, u1, z0, z1;
};
Rect2 rect_along(const std::array<Vec3, 4>& corners, const Vec3& u) {
  Rect2 r{1e9, -1e9, 1e9, -1e9};
  for (const Vec3& c : corners) {
    r.u0 = std::min(r.u0, c.dot(u));
    r.u1 = std::max(r.u1, c.dot(u));
    r.z0 = std::min(r.z0, c.z());
    r.z1 = std::max(r.z1, c.z());
  }
  return r;
}
Vec3 centre(const DetectedOpening& o) {
  return 0.25 * (o.corners[0] + o.corners[1] + o.corners[2] + o.corners[3]);
}

using sim_platform::opening_iou;  // IoU in the true opening's wall plane

// Does the segment a → p pass through the axis-aligned box [lo, hi] (slab test)?
bool segment_hits_box(const Vec3& a, const Vec3& p, const Vec3& lo, const Vec3& hi) {
  double t0 = 0, t1 = 1;
  const Vec3 d = p - a;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// make_room with a door (x ∈ [1.0, 2.0], up to 2.1 m) and a window (x ∈ [3.5, 5.0],
// z ∈ [0.9, 2.3]) in its south wall.
Cloud door_and_window_room() {
  std::mt19937 rng(7);
  return make_room(4.0, rng, [](const Vec3& p) {
    const bool door = p.x() > 1.0 && p.x() < 2.0 && p.z() < 2.1;
    const bool window = p.x() > 3.5 && p.x() < 5.0 && p.z() > 0.9 && p.z() < 2.3;
    return door || window;
  });
}

TEST(Openings, FindsDoorAndWindowWithTheirSizes) {
  const Cloud cloud = door_and_window_room();
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  const std::vector<Point3> scanners{{3.0, 3.0, 1.5}};
  OpeningsReport report;
  const auto found = detect_openings(cloud, 3.0, *tree, scanners, {}, &report);
  EXPECT_EQ(report.walls.size(), 4u);
  ASSERT_EQ(found.size(), 2u);
  const double tol = 0.1;  // two cells
  int doors = 0, windows = 0;
  for (const DetectedOpening& o : found) {
    std::printf("%s: width %.3f height %.3f sill %.3f LOS %.2f\n", to_string(o.kind), o.width,
                o.height, o.sill, o.los_fraction);
    const Rect2 r = rect_along(o.corners, Vec3::UnitX());
    for (const Vec3& c : o.corners) EXPECT_NEAR(c.y(), 0.0, 0.01);
    EXPECT_GE(o.los_fraction, 0.85);
    if (o.kind == OpeningKind::kDoor) {
      ++doors;
      EXPECT_NEAR(r.u0, 1.0, tol);
      EXPECT_NEAR(r.u1, 2.0, tol);
      EXPECT_NEAR(r.z0, 0.0, 1e-9);
      EXPECT_NEAR(r.z1, 2.1, tol);
      EXPECT_NEAR(o.width, 1.0, tol);
      EXPECT_NEAR(o.height, 2.1, tol);
    } else {
      ++windows;
      EXPECT_NEAR(r.u0, 3.5, tol);
      EXPECT_NEAR(r.u1, 5.0, tol);
      EXPECT_NEAR(r.z0, 0.9, tol);
      EXPECT_NEAR(r.z1, 2.3, tol);
      EXPECT_NEAR(o.width, 1.5, tol);
      EXPECT_NEAR(o.height, 1.4, tol);
    }
  }
  EXPECT_EQ(doors, 1);
  EXPECT_EQ(windows, 1);

  // The hole's leaves in the wall plane carry the opening's label; the wall
  // beside it stays occupied.
  const std::size_t labelled = label_openings(*tree, found);
  EXPECT_GT(labelled, 0u);
  auto label_at = [&](double x, double y, double z) {
    const auto o = tree->find_octant(Point3(x, y, z));
    return o ? o->label() : Label::kUnknown;
  };
  EXPECT_EQ(label_at(1.5, 0.001, 1.0), Label::kDoor);
  EXPECT_EQ(label_at(4.2, 0.001, 1.6), Label::kWindow);
  EXPECT_EQ(label_at(2.8, 0.001, 1.0), Label::kOccupied);
  EXPECT_EQ(label_at(1.5, 0.001, 2.7), Label::kOccupied);
}

// Beyond the inner corner of an L-shaped room a wall's plane runs on through open space
// from floor to ceiling; the few ceiling returns the ceiling's cut leaves a couple of
// centimetres under it close the gap at the top. That is no door: a door leaves wall
// (a lintel, min_lintel) below the ceiling. A real door in the same wall is found.
TEST(Openings, AGapUpToTheCeilingsStrayReturnsIsNoDoor) {
  std::mt19937 rng(3);
  const double ceiling = 2.5;
  Cloud cloud;
  for (const auto& p : make_room(4.0, rng, [](const Vec3& p) {
         const bool open_to_ceiling = p.x() > 3.5 && p.x() < 4.5;
         const bool door = p.x() > 1.0 && p.x() < 2.0 && p.z() < 2.1;
         return open_to_ceiling || door;
       }))
    if (p.z < 2.46) cloud.push_back(p);  // what the ceiling's cut leaves of the walls
  std::uniform_real_distribution<double> along(3.5, 4.5), off(-0.01, 0.01);
  for (int i = 0; i < 60; ++i)  // stray ceiling returns over the gap, 2-4 cm under it
    cloud.push_back(pcl::PointXYZ{float(along(rng)), float(off(rng)), float(2.47 + off(rng))});
  auto tree = discretize(cloud, ceiling, {0.05, 0.8});
  const std::vector<Point3> scanners{{3.0, 3.0, 1.5}};
  OpeningParams no_lintel;
  no_lintel.min_lintel = 0.0;
  // Without the rule the gap is still no door: the stray returns lie in the ceiling's row,
  // and over the gap's columns there is no wall below it (columns_with_wall).
  const auto without = detect_openings(cloud, ceiling, *tree, scanners, no_lintel);
  ASSERT_EQ(without.size(), 1u);
  EXPECT_EQ(without[0].kind, OpeningKind::kDoor);
  const auto found = detect_openings(cloud, ceiling, *tree, scanners);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(centre(found[0]).x(), 1.5, 0.05);
}

// Two walls in line with a corridor between them (x 3.5 .. 4.5, floor to ceiling) make
// one plane with a gap. A few stray returns across the gap at 0.9 m and 2.2 m (a grazing
// ray off a jamb, noise) once bounded a "window" between them: wall above and below a
// hole must span most of its width.
TEST(Openings, AGapBetweenWallsInLineIsNoWindowForStrayReturns) {
  std::mt19937 rng(5);
  Cloud cloud = make_room(4.0, rng, [](const Vec3& p) {
    const bool corridor = p.x() > 3.5 && p.x() < 4.5;
    const bool door = p.x() > 1.0 && p.x() < 2.0 && p.z() < 2.1;
    return corridor || door;
  });
  for (const double z : {0.92, 2.22})
    for (const double x : {3.72, 3.97, 4.22})
      cloud.push_back(pcl::PointXYZ{float(x), 0.0f, float(z)});
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  const std::vector<Point3> scanners{{3.0, 3.0, 1.5}};
  const auto found = detect_openings(cloud, 3.0, *tree, scanners);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(centre(found[0]).x(), 1.5, 0.05);
}

// The floor's and the ceiling's cuts leave a few of their returns a couple of centimetres
// from them, along every plane. Where a wall's plane runs on through open space (the room
// beyond the wall's end), those bands and a stray face in line with the wall (a cabinet's
// side 5 m on) once joined it into one segment twice its length, mostly empty: the wall
// failed min_wall_fill and its door was lost. Only points between the bands show where a
// wall stands.
TEST(Openings, FloorAndCeilingBandsDoNotCarryAWallThroughOpenSpace) {
  std::mt19937 rng(11);
  const double ceiling = 3.0;
  Cloud cloud = make_room(4.0, rng, [](const Vec3& p) {
    return p.x() > 1.0 && p.x() < 2.0 && p.z() < 2.1;  // a door
  });
  std::uniform_real_distribution<double> off(-0.01, 0.01);
  for (double x = 6.05; x < 12.0; x += 0.04)  // the bands beyond the wall's end
    for (const double z : {0.02, ceiling - 0.02})
      cloud.push_back(pcl::PointXYZ{float(x), float(off(rng)), float(z + off(rng))});
  for (double z = 0.01; z < 2.0; z += 0.02)  // a cabinet's side in line with the wall
    cloud.push_back(pcl::PointXYZ{11.5f, float(off(rng)), float(z)});
  auto tree = discretize(cloud, ceiling, {0.05, 0.8});
  const std::vector<Point3> scanners{{3.0, 3.0, 1.5}};
  OpeningsReport report;
  const auto found = detect_openings(cloud, ceiling, *tree, scanners, {}, &report);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(centre(found[0]).x(), 1.5, 0.05);
  // The south wall ends where it stands, at x = 6, not at the cabinet.
  const auto south =
      std::find_if(report.walls.begin(), report.walls.end(), [](const DetectedWall& w) {
        return std::abs(w.normal.y()) > 0.9 && std::abs(w.offset) < 0.1;
      });
  ASSERT_NE(south, report.walls.end());
  const double a = std::abs(south->u_min), b = std::abs(south->u_max);
  EXPECT_NEAR(std::max(a, b), 6.0, 0.1);
}

// A scanner confirms only what it could have seen: cells within its range and elevation
// limits. The room of FindsDoorAndWindowWithTheirSizes: its door (x 1 .. 2, up to 2.1 m)
// and window (x 3.5 .. 5, z 0.9 .. 2.3) 3 m from the scanner at 1.5 m. Looking down no
// further than -5°, the scanner sees neither below about 1.2 m: the door keeps 42 % seen
// up to its top (partly hidden, confirmed), the window loses its sill (not confirmed).
// From 1.5 m off the wall with a range of 2.4 m, the door is in range, the window not.
TEST(Openings, AScannerConfirmsOnlyWithinItsLimits) {
  const Cloud cloud = door_and_window_room();
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  ScannerView view(Point3(3.0, 3.0, 1.5));
  view.elevation_min_deg = -90;
  view.elevation_max_deg = 90;
  auto kinds = [&](const ScannerView& v) {  // "door window" when both are found
    std::vector<std::string> out;
    for (const DetectedOpening& o : detect_openings(cloud, 3.0, *tree, std::vector{v}))
      out.push_back(to_string(o.kind));
    std::sort(out.begin(), out.end());
    std::string joined;
    for (const std::string& k : out) joined += (joined.empty() ? "" : " ") + k;
    return joined;
  };
  EXPECT_EQ(kinds(view), "door window");
  ScannerView level = view;
  level.elevation_min_deg = -5;
  EXPECT_EQ(kinds(level), "door");
  ScannerView near = view;
  near.position = Point3(1.5, 1.5, 1.5);
  EXPECT_EQ(kinds(near), "door window");
  near.max_range = 2.4;
  EXPECT_EQ(kinds(near), "door");
}

// A door through a 0.25 m wall, scanned from the room and from beyond the wall: the hole
// is in both faces of the wall, and found on both. It is one door, kept on the face of the
// room the survey started in (the first scanner's).
TEST(Openings, ADoorSeenFromBothSidesOfItsWallIsOneDoor) {
  std::mt19937 rng(11);
  auto door = [](const Vec3& p) { return p.x() > 1.0 && p.x() < 2.0 && p.z() < 2.1; };
  Cloud cloud = make_room(4.0, rng, door);
  const Vec3 X = Vec3::UnitX(), Z = Vec3::UnitZ();
  add_rect(cloud, Vec3(-0.25, -0.25, 0), X, 6.5, Z, 3.0, 0.02, rng, door);  // the far face
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  const std::vector<Point3> scanners{{3.0, 3.0, 1.5}, {1.5, -2.0, 1.5}};
  OpeningsReport report;
  const auto found = detect_openings(cloud, 3.0, *tree, scanners, {}, &report);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(centre(found[0]).y(), 0.0, 0.03);  // the room's face
  EXPECT_EQ(report.far_faces, 1u);
  // Both faces hold it: with walls taken as no thicker than nothing, both doors stay.
  OpeningParams thin;
  thin.max_wall_thickness = 0.0;
  const auto both = detect_openings(cloud, 3.0, *tree, scanners, thin);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NEAR(std::abs(centre(both[0]).y() - centre(both[1]).y()), 0.25, 0.03);
}

TEST(Openings, OcclusionShadowIsRejectedByLineOfSight) {
  std::mt19937 rng(11);
  const Vec3 scanner(2.5, 4.0, 1.5);
  // A cabinet x ∈ [2, 3], y ∈ [1.0, 1.4], 2 m high, in front of the wall y = 0.
  const Vec3 box_lo(2.0, 1.0, 0.0), box_hi(3.0, 1.4, 2.0);
  auto hidden = [&](const Vec3& p) { return segment_hits_box(scanner, p, box_lo, box_hi); };
  // The wall loses the points the cabinet hides: a rectangular-looking hole of
  // door size that reaches the floor (≈ 1.5 m wide, 2.27 m high).
  Cloud cloud = make_room(5.0, rng, hidden);
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
  const double s = 0.02;
  add_rect(cloud, Vec3(2.0, 1.4, 0.0), X, 1.0, Z, 2.0, s, rng);  // front
  add_rect(cloud, Vec3(2.0, 1.0, 0.0), X, 1.0, Z, 2.0, s, rng);  // back
  add_rect(cloud, Vec3(2.0, 1.0, 0.0), Y, 0.4, Z, 2.0, s, rng);  // sides
  add_rect(cloud, Vec3(3.0, 1.0, 0.0), Y, 0.4, Z, 2.0, s, rng);
  add_rect(cloud, Vec3(2.0, 1.0, 2.0), X, 1.0, Y, 0.4, s, rng);  // top
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  const std::vector<Point3> scanners{{scanner.x(), scanner.y(), scanner.z()}};

  // Without the LOS test the shadow passes for a door: the hole is real.
  OpeningParams no_los;
  no_los.los_min_fraction = 0.0;
  const auto unchecked = detect_openings(cloud, 3.0, *tree, scanners, no_los);
  ASSERT_EQ(unchecked.size(), 1u);
  EXPECT_EQ(unchecked[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(centre(unchecked[0]).x(), 2.5, 0.1);
  std::printf("shadow as a door: width %.3f height %.3f, LOS %.3f\n", unchecked[0].width,
              unchecked[0].height, unchecked[0].los_fraction);
  EXPECT_LT(unchecked[0].los_fraction, 0.5);

  OpeningsReport report;
  const auto confirmed = detect_openings(cloud, 3.0, *tree, scanners, {}, &report);
  EXPECT_TRUE(confirmed.empty());
  const bool shadow_rejected =
      std::any_of(report.rejected.begin(), report.rejected.end(), [](const DetectedOpening& o) {
        return o.kind == OpeningKind::kDoor && std::abs(centre(o).x() - 2.5) < 0.1 &&
               o.los_fraction < 0.85;
      });
  EXPECT_TRUE(shadow_rejected);

  // A second scan taken between the cabinet and the wall, 0.1 m off the wall's plane
  // (as in one of its doorways): the wall is nearer than its minimum range, so it
  // recorded no points of it, and its short lines to the shadow's cells met nothing:
  // it would confirm the shadow. A scanner that near a wall's plane does not count for
  // that wall.
  const std::vector<Point3> with_edge_on{scanners[0], Point3(2.5, 0.1, 1.5)};
  EXPECT_TRUE(detect_openings(cloud, 3.0, *tree, with_edge_on).empty());
}

// A cabinet 0.9 m wide, 0.5 m deep and 2.1 m high stands 1 cm off the long wall of a
// 12 × 5 m room, seen by scanners 0.9 m off that wall on either side of it. Neither sees
// the wall behind it: a hole of door size. A line of sight ends 1.5 leaves in front of the
// wall, so a line grazing the wall ends before it meets the cabinet's side for cells
// within margin / tan(incidence) of the side: from 5 m along the wall, 0.42 m of the
// 0.9 m, from each end (93 % of the shadow "seen"). Such lines must not confirm the
// shadow as a door; from 4 m along, lines that pass the slack rule see two strips at its
// sides (half of it), which must not confirm it as a partly hidden door either. The same hole made
// by a real door is found once a scan sees it from the room.
TEST(Openings, ACabinetsShadowSeenAlongTheWallIsNoDoor) {
  const Vec3 box_lo(5.55, 0.01, 0.0), box_hi(6.45, 0.51, 2.1);
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
  auto room = [&](const std::vector<Vec3>& scanners, bool cabinet) {
    std::mt19937 rng(5);
    Cloud c;
    const double h = 3.0, s = 0.02;
    // The south wall keeps a point where some scanner sees it (the union of the scans).
    add_rect(c, Vec3(0, 0, 0), X, 12.0, Z, h, s, rng, [&](const Vec3& p) {
      if (!cabinet) return p.x() > 5.55 && p.x() < 6.45 && p.z() < 2.1;  // a door
      for (const Vec3& a : scanners)
        if (!segment_hits_box(a, p, box_lo, box_hi)) return false;
      return true;
    });
    add_rect(c, Vec3(0, 5, 0), X, 12.0, Z, h, s, rng);
    add_rect(c, Vec3(0, 0, 0), Y, 5.0, Z, h, s, rng);
    add_rect(c, Vec3(12, 0, 0), Y, 5.0, Z, h, s, rng);
    if (cabinet) {
      add_rect(c, Vec3(5.55, 0.51, 0), X, 0.9, Z, 2.1, s, rng);  // front
      add_rect(c, Vec3(5.55, 0.01, 0), Y, 0.5, Z, 2.1, s, rng);  // sides
      add_rect(c, Vec3(6.45, 0.01, 0), Y, 0.5, Z, 2.1, s, rng);
      add_rect(c, Vec3(5.55, 0.01, 2.1), X, 0.9, Y, 0.5, s, rng);  // top
    }
    return c;
  };
  auto positions = [](const std::vector<Vec3>& v) {
    std::vector<Point3> out;
    for (const Vec3& a : v) out.emplace_back(a.x(), a.y(), a.z());
    return out;
  };
  for (double along : {5.0, 4.0}) {
    const std::vector<Vec3> scanners{{6.0 - along, 0.9, 1.5}, {6.0 + along, 0.9, 1.5}};
    const Cloud cloud = room(scanners, true);
    auto tree = discretize(cloud, 3.0, {0.05, 0.8});
    // The hole is there: without the LOS test it passes for a door.
    OpeningParams no_los;
    no_los.los_min_fraction = 0.0;
    const auto unchecked = detect_openings(cloud, 3.0, *tree, positions(scanners), no_los);
    ASSERT_EQ(unchecked.size(), 1u) << along << " m along";
    EXPECT_NEAR(centre(unchecked[0]).x(), 6.0, 0.1);
    OpeningsReport report;
    const auto found = detect_openings(cloud, 3.0, *tree, positions(scanners), {}, &report);
    EXPECT_TRUE(found.empty()) << along << " m along: " << found.size() << " openings, LOS "
                               << (found.empty() ? 0.0 : found[0].los_fraction);
    ASSERT_FALSE(report.rejected.empty()) << along << " m along";
    std::printf("%.0f m along: shadow rejected, LOS %.2f\n", along,
                report.rejected[0].los_fraction);
  }
  // A door in its place, seen from the middle of the room as well: found.
  const std::vector<Vec3> scanners{{1.0, 0.9, 1.5}, {11.0, 0.9, 1.5}, {6.0, 3.0, 1.5}};
  const Cloud cloud = room(scanners, false);
  auto tree = discretize(cloud, 3.0, {0.05, 0.8});
  const auto found = detect_openings(cloud, 3.0, *tree, positions(scanners));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].kind, OpeningKind::kDoor);
  EXPECT_NEAR(found[0].width, 0.9, 0.1);
  EXPECT_NEAR(centre(found[0]).x(), 6.0, 0.05);
}

// --- lab scene ------------------------------------------------------------------------

struct LabRun {
  std::size_t visible = 0, matched = 0, false_positives = 0;
  std::vector<double> ious;  // of the visible openings, in ground-truth order
};

TEST(Openings, LabSceneFromStartMatchesGroundTruth) {
  const sim::Scene scene =
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
  const sim::GroundTruth truth(scene);
  const std::vector<sim::OpeningRect> gt = truth.openings();
  ASSERT_EQ(gt.size(), 4u);
  const sim::Pose2 start{scene.robot.start.x(), scene.robot.start.y(), scene.robot.start_yaw_deg};

  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    sim::ScanOptions so;
    so.seed = seed;
    so.threads = 1;
    so.with_intensity = false;
    const sim::Scan s = sim::scan(truth.ray_caster(), test_scanner(scene), start, so);
    Cloud cloud;
    cloud.reserve(s.points.size());
    const Eigen::Isometry3d to_world = s.sensor_to_world();
    for (const auto& p : s.points) {
      const Vec3 w = to_world * p.cast<double>();
      cloud.push_back(pcl::PointXYZ{float(w.x()), float(w.y()), float(w.z())});
    }
    PreprocessParams pp;
    pp.target_points = 400000;
    const PreprocessResult pre = preprocess(cloud, pp);
    auto tree = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.8});
    const Vec3 origin = pre.transform * s.origin();
    OpeningsReport report;
    const auto t0 = std::chrono::steady_clock::now();
    const auto found = detect_openings(*pre.cloud, pre.ceiling_height, *tree,
                                       {Point3(origin.x(), origin.y(), origin.z())}, {}, &report);
    // Printed for information only (shared machine): nothing is asserted on it.
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    auto match = [&](const DetectedOpening& d, const sim::OpeningRect& g) {
      return opening_iou(d, g, pre.transform);
    };
    LabRun run;
    std::printf(
        "seed %llu: %zu points, %zu walls, %zu candidates, %zu rejected by LOS, %zu LOS rays, "
        "%.2f s\n",
        static_cast<unsigned long long>(seed), pre.cloud->size(), report.walls.size(),
        report.candidates, report.rejected.size(), report.los_rays, seconds);
    for (const sim::OpeningRect& g : gt) {
      const Vec3 c = 0.25 * (g.corners[0] + g.corners[1] + g.corners[2] + g.corners[3]);
      const bool visible = truth.segment_free(s.origin(), c);
      double best = 0;
      for (const DetectedOpening& d : found) best = std::max(best, match(d, g));
      std::printf("  %s wall %d #%d (%.2f x %.2f): %s, IoU %.3f\n", sim::to_string(g.kind), g.wall,
                  g.index, g.width, g.height, visible ? "visible" : "not visible", best);
      if (!visible) continue;
      ++run.visible;
      run.ious.push_back(best);
      EXPECT_GE(best, 0.7) << "seed " << seed << ": " << sim::to_string(g.kind) << " of wall "
                           << g.wall;
    }
    for (const DetectedOpening& d : found) {
      double best = 0;
      for (const sim::OpeningRect& g : gt) best = std::max(best, match(d, g));
      const Vec3 c = centre(d);
      std::printf("  detected %s at (%.2f, %.2f, %.2f) %.2f x %.2f, LOS %.2f, best IoU %.3f\n",
                  to_string(d.kind), c.x(), c.y(), c.z(), d.width, d.height, d.los_fraction, best);
      EXPECT_GE(best, 0.3) << "seed " << seed << ": false positive " << to_string(d.kind) << " at ("
                           << c.x() << ", " << c.y() << ", " << c.z() << ")";
    }
    for (const DetectedOpening& d : report.rejected) {
      const Vec3 c = centre(d);
      std::printf("  rejected %s at (%.2f, %.2f, %.2f) %.2f x %.2f, LOS %.2f\n", to_string(d.kind),
                  c.x(), c.y(), c.z(), d.width, d.height, d.los_fraction);
    }
    // The start sees at least the window and one door: the check above is not vacuous.
    EXPECT_GE(run.visible, 2u);
    EXPECT_EQ(found.size(), 4u);

    if (seed == 1) {
      // With the paper's rule alone, door 1 (its lower half behind the computer
      // on bench 2, which the ground truth confirms) is rejected: that is what
      // OpeningParams::partly_hidden_min_los is for.
      OpeningParams paper_only;
      paper_only.partly_hidden_min_los = 0.0;
      const auto strict = detect_openings(*pre.cloud, pre.ceiling_height, *tree,
                                          {Point3(origin.x(), origin.y(), origin.z())}, paper_only);
      EXPECT_EQ(strict.size(), 3u);
      for (const DetectedOpening& d : strict) EXPECT_GE(d.los_fraction, 0.85);
      std::printf("  paper rule only: %zu openings\n", strict.size());
    }
  }
}

TEST(Openings, MapCeilingNeedsAFloorAndADenseLayerAboveTwoMetres) {
  SemiOcTree t(0.05, 0.8);
  auto fill_layer = [&](double z, double side) {  // occupied leaves over side × side m
    for (double x = 0.025; x < side; x += 0.05)
      for (double y = 0.025; y < side; y += 0.05) {
        octomap::OcTreeKey k;
        ASSERT_TRUE(t.key_of({x, y, z}, k));
        t.set_label(k, t.leaf_level(), Label::kOccupied);
      }
  };
  fill_layer(2.725, 3.0);  // a ceiling, but no floor: not levelled at z = 0
  EXPECT_FALSE(map_ceiling_height(t));
  fill_layer(0.025, 3.0);  // the floor
  ASSERT_TRUE(map_ceiling_height(t));
  EXPECT_DOUBLE_EQ(*map_ceiling_height(t), 2.725);
  fill_layer(1.525, 3.0);  // a dense layer below 2 m does not count
  EXPECT_DOUBLE_EQ(*map_ceiling_height(t), 2.725);
  EXPECT_FALSE(map_ceiling_height(t, 3.0));  // nothing above 3 m
  SemiOcTree sparse(0.05, 0.8);              // a floor and a far thinner layer above 2 m
  for (double x = 0.025; x < 3.0; x += 0.05)
    for (double y = 0.025; y < 3.0; y += 0.05) {
      octomap::OcTreeKey k;
      ASSERT_TRUE(sparse.key_of({x, y, 0.025}, k));
      sparse.set_label(k, sparse.leaf_level(), Label::kOccupied);
      if (y < 0.5) {
        ASSERT_TRUE(sparse.key_of({x, y, 2.525}, k));
        sparse.set_label(k, sparse.leaf_level(), Label::kOccupied);
      }
    }
  EXPECT_FALSE(map_ceiling_height(sparse));  // 1/6 of the floor's leaves: not a ceiling
}

// The way in for OctoMap users: the lab mapped by OctoMap itself from the start
// (insertPointCloud, as octomap_server does), imported, its ceiling found and
// its doors and window detected in the map alone, without points.
// The lab mapped by OctoMap itself from the robot's start, at the leaf sizes OctoMap
// users run (the wall grid's cells are the map's leaves). At 0.1 m the line of sight to
// the hole's column beside a jamb used to end inside the jamb's surface leaf when the
// ray came in obliquely, and the door at (10.4, 6.4) was rejected as a shadow.
class OccupancyMapOfTheLab : public ::testing::TestWithParam<double> {};

TEST_P(OccupancyMapOfTheLab, FromItsStartAllFourOpeningsAreFound) {
  const double leaf = GetParam();
  const sim::Scene scene =
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
  const sim::GroundTruth truth(scene);
  const sim::Pose2 start{scene.robot.start.x(), scene.robot.start.y(), scene.robot.start_yaw_deg};
  sim::ScanOptions so;
  so.seed = 1;
  so.with_intensity = false;
  const sim::Scan s = sim::scan(truth.ray_caster(), test_scanner(scene), start, so);
  const Eigen::Isometry3d to_world = s.sensor_to_world();
  octomap::Pointcloud points;
  points.reserve(s.points.size());
  for (const auto& p : s.points) {
    const Vec3 w = to_world * p.cast<double>();
    points.push_back(float(w.x()), float(w.y()), float(w.z()));
  }
  const Vec3 o = s.origin();
  const auto t0 = std::chrono::steady_clock::now();
  octomap::OcTree map(leaf);
  map.insertPointCloud(points, octomap::point3d(float(o.x()), float(o.y()), float(o.z())), -1.0,
                       false, true);
  std::printf("OctoMap insertPointCloud: %zu nodes [%.2f s]\n", map.size(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  const auto tree = from_occupancy_octree(map, 0.8);
  const std::optional<double> ceiling = map_ceiling_height(*tree);
  ASSERT_TRUE(ceiling);
  EXPECT_NEAR(*ceiling, 3.2, 0.05);
  OpeningsReport report;
  const auto found =
      detect_openings_in_map(*tree, *ceiling, {Point3(o.x(), o.y(), o.z())}, {}, &report);
  std::printf("%zu walls, %zu candidates, %zu found, %zu rejected\n", report.walls.size(),
              report.candidates, found.size(), report.rejected.size());
  // All four are in view of the start (the pipeline's test above finds the same).
  const std::vector<sim::OpeningRect> gt = truth.openings();
  ASSERT_EQ(gt.size(), 4u);
  const Eigen::Isometry3d world = Eigen::Isometry3d::Identity();
  for (const sim::OpeningRect& g : gt) {
    double best = 0;
    for (const DetectedOpening& d : found) best = std::max(best, opening_iou(d, g, world));
    EXPECT_GE(best, 0.7) << sim::to_string(g.kind) << " of wall " << g.wall;
  }
  for (const DetectedOpening& d : found) {
    double best = 0;
    for (const sim::OpeningRect& g : gt) best = std::max(best, opening_iou(d, g, world));
    const Vec3 c = centre(d);
    std::printf("  %s at (%.2f, %.2f, %.2f) %.2f x %.2f, sill %.2f, LOS %.2f, IoU %.3f\n",
                to_string(d.kind), c.x(), c.y(), c.z(), d.width, d.height, d.sill, d.los_fraction,
                best);
    EXPECT_GE(best, 0.3) << "false positive " << to_string(d.kind) << " at (" << c.x() << ", "
                         << c.y() << ", " << c.z() << ")";
  }
  EXPECT_EQ(found.size(), 4u);  // one wall each, not one per layer of leaves
}

INSTANTIATE_TEST_SUITE_P(Openings, OccupancyMapOfTheLab, ::testing::Values(0.05, 0.1),
                         [](const ::testing::TestParamInfo<double>& info) {
                           return info.param < 0.075 ? "Leaf5cm" : "Leaf10cm";
                         });

}  // namespace
}  // namespace semioctree
