// Stage 4 (paper 2.2.2): doors and windows. Walls are found as vertical RANSAC
// planes and rasterised; rectangular holes of door or window size are
// candidates, confirmed only when enough of their cells are seen directly from
// a scanner position (else they are shadows), then labelled door / window.
// The rules and their reasons: docs/occlusion.md.
#pragma once

#include <octomap/OcTree.h>

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/scan_io.h"

namespace semioctree {

struct OpeningParams {
  // --- walls (RANSAC, PCL SACMODEL_PARALLEL_PLANE about z) ---
  double ransac_distance = 0.03;     // inlier distance to the plane, m
  double max_normal_tilt_deg = 5.0;  // a wall's normal is within this of horizontal
  int ransac_iterations = 500;
  // RANSAC runs on a random subset this large. Whether it finds a plane depends on the
  // plane's share of the points (500 draws of 3 find a share of 0.15 with probability
  // 0.82), not on the subset's size, which only sets how well the shares are counted:
  // ±0.4 % (one standard error) at a share of 0.2 with 10 000 points.
  std::size_t ransac_sample = 10000;
  std::size_t min_plane_points = 500;      // smaller planes end the search
  int max_planes = 20;                     // planes searched at most
  double min_wall_length = 1.5;            // a wall segment is at least this long, m
  double min_wall_height_fraction = 0.75;  // its points span this share of the room height
  // Columns empty over this length split a plane, m: empty at every height between the
  // floor's band (floor_tolerance) and the ceiling's (min_lintel), which the cuts of
  // floor and ceiling leave a few returns in all along the plane.
  double wall_split_gap = 0.5;
  // Not in the paper: share of a wall segment's grid (floor to ceiling) that
  // must hold points. A vertical plane through scattered furniture (a column,
  // a bench's side, a screen) spans the room's height too, but is mostly
  // empty, and its gaps would pass for doors.
  double min_wall_fill = 0.5;

  // --- wall grid ---
  double cell = 0.0;        // grid cell side, m (0: the tree's leaf size)
  int min_cell_points = 1;  // a cell with at least this many points is occupied

  // Wall left between a door's or a window's top and the ceiling, m. A hole whose top
  // row is the ceiling's own band (the returns of the ceiling that its cut left, a few
  // cm under it) is open above, not enclosed: beyond the inner corner of an L-shaped
  // room a wall's plane runs on through open space from floor to ceiling.
  double min_lintel = 0.1;

  // --- doors: holes reaching the floor ---
  double door_min_width = 0.6, door_max_width = 2.5;    // m
  double door_min_height = 1.8, door_max_height = 2.6;  // m
  double floor_tolerance = 0.1;  // a door's bottom is at most this above the floor, m

  // --- windows: holes with a sill, ending below the ceiling ---
  double window_min_width = 0.4, window_max_width = 4.0;    // m
  double window_min_height = 0.4, window_max_height = 2.5;  // m
  double window_min_sill = 0.3;                             // m above the floor

  // --- confirmation by line of sight ---
  double los_min_fraction = 0.85;  // share of the hole's cells seen directly (paper: 85 %)
  // Not in the paper: a hole partly hidden by something standing in front of
  // it (a door whose lower half is behind a bench) fails the 85 % rule although
  // what is seen of it is seen through. It is still confirmed when at least this
  // share of its cells is seen directly and the seen cells reach the hole's left
  // and right sides and its top (a window: also its bottom), so that the
  // rectangle is fixed by what is seen and not by the shadow. A pure shadow is
  // seen through nowhere and stays rejected. 0 turns the rule off (paper only).
  double partly_hidden_min_los = 0.4;
  // A LOS ray ends this far (in leaf sizes) in front of the wall plane, measured
  // along the wall's normal, so that the occupied leaves of the wall's surface
  // at the rim of the hole (they reach up to a leaf in front of the plane) do
  // not count as obstacles, however obliquely the ray comes in.
  double los_end_margin_leaves = 1.5;
  // A scanner nearer the wall's plane than this (a scan taken in one of the
  // wall's doorways) does not confirm that wall's holes: it sees the wall
  // edge-on, and its lines along the face would confirm any shadow, m.
  double los_min_scanner_off_wall = 0.3;

  // --- one hole, two faces ---
  // A hole through a wall is found on both faces once a scan stood beyond the wall.
  // Parallel planes nearer than this are taken as the two faces of one wall: the thickest
  // walls of the buildings surveyed; two walls with a passage between them (a corridor)
  // stand farther apart, as a robot passes between them, m.
  double max_wall_thickness = 0.6;
};

enum class OpeningKind { kDoor, kWindow };
const char* to_string(OpeningKind kind);  // "door" / "window"
Label label_of(OpeningKind kind);         // Label::kDoor / Label::kWindow

struct DetectedOpening {
  OpeningKind kind = OpeningKind::kDoor;
  // World (levelled) frame, in the wall plane: bottom-near, bottom-far,
  // top-far, top-near ("near" = smaller coordinate along the wall).
  std::array<Eigen::Vector3d, 4> corners;
  // The centre of its rectangle.
  Eigen::Vector3d centre() const {
    return 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
  }
  double width = 0, height = 0;  // m
  double sill = 0;               // bottom above the floor, m (≈ 0 for doors)
  double los_fraction = 0;       // share of its cells with direct LOS from a scanner
  Eigen::Vector3d wall_normal = Eigen::Vector3d::Zero();  // unit, horizontal
  int wall = -1;                                          // index into OpeningsReport::walls
};

// A wall segment that was rasterised.
struct DetectedWall {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, horizontal
  double offset = 0;                                 // plane: normal·p + offset = 0
  Eigen::Vector3d u_axis = Eigen::Vector3d::Zero();  // along the wall
  double u_min = 0, u_max = 0;                       // extent along u_axis, m
  std::size_t points = 0;
};

struct OpeningsReport {
  std::vector<DetectedWall> walls;
  std::size_t candidates = 0;             // holes of door or window size
  std::vector<DetectedOpening> rejected;  // candidates failing the LOS test
  std::size_t los_rays = 0;               // segments cast for the LOS test
  std::size_t far_faces = 0;  // openings found again on the far face of their wall, dropped
};

// `levelled` has the floor at z = 0 and floor/ceiling points removed (see
// preprocess); `tree` is its occupancy analysis (see discretize). Openings
// overlapping a larger confirmed one on the same wall are dropped. A scanner's line
// confirms a cell only within its range and elevation limits (ScannerView; its returns
// are not used: a window onto the open sky gives none, and is still an opening).
std::vector<DetectedOpening> detect_openings(const Cloud& levelled, double ceiling_height,
                                             const SemiOcTree& tree,
                                             const std::vector<ScannerView>& scanners,
                                             const OpeningParams& params = {},
                                             OpeningsReport* report = nullptr);
// The same for scanners known by their positions alone: no limits.
std::vector<DetectedOpening> detect_openings(const Cloud& levelled, double ceiling_height,
                                             const SemiOcTree& tree,
                                             const std::vector<Point3>& scanner_positions,
                                             const OpeningParams& params = {},
                                             OpeningsReport* report = nullptr);

// The ceiling of a map that holds no points (an OctoMap occupancy map imported
// with from_occupancy_octree), its floor at z = 0: the centre height of the
// layer of leaves above `min_height` holding the most occupied leaves. Nullopt
// when the map has no floor layer (no occupied leaves within a leaf of z = 0),
// or no layer above `min_height` holds a quarter as many as the floor's.
std::optional<double> map_ceiling_height(const SemiOcTree& tree, double min_height = 2.0);

// detect_openings for such a map: the centres of its occupied leaves stand for
// the points, without the floor's and the ceiling's layers (as preprocess
// removes their points). With the default cell size the wall grid's cells are
// the map's leaves, one point each; walls take inliers within at least a leaf.
std::vector<DetectedOpening> detect_openings_in_map(const SemiOcTree& tree, double ceiling_height,
                                                    const std::vector<Point3>& scanner_positions,
                                                    const OpeningParams& params = {},
                                                    OpeningsReport* report = nullptr);

// The share of an opening's rectangle through which an occupancy map (OctoMap: only
// rays that returned carve free space) holds free space just behind the wall: sampled at
// half-leaf steps over the rectangle, 1.5 and 2.5 leaves beyond its plane on the side
// away from the scanners, a sample counts if either point is a free node. Rays that went
// through a real opening carved the space in and behind it; behind a wall's shadow, or a
// gap that sparse rays left in a wall's surface, the map holds nothing (docs/occlusion.md).
double share_carved_behind(const DetectedOpening& opening, const octomap::OcTree& map,
                           const std::vector<Point3>& scanner_positions);

// Labels the leaf octants that the hole's rectangle passes through door or
// window; occupied leaves (the points of a jamb) keep their label. Returns the
// number of leaves labelled.
std::size_t label_openings(SemiOcTree& tree, const std::vector<DetectedOpening>& openings);

}  // namespace semioctree
