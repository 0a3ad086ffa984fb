// Next-Best-View candidates: the grid positions the robot can scan from next
// (docs/nbv.md, "Candidates" and "Blind zone of past scans").
#pragma once

#include <cstddef>
#include <vector>

#include "semioctree/nbv/params.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct RobotGeometry {
  double radius = 0.5;          // safety cylinder radius, m
  double scanner_height = 1.5;  // optical centre above the floor, m
  double top_margin = 0.1;      // scanner head above the optical centre, m
  // Obstacles lying wholly below this height (or within the floor's leaf layer,
  // see floor_layer_clearance) are driven over: the remains of the cut floor.
  double ground_clearance = 0.05;  // m
  double top() const { return scanner_height + top_margin; }
};

struct CandidateReport {
  std::size_t grid_points = 0;   // grid points over the map
  std::size_t doorways = 0;      // NbvParams::doorways on the plane (tested as grid points are)
  std::size_t not_empty = 0;     // octant at scanner height not empty (or outside the map)
  std::size_t outside_area = 0;  // where NbvParams::may_stand forbids
  std::size_t cylinder_blocked = 0;
  std::size_t unreachable = 0;
  std::size_t already_scanned = 0;  // within a leaf of a past scan's optical centre
  std::size_t feasible = 0;
  std::size_t blind_octants_freed = 0;  // occluded octants exempted by the blind-zone rule
  std::size_t specks_freed = 0;  // leaves of enclosed specks (enclosed_speck_leaves) exempted
  bool robot_in_map = false;
};

// The height below which the candidate test drives over obstacles: the robot's
// ground clearance, or `leaf_size` if that is larger; 0 when the clearance is
// not > 0 (then nothing is driven over).
double floor_layer_clearance(const RobotGeometry& robot, double leaf_size);

// The robot's body around its scanner, for ReturnDirections::open_within: its safety
// cylinder from the floor-layer clearance up to its top.
PlatformBody platform_body(const RobotGeometry& robot, double leaf_size);

// The robot's shortest paths as find_candidates searched them, to trace its route to a
// position: the plane of leaf cells, each cell's previous one on its path.
struct RouteTree {
  double leaf = 0;
  std::int64_t x0 = 0, y0 = 0;  // cell (x, y) is leaf column (x + x0, y + y0)
  int nx = 0, ny = 0;
  std::int64_t start = -1;             // the robot's cell; -1: the robot is off the map
  std::vector<std::int32_t> previous;  // per cell; -1 at the start and where not reached

  // The route to `to` (x, y): the centres of the cells where it turns, the robot's cell
  // first and `to`'s last (z = to.z); empty if `to`'s cell was not reached.
  std::vector<Point3> route_to(const Point3& to) const;
};

// Feasible candidate positions (scanner positions, z = scanner height), in grid
// order (y, then x), then the feasible doorways (at their leaf cell's centre), on space seen free
// (and, with stand_beyond_openings, seen through an opening) where may_stand allows.
// `robot_position`: the robot on the floor (z ignored); `past_scans`: optical centres of the scans
// so far (their blind zones; and a grid point within a leaf of one is no candidate: in a static
// scene a scan from there would see again what that scan saw, whatever the scoring's targets say).
// Uses candidate_spacing, grid_anchor, limits, blind_zone_is_free, may_stand, stand_beyond_openings
// and doorways of `params`. `path_m` (if given) gets each candidate's shortest path from the robot
// over the cells its safety cylinder clears, m: steps between leaf cells, diagonal ones only where
// the robot does not cut a corner (docs/nbv.md, "Path"); `routes` (if given) the paths
// themselves. Throws std::invalid_argument for a radius < 0 or a scanner height <= 0, or a
// grid anchor beyond the key range.
std::vector<Point3> find_candidates(const SemiOcTree& tree, const RobotGeometry& robot,
                                    const Point3& robot_position,
                                    const std::vector<Point3>& past_scans, const NbvParams& params,
                                    CandidateReport* report = nullptr,
                                    std::vector<double>* path_m = nullptr,
                                    RouteTree* routes = nullptr);

}  // namespace semioctree
