// Next-Best-View candidates: the safety cylinder checked against a brute-force
// rule, the floor layer driven over, the grid and its anchor, reachability, and
// the blind zone under past scans (also on a pruned map).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/nbv.h"
#include "semioctree/occlusion.h"
#include "support/nbv_maps.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

using testing::kLeaf;
using testing::Map;
using testing::open_limits;
using testing::room_with_pillar;
using testing::score_at;

// --- candidates ---------------------------------------------------------------------------

// A 4 × 4 × 2.4 m room: walls, an occupied pillar, a small occluded octant low
// down, an occluded octant above the scanner's top and an occupied leaf on the
// floor (below the ground clearance).
struct FurnishedRoom : Map {
  FurnishedRoom() : Map(5, 5, 3) {
    walls(4.0, 4.0, 2.4);
    leaves({1.0, 1.0, 0.5}, {1.1, 1.1, 1.0}, Label::kOccupied);  // pillar
    set(3.05, 3.05, 0.25, 3, Label::kOccluded);                  // low, in reach
    set(2.05, 3.05, 2.05, 3, Label::kOccluded);                  // above 1.6 m
    leaf(3.025, 1.025, 0.025, Label::kOccupied);                 // on the floor
  }
};

struct Cell {
  int x, y;
  bool operator<(const Cell& o) const { return std::tie(x, y) < std::tie(o.x, o.y); }
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
};

// The candidates of a leaf-spacing grid by the rule, brute force: obstacle
// columns from every octant meeting [clearance, top), cylinder clear when no
// obstacle column centre is within radius + leaf/2, reachable by a 4-connected
// fill over clear cells, empty at scanner height.
std::vector<Cell> brute_force_candidates(const SemiOcTree& t, const RobotGeometry& robot,
                                         const Point3& start, int cells) {
  std::set<Cell> obstacles;
  t.for_each_octant([&](const Octant& o) {
    const Label l = o.label();
    if (l != Label::kOccupied && l != Label::kOccluded && l != Label::kUnknown) return;
    const double z0 = o.center.z - o.size / 2, z1 = o.center.z + o.size / 2;
    if (z1 <= robot.ground_clearance + 1e-9 || z0 >= robot.top() - 1e-9) return;
    const int n = int(std::lround(o.size / kLeaf));
    const int x0 = int(std::lround((o.center.x - o.size / 2) / kLeaf));
    const int y0 = int(std::lround((o.center.y - o.size / 2) / kLeaf));
    for (int x = x0; x < x0 + n; ++x)
      for (int y = y0; y < y0 + n; ++y) obstacles.insert({x, y});
  });
  const double reach = robot.radius / kLeaf + 0.5;
  std::vector<char> clear(cells * cells, 0);
  for (int x = 0; x < cells; ++x)
    for (int y = 0; y < cells; ++y) {
      bool ok = true;
      for (const Cell& o : obstacles)
        if (double(o.x - x) * (o.x - x) + double(o.y - y) * (o.y - y) <= reach * reach) {
          ok = false;
          break;
        }
      // Outside the map is unknown: the nearest outside cell is an obstacle too.
      for (int d : {x + 1, y + 1, cells - x, cells - y}) ok &= double(d) > reach;
      clear[x * cells + y] = ok;
    }
  std::vector<char> reached(cells * cells, 0);
  const int sx = int(start.x / kLeaf), sy = int(start.y / kLeaf);
  std::vector<Cell> stack{{sx, sy}};
  reached[sx * cells + sy] = 1;
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    for (const Cell& d : {Cell{1, 0}, Cell{-1, 0}, Cell{0, 1}, Cell{0, -1}}) {
      const int x = c.x + d.x, y = c.y + d.y;
      if (x < 0 || y < 0 || x >= cells || y >= cells) continue;
      if (reached[x * cells + y] || !clear[x * cells + y]) continue;
      reached[x * cells + y] = 1;
      stack.push_back({x, y});
    }
  }
  std::vector<Cell> out;
  for (int y = 0; y < cells; ++y)
    for (int x = 0; x < cells; ++x) {
      const auto o =
          t.find_octant(Point3((x + 0.5) * kLeaf, (y + 0.5) * kLeaf, robot.scanner_height));
      if (o && o->label() == Label::kEmpty && clear[x * cells + y] && reached[x * cells + y])
        out.push_back({x, y});
    }
  return out;
}

std::vector<Cell> cells_of(const std::vector<Point3>& ps) {
  std::vector<Cell> out;
  for (const Point3& p : ps)
    out.push_back({int(std::floor(p.x / kLeaf)), int(std::floor(p.y / kLeaf))});
  return out;
}

bool has_candidate_near(const std::vector<Point3>& ps, double x, double y, double tol = 1e-6) {
  for (const Point3& p : ps)
    if (std::hypot(p.x - x, p.y - y) < tol) return true;
  return false;
}

TEST(Nbv, AGridPointAlreadyScannedFromIsNoCandidate) {
  // The scan stood on a grid point (the robot drives to candidates): a scan from there
  // would see again what it saw, so that point is no candidate; its neighbours still are.
  FurnishedRoom m;
  RobotGeometry robot;
  NbvParams p;
  p.candidate_spacing = 0.5;
  const Point3 start(2.0, 2.0, 0);
  CandidateReport before;
  const auto all = find_candidates(m.t, robot, start, {}, p, &before);
  ASSERT_GT(all.size(), 4u);
  const Point3 scanned = all[all.size() / 2];
  // The scan's optical centre as registration leaves it: a few millimetres off.
  const Point3 past(scanned.x + 0.004, scanned.y - 0.003, robot.scanner_height);
  CandidateReport after;
  const auto left = find_candidates(m.t, robot, start, {past}, p, &after);
  EXPECT_EQ(after.already_scanned, 1u);
  EXPECT_EQ(left.size(), all.size() - 1);
  EXPECT_EQ(after.feasible, left.size());
  EXPECT_FALSE(has_candidate_near(left, scanned.x, scanned.y));
  EXPECT_TRUE(has_candidate_near(left, scanned.x + 0.5, scanned.y) ||
              has_candidate_near(left, scanned.x - 0.5, scanned.y));
  EXPECT_EQ(before.already_scanned, 0u);
}

TEST(Nbv, CandidatesKeepTheSafetyCylinderFreeOfObstacles) {
  FurnishedRoom m;
  RobotGeometry robot;
  NbvParams p;
  p.candidate_spacing = kLeaf;  // every leaf cell is a grid point
  const Point3 start(2.0, 2.0, 0);
  CandidateReport rep;
  const auto got = find_candidates(m.t, robot, start, {}, p, &rep);
  const auto expected = brute_force_candidates(m.t, robot, start, 80);
  EXPECT_GT(expected.size(), 500u);
  auto sorted = [](std::vector<Cell> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_TRUE(sorted(cells_of(got)) == sorted(expected))
      << got.size() << " candidates, brute force " << expected.size();
  EXPECT_EQ(rep.feasible, got.size());
  EXPECT_GT(rep.cylinder_blocked, 0u);
  for (const Point3& c : got) EXPECT_DOUBLE_EQ(c.z, robot.scanner_height);
  // Spot checks: clear in the middle, too near the pillar (0.3 m), the low
  // occluded octant (0.35 m) or a wall (0.4 m); the occluded octant above the
  // scanner's top and the floor leaf do not count.
  EXPECT_TRUE(has_candidate_near(got, 2.025, 2.025));
  EXPECT_FALSE(has_candidate_near(got, 1.375, 1.025));
  EXPECT_FALSE(has_candidate_near(got, 3.425, 3.075));
  EXPECT_FALSE(has_candidate_near(got, 0.425, 2.025));
  EXPECT_TRUE(has_candidate_near(got, 2.075, 3.025));
  EXPECT_TRUE(has_candidate_near(got, 3.025, 1.025));
  // Without ground clearance the floor leaf is an obstacle.
  RobotGeometry no_clearance;
  no_clearance.ground_clearance = 0;
  EXPECT_FALSE(has_candidate_near(find_candidates(m.t, no_clearance, start, {}, p), 3.025, 1.025));
  // A slimmer robot fits nearer the pillar.
  RobotGeometry slim;
  slim.radius = 0.2;
  EXPECT_TRUE(has_candidate_near(find_candidates(m.t, slim, start, {}, p), 1.375, 1.025));
}

// At a 0.1 m leaf the floor's layer [0, 0.1) holds the floor's points (all of them in an
// OctoMap map, what the floor cut leaves in ours). Below the leaf the map cannot tell an
// obstacle from the floor: that layer is driven over, a taller obstacle is not. Before,
// a leaf above the 5 cm clearance made the floor an obstacle everywhere: `survey --leaf
// 0.1` stopped after its first scan with no feasible candidate.
TEST(Nbv, FloorLayerOfACoarseLeafIsDrivenOver) {
  SemiOcTree t{0.1, 0.8};
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 3; ++z) t.create_coarse({x, y, z}, Label::kEmpty);
  auto leaf = [&](double x, double y, double z, Label l) {
    octomap::OcTreeKey k;
    ASSERT_TRUE(t.key_of({x, y, z}, k));
    t.set_label(k, t.leaf_level(), l);
  };
  for (double x = 0.05; x < 4.8; x += 0.1)
    for (double y = 0.05; y < 4.8; y += 0.1) leaf(x, y, 0.05, Label::kOccupied);  // the floor
  leaf(1.25, 2.45, 0.15, Label::kOccupied);  // a box 0.2 m tall on the floor
  leaf(1.25, 2.45, 0.05, Label::kOccupied);
  NbvParams p;
  p.candidate_spacing = 0.1;
  const Point3 start(2.45, 2.45, 0);
  RobotGeometry robot;
  EXPECT_DOUBLE_EQ(floor_layer_clearance(robot, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(floor_layer_clearance(robot, 0.05), 0.05);
  const std::vector<Point3> got = find_candidates(t, robot, start, {}, p);
  // Clear of the map's border (unknown beyond it) by radius + leaf/2 = 0.55 m.
  EXPECT_TRUE(has_candidate_near(got, 2.45, 2.45));
  EXPECT_TRUE(has_candidate_near(got, 3.95, 3.95));
  EXPECT_FALSE(has_candidate_near(got, 1.65, 2.45));  // 0.4 m from the box
  EXPECT_TRUE(has_candidate_near(got, 1.85, 2.45));   // 0.6 m from it
  EXPECT_GT(got.size(), 300u);
  // No clearance: nothing is driven over, the floor blocks every cylinder.
  RobotGeometry strict;
  strict.ground_clearance = 0;
  EXPECT_DOUBLE_EQ(floor_layer_clearance(strict, 0.1), 0.0);
  EXPECT_TRUE(find_candidates(t, strict, start, {}, p).empty());
}

TEST(Nbv, CandidateGridGivesSeveralPositionsPerLargeOctant) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  NbvParams p;
  p.candidate_spacing = 0.4;
  const auto got = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  // The coarse voxel [1.6, 2.4)² at scanner height is one empty octant.
  int inside = 0;
  for (const Point3& c : got) inside += c.x > 1.6 && c.x < 2.4 && c.y > 1.6 && c.y < 2.4;
  EXPECT_EQ(inside, 4);
  // World-aligned grid at leaf centres, 0.4 m apart.
  for (const Point3& c : got) {
    EXPECT_NEAR(std::remainder(c.x - 0.225, 0.4), 0.0, 1e-9);
    EXPECT_NEAR(std::remainder(c.y - 0.225, 0.4), 0.0, 1e-9);
  }
  // 4 × 4 m with walls (leaf cells 0 and 79), clearance 10.5 cells: cells
  // 12, 20, ..., 68 (x, y = 0.625 ... 3.425): 8 × 8.
  EXPECT_EQ(got.size(), 64u);
}

TEST(Nbv, CandidateGridPassesThroughItsAnchor) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  NbvParams p;
  p.candidate_spacing = 0.4;
  const std::vector<Point3> fixed = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  p.grid_anchor = Point3(1.93, 2.11, 1.5);  // leaf cell centre (1.925, 2.125)
  const std::vector<Point3> got = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  EXPECT_TRUE(has_candidate_near(got, 1.925, 2.125));
  EXPECT_FALSE(has_candidate_near(fixed, 1.925, 2.125));
  for (const Point3& c : got) {
    EXPECT_NEAR(std::remainder(c.x - 1.925, 0.4), 0.0, 1e-9);
    EXPECT_NEAR(std::remainder(c.y - 2.125, 0.4), 0.0, 1e-9);
  }
  // Clear from 0.625 to 3.425 (see above): x 0.725 ... 3.125 (7), y 0.925 ... 3.325 (7).
  EXPECT_EQ(got.size(), 49u);
  p.grid_anchor = Point3(-1e6, 0, 0);  // beyond OctoMap's key range
  EXPECT_THROW(find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p), std::invalid_argument);
}

TEST(Nbv, UnreachablePocketOfFreeFloorGivesNoCandidates) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  // A closet [2.4, 4) × [2.4, 4) walled off to the ceiling.
  m.leaves({2.4, 2.4, 0}, {2.45, 4.0, 2.4}, Label::kOccupied);
  m.leaves({2.4, 2.4, 0}, {4.0, 2.45, 2.4}, Label::kOccupied);
  NbvParams p;
  p.candidate_spacing = 0.1;
  auto in_closet = [](const Point3& c) { return c.x > 2.4 && c.y > 2.4; };
  CandidateReport rep;
  const auto outside = find_candidates(m.t, RobotGeometry{}, {1.0, 1.0, 0}, {}, p, &rep);
  EXPECT_FALSE(outside.empty());
  EXPECT_GT(rep.unreachable, 0u);
  for (const Point3& c : outside) EXPECT_FALSE(in_closet(c)) << c.x << ", " << c.y;
  // From inside the closet only the closet is reachable.
  const auto inside = find_candidates(m.t, RobotGeometry{}, {3.2, 3.2, 0}, {}, p);
  EXPECT_FALSE(inside.empty());
  for (const Point3& c : inside) EXPECT_TRUE(in_closet(c)) << c.x << ", " << c.y;
  // A robot outside the map has nowhere to go.
  const auto lost = find_candidates(m.t, RobotGeometry{}, {9.0, 9.0, 0}, {}, p, &rep);
  EXPECT_TRUE(lost.empty());
  EXPECT_FALSE(rep.robot_in_map);
}

// Each candidate's path from the robot: in an open room about the straight line
// (within the 8 % an 8-connected grid adds at worst, and the half leaves between the
// robot's cell centre and the robot); behind a partition, around its end.
TEST(Nbv, CandidatePathsGoAroundObstacles) {
  Map m(6, 5, 3);
  m.walls(4.8, 4.0, 2.4);
  NbvParams p;
  p.candidate_spacing = 0.2;
  RobotGeometry robot;
  robot.radius = 0.3;
  const Point3 start(1.0, 1.0, 0);
  std::vector<double> open_path;
  const std::vector<Point3> open = find_candidates(m.t, robot, start, {}, p, nullptr, &open_path);
  ASSERT_EQ(open.size(), open_path.size());
  ASSERT_GT(open.size(), 50u);
  const double slack = kLeaf;  // the robot's cell centre is up to a leaf·√2/2 off
  for (std::size_t i = 0; i < open.size(); ++i) {
    const double line = std::hypot(open[i].x - start.x, open[i].y - start.y);
    EXPECT_GE(open_path[i], line - slack) << open[i].x << ", " << open[i].y;
    EXPECT_LE(open_path[i], 1.0824 * line + slack) << open[i].x << ", " << open[i].y;
  }
  // A full-height partition at x ∈ [2.4, 2.45) from y = 0 to 3.0: the robot at x = 1 must
  // go round its end (y > 3.0 + radius) to reach x = 3.6.
  m.leaves({2.4, 0, 0}, {2.45, 3.0, 2.4}, Label::kOccupied);
  std::vector<double> path;
  RouteTree routes;
  const std::vector<Point3> behind =
      find_candidates(m.t, robot, start, {}, p, nullptr, &path, &routes);
  bool checked = false;
  for (std::size_t i = 0; i < behind.size(); ++i) {
    const Point3& c = behind[i];
    if (c.x < 3.5 || c.y > 1.5) continue;  // behind the partition, low down
    // At least up to the end of the partition (clear of it by the radius) and back down.
    const double round_end = std::hypot(2.425 - start.x, 3.0 + robot.radius - start.y) +
                             std::hypot(c.x - 2.425, 3.0 + robot.radius - c.y);
    EXPECT_GE(path[i], round_end - 2 * slack) << c.x << ", " << c.y;
    // The route: from the robot's cell to the candidate, as long as the path, round the
    // partition's end, never across it.
    const std::vector<Point3> route = routes.route_to(c);
    ASSERT_GE(route.size(), 3u);
    EXPECT_LE(std::hypot(route.front().x - start.x, route.front().y - start.y), kLeaf);
    EXPECT_EQ(route.back().x, c.x);
    EXPECT_EQ(route.back().y, c.y);
    double length = 0, highest = 0;
    for (std::size_t k = 0; k + 1 < route.size(); ++k) {
      const Point3 &a = route[k], &b = route[k + 1];
      length += std::hypot(b.x - a.x, b.y - a.y);
      highest = std::max(highest, b.y);
      if ((a.x < 2.425) != (b.x < 2.425)) {  // crosses the partition's line: above its end
        const double y = a.y + (b.y - a.y) * (2.425 - a.x) / (b.x - a.x);
        EXPECT_GT(y, 3.0 + robot.radius - slack);
      }
    }
    EXPECT_NEAR(length, path[i], 1e-3);
    EXPECT_GT(highest, 3.0 + robot.radius - slack);
    checked = true;
  }
  EXPECT_TRUE(checked);
  // A position not reached, or off the plane, has no route.
  EXPECT_TRUE(routes.route_to(Point3(100, 100, 0)).empty());
  EXPECT_TRUE(routes.route_to(Point3(2.425, 1.0, 0)).empty());  // in the partition
}

TEST(Nbv, BlindZoneUnderPastScansIsNotAnObstacle) {
  const auto tree = discretize(room_with_pillar(), 2.4, {0.05, 0.8});
  const Point3 scan(1.0, 2.0, 1.5);
  study_occlusion(*tree, {ScannerView{scan}});  // default limits: blind below −60°
  // The occlusion study did label the cone under the scanner occluded.
  ASSERT_EQ(tree->find_octant(Point3(1.0, 2.0, 0.3))->label(), Label::kOccluded);
  NbvParams p;
  p.candidate_spacing = 0.1;
  CandidateReport rep;
  const auto with_rule = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p, &rep);
  EXPECT_GT(rep.blind_octants_freed, 0u);
  ASSERT_FALSE(with_rule.empty());
  // The robot can move off the spot it scanned from, and candidates close to
  // it are feasible: nearer than the cone's floor radius (0.87 m) plus the
  // robot's radius, which would be the limit if the cone were an obstacle.
  // (Within 0.6 m the scanner-height octant itself is in the minimum-range
  // sphere, not empty, so no candidate.)
  double nearest = 1e9;
  for (const Point3& c : with_rule) nearest = std::min(nearest, std::hypot(c.x - 1.0, c.y - 2.0));
  EXPECT_LT(nearest, 0.8);
  // The pillar's real shadow is still an obstacle: nothing right behind it.
  for (const Point3& c : with_rule)
    EXPECT_FALSE(c.x > 2.6 && c.x < 3.4 && c.y > 1.8 && c.y < 2.2) << c.x << ", " << c.y;
  // The paper's rule alone: the cone around the robot encloses it.
  p.blind_zone_is_free = false;
  EXPECT_TRUE(find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p).empty());
  // And a blind zone of another scan position does not free this one's.
  p.blind_zone_is_free = true;
  EXPECT_TRUE(
      find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {Point3(3.0, 3.2, 1.5)}, p).empty());
}

// The robot stood where it scanned: nothing but the robot stood in its cylinder there,
// so occluded or unknown octants within its radius of a past scan position are no
// obstacle, whatever the scan saw of them (a coarse octant at its feet, judged occluded
// from its sample points). Their part beyond the radius still is; occupied leaves always.
TEST(Nbv, TheRobotsOwnFootprintAtPastScansIsNoObstacle) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  m.leaves({2.0, 1.6, 0.3}, {2.35, 1.95, 0.65}, Label::kOccluded);  // 0.35 m, a corner at the robot
  NbvParams p;
  p.candidate_spacing = 0.1;
  p.blind_zone_is_free = false;  // this rule alone
  RobotGeometry robot;
  robot.radius = 0.408;
  const Point3 start(2.0, 2.0, 0);
  const Point3 scanned_here(2.0, 2.0, robot.scanner_height);
  // Without the position it scanned from, the block boxes the robot in.
  EXPECT_TRUE(find_candidates(m.t, robot, start, {}, p).empty());
  const auto freed = find_candidates(m.t, robot, start, {scanned_here}, p);
  ASSERT_FALSE(freed.empty());
  // The block's corner beyond the robot's radius is still an obstacle: no candidate's
  // cylinder reaches its farthest leaf (its centre 0.50 m from the robot).
  for (const Point3& c : freed)
    EXPECT_GT(std::hypot(c.x - 2.325, c.y - 1.625), robot.radius + 0.5 * kLeaf)
        << c.x << ", " << c.y;
  // An occupied block there (a return fell in it) stays an obstacle.
  Map occupied(5, 5, 3);
  occupied.walls(4.0, 4.0, 2.4);
  occupied.leaves({2.0, 1.6, 0.3}, {2.35, 1.95, 0.65}, Label::kOccupied);
  EXPECT_TRUE(find_candidates(occupied.t, robot, start, {scanned_here}, p).empty());
}

// A pruned map (siblings with one label merged, as every occlusion study
// leaves it) frees the same blind zone as the map before pruning: the rule must not
// depend on how the cone is subdivided.
TEST(Nbv, BlindZoneRuleGivesTheSameCandidatesOnAPrunedMap) {
  const auto tree = discretize(room_with_pillar(), 2.4, {0.05, 0.8});
  const Point3 scan(1.0, 2.0, 1.5);
  OcclusionParams unmerged;
  unmerged.prune = false;
  study_occlusion(*tree, {ScannerView{scan}}, unmerged);
  NbvParams p;
  p.candidate_spacing = 0.1;
  const auto before = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p);
  ASSERT_FALSE(before.empty());
  const std::size_t nodes = tree->calcNumNodes();
  tree->prune();
  ASSERT_LT(tree->calcNumNodes(), nodes);  // blind leaves did merge
  CandidateReport rep;
  const auto after = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p, &rep);
  EXPECT_GT(rep.blind_octants_freed, 0u);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].x, before[i].x);
    EXPECT_EQ(after[i].y, before[i].y);
  }
}

// An imported map's unknown specks (enclosed_speck_leaves): a leaf or two of unknown or
// occluded space with free space on every side (or the floor under it) does not block
// the cylinder; a larger unknown block, or one touching an obstacle, still does. Off by
// default (the survey's own maps).
TEST(Nbv, EnclosedUnknownSpecksDoNotBlockTheCylinder) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  m.leaf(2.025, 2.025, 1.025, Label::kUnknown);                    // a speck in mid-air
  m.leaves({2.0, 2.0, 0.5}, {2.1, 2.05, 0.55}, Label::kOccluded);  // two leaves
  m.leaf(2.025, 2.025, 0.025, Label::kOccupied);                   // the floor's leaf …
  m.leaf(2.025, 2.025, 0.075, Label::kUnknown);                    // … and a speck on it
  m.leaves({1.0, 3.0, 0.5}, {1.15, 3.15, 0.65}, Label::kUnknown);  // 3 leaves a side
  m.leaves({3.0, 1.0, 1.0}, {3.05, 1.05, 1.1}, Label::kUnknown);   // on a box's top:
  m.leaf(3.025, 1.025, 0.975, Label::kOccupied);
  NbvParams p;
  p.candidate_spacing = 0.1;
  RobotGeometry robot;
  robot.radius = 0.3;
  const Point3 start(1.0, 1.0, 0);
  CandidateReport off, on;
  const auto strict = find_candidates(m.t, robot, start, {}, p, &off);
  EXPECT_EQ(off.specks_freed, 0u);
  EXPECT_FALSE(has_candidate_near(strict, 2.05, 2.05, 0.06));
  p.enclosed_speck_leaves = 2;
  const auto freed = find_candidates(m.t, robot, start, {}, p, &on);
  EXPECT_EQ(on.specks_freed, 4u);  // 1 + 2 + 1 leaves
  EXPECT_TRUE(has_candidate_near(freed, 2.05, 2.05, 0.06));
  EXPECT_FALSE(has_candidate_near(freed, 1.05, 3.05, 0.06));  // the 3-leaf block
  EXPECT_FALSE(has_candidate_near(freed, 3.05, 1.05, 0.06));  // the box
  EXPECT_GT(freed.size(), strict.size());
}

}  // namespace
}  // namespace semioctree
