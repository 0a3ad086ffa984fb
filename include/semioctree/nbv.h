// Stages 6–7 (paper 2.2 "NBV calculation", Eq 3–5): Next-Best-View candidates,
// their scores and the stop percentage.
//
// Candidates. A world-aligned grid of positions (spacing `candidate_spacing`,
// at the centres of leaf cells, through NbvParams::grid_anchor if given) on the
// horizontal plane at scanner height; a
// grid point is a candidate when
//  * the octant holding (x, y, scanner height) is `empty` (or a `scan`/`nbv`
//    marker): inside the surveyed room, not `out`, `door`, `window`, occluded;
//  * its safety cylinder (robot radius, from the floor to the top of the
//    scanner) holds no obstacle: occupied, occluded or unknown space (also
//    space without a coarse voxel, and outside the map). Obstacles lying wholly
//    below RobotGeometry::ground_clearance, or wholly in the floor's own leaf
//    layer z ∈ [0, leaf) when the leaf is larger (floor_layer_clearance), are
//    driven over. An obstacle leaf
//    cell is inside the cylinder when its centre is within radius + leaf/2 of
//    the axis, horizontally. Because the cylinder is vertical, an obstacle is
//    inside it exactly when the obstacle's column (projected on the floor) is,
//    so the test runs on a 2-D obstacle map at leaf resolution (cell =
//    obstacle anywhere in z ∈ [clearance, top)) with dynamicEDT3D's
//    DynamicEDT3D (one z layer): one distance look-up per grid cell instead of
//    a 3-D distance field of the whole room (24 B per voxel, and an OcTree
//    with the occluded space expanded to the leaves for DynamicEDTOctomap);
//  * it is reachable: 4-connected flood fill over the cells whose cylinder is
//    clear (the robot's configuration space), seeded at the robot's current
//    position, whose own cell always counts as traversable.
// Large empty octants thus give several candidates (one per grid point); empty
// octants smaller than the spacing between grid points give none. The grid is
// the same for any coarse size, so a semioctree and a homogeneous grid of the
// same room get the same candidate positions. Default spacing 0.5 m (about
// the robot's radius): the scoring cost is linear in the number of
// candidates, and the lab after its first scan has 85 of them at 0.5 m
// (~5 CPU-seconds of scoring, ~2.5 s on two cores) against 124 at 0.4 m
// (~7.5 CPU-seconds), which would break the survey's time budget.
//
// Blind zone of past scans. The scanner sees nothing below its minimum
// elevation (−60°) nor within its minimum range, so the occlusion study labels
// a cone under every past scan position (and a small sphere around it)
// `occluded` although nothing hides it: it is unobserved, not shadowed, and
// the robot itself stood there. Rule: an occluded octant all of whose sample
// points (the centre; for octants above the leaf also the centres of its 8
// corner leaves, so that a merged octant is judged as its leaves were) lie in
// the blind zone (elevation below the minimum, or closer than the minimum
// range) of some past scan position is not an obstacle for the cylinder.
// Occupied space is always an obstacle, and occluded space with any sample
// outside every blind zone (a real shadow) is too. The blind zone still counts as occluded for the
// score and the stop percentage.
//
// Score (Eq 3–4). For a scanner at position p and each occluded target t
// (segment p → centre of t, traversed through the SemiOcTree):
//   S = 1          nothing occluded or occupied crossed (direct LOS)
//   S = 1/(1+n)    n occluded octants crossed, nothing occupied
//   S = 0          an occupied or unknown octant is crossed; or the line passes
//                  through a `door` or `window` octant (our reading: the target
//                  would then be seen from outside the room, i.e. become `out`,
//                  which does not complete the room); or the target is outside
//                  the scanner's range/elevation limits (ScannerView).
// The scanner's own octant neither blocks nor counts (as in the occlusion
// study), the target's own octant does not count; `out`, `empty`, `scan`,
// `nbv` octants are transparent.
//  * Method 1: every occluded octant is a target at its own size, weighted by
//    its volume in leaf cells (an octant scores 8× its child); n counts
//    occluded octants crossed at their own size.
//  * Method 2 (level ℓ, default the leaf): the map is read as a uniform grid of
//    level-ℓ cells ("the resolution is considered uniform"), every target
//    weighs 1. A bigger occluded octant is 8^(ℓ−level) targets (the centres of
//    its level-ℓ sub-cells); a level-ℓ cell split into finer octants is one
//    target when it holds no occupied leaf and at least half its volume is
//    occluded. n counts the level-ℓ cells crossed that hold occluded space on
//    the line (a bigger octant contributes the level-ℓ cells the line crosses
//    inside it, counted with the traversal's own crossing formula). Blocking
//    still uses the finest information (the occupied leaves the line actually
//    hits). At ℓ = leaf this is the score of the same map stored as a
//    homogeneous grid (tested; up to lines passing exactly through cell edges).
//    It costs one segment per level-ℓ cell of occluded space: at the leaf, as
//    much as the homogeneous grid (the paper: "the smaller the octant size of
//    the selected level, the longer the processing time").
//  * Method 3 (ours; surface instead of volume): the targets are the occluded
//    octants with a face on free space (empty, scan, nbv) — the occlusion
//    frontier; the neighbour across a face is the octant holding the point a
//    quarter leaf beyond the face's centre. A target adds the area of its free
//    faces that face p (p beyond the face's plane) when the line to it is not
//    blocked, whatever occluded space it crosses (S = area, no 1/(1+n)): the
//    scanner looks through that face into the unseen space behind it, which
//    is where the surfaces not yet scanned are. Volume rewards deep shadows
//    near the floor (the floor is cut out of every scan) and hollow interiors;
//    the frontier holds ~1/6 of the occluded octants, so it is also cheaper.
// Scores are sums in a fixed order per candidate and candidates are scored
// independently (in parallel), so results do not depend on the thread count.
//
// Cost. One traversal per candidate–target pair within the scanner's limits,
// except for pairs proven blocked without one: a segment that passes through
// the interior of any blocking octant (occupied, unknown, door, window) scores
// 0 whatever else it crosses, so each candidate keeps the blockers it found,
// binned by direction, and each target the last two blockers found on lines
// to it from any candidate; a new pair is first tested against those (a slab
// test). This is exact (tested against a brute-force reference), only faster:
// in the lab ~2/3 of all pairs are settled so (targets behind walls, under
// furniture); the rest are traversed. Lines seen (direct or semi-direct) must
// be traversed to the end to count n, and they dominate the remaining time.
//
// Room. The map holds whatever the scans reached: through a window the lab's
// map spans a street and the next building (≈ 1 600 m³ against a 283 m³ room),
// and beyond every wall lies occluded space. Counted as targets, that space
// pulls the NBV towards walls it shows through unscanned wall parts (Eq 4
// still credits a line that crosses n occluded octants, and one 0.8 m octant
// beyond the wall weighs 512 leaves): after three lab scans 76 % of the NBV's
// expected volume lay outside the room, behind the west wall. In Eq 5's
// denominator it makes the stop percentage depend on the view out of the
// window. The paper's grid was about the room (its Table 1: 5.9 % out), so
// the survey counts the room only (NbvParams::room, from room_box).
//
// Stop percentage (Eq 5): volume of the occluded octants visible from the NBV
// / volume of occluded + empty + occupied + out octants × 100; door and window
// octants (empty space in the wall) count with empty, scan/nbv markers too;
// unknown space is not counted. "Visible" is weighted as in the score (our
// reading): an octant seen directly counts whole, one behind n occluded
// octants counts 1/(1+n) of its volume (it may or may not be seen), a blocked
// one nothing. So the numerator is the volume the NBV is expected to reveal —
// the NBV's method-1 score (leaf cells) times the leaf cell's volume.
// Counting every unblocked octant whole would charge the survey with all the
// space behind each surface not scanned yet (a wall seen nowhere hides the
// whole building behind it), which one more scan reveals only a layer of.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

// The surveyed room as an axis-aligned box (map frame): with NbvParams::room set,
// the score's targets and both volumes of Eq 5 are counted inside it only.
struct RoomBox {
  Point3 min, max;
  bool contains(const Point3& p) const;
  // Volume of the part of the cube of side `size` centred at `c` inside the box.
  double overlap(const Point3& c, double size) const;
};

// The room the scanners stand in, read from the map: a 4-connected flood fill
// over the leaf cells of the horizontal plane at `height` whose octant there is
// free (empty, scan, nbv), seeded at the scanners' cells; its bounding box,
// grown by one leaf on each side (the leaves of the room's own wall faces), from
// floor_z to ceiling_z. The fill stays in the room: doors and windows are
// labelled, what is seen through them is `out`, and walls are occupied.
// std::nullopt when no scanner's cell at that height is free.
std::optional<RoomBox> room_box(const SemiOcTree& tree, const std::vector<Point3>& scanners,
                                double height, double floor_z, double ceiling_z);

struct RobotGeometry {
  double radius = 0.5;          // safety cylinder radius, m
  double scanner_height = 1.5;  // optical centre above the floor, m
  double top_margin = 0.1;      // scanner head above the optical centre, m
  // Obstacles lying wholly below this height, or wholly in the floor's leaf
  // layer when the leaf is larger (floor_layer_clearance), are driven over (not
  // in the cylinder). The floor segmentation removes the points within 2σ of the
  // floor, i.e. ~95 % of them: the rest become scattered occupied leaves (and
  // their tiny shadows) in the lowest leaf layer, all over the floor.
  double ground_clearance = 0.05;  // m
  double top() const { return scanner_height + top_margin; }
};

struct NbvParams {
  static constexpr unsigned kLeafLevel = ~0u;
  int method = 1;               // 1: all levels, volume-weighted; 2: one level; 3: frontier surface
  unsigned level = kLeafLevel;  // method 2: the level ℓ (kLeafLevel: the tree's leaf)
  double candidate_spacing = 0.5;  // m, rounded to a whole number of leaves (≥ 1)
  // A point the candidate grid passes through: the leaf cell holding it (x, y; z
  // ignored) is a grid point. The survey anchors the grid at its first scan position, as
  // the coverage reference anchors its grid at the robot's start, so that the planner
  // chooses among the positions the reference (and `coverage-bound`) are defined on:
  // at 0.5 m the lab's fixed grid (below) has no candidate where that grid has them.
  // Empty: the grid points are the leaf cells ≡ m/2 (mod m), m = spacing in leaves.
  std::optional<Point3> grid_anchor;
  unsigned threads = 0;  // 0: one per core; results do not depend on it
  // Range and elevation limits of the scanner (position ignored): for the
  // score, the stop percentage and the blind zone of past scans.
  ScannerView limits;
  bool blind_zone_is_free = true;  // the blind-zone rule above (false: paper only)
  // The surveyed room (room_box): occluded space outside it is no target and
  // Eq 5 counts volumes inside it only; a method-1 target straddling its faces
  // weighs its part inside, methods 2 and 3 keep the targets centred inside.
  // Empty: the whole map, as the paper's formula reads. See "Room" above.
  std::optional<RoomBox> room;
  // Called after each candidate is scored with (candidates scored, candidates),
  // from the scoring threads: it must be thread-safe. Empty: no calls.
  std::function<void(std::size_t, std::size_t)> progress;
};

struct NbvCandidate {
  Point3 position;  // scanner position: (x, y) of the candidate, z = scanner height
  // Eq 3, in the method's unit: method 1 leaf cells of occluded volume (× leaf³ for
  // m³), method 2 level-ℓ cells, method 3 m² of frontier faces. Compare scores of
  // one method only.
  double score = 0;
};

struct CandidateReport {
  std::size_t grid_points = 0;  // grid points over the map
  std::size_t not_empty = 0;    // octant at scanner height not empty (or outside the map)
  std::size_t cylinder_blocked = 0;
  std::size_t unreachable = 0;
  std::size_t feasible = 0;
  std::size_t blind_octants_freed = 0;  // occluded octants exempted by the blind-zone rule
  bool robot_in_map = false;
};

struct ScoringStats {
  std::size_t targets = 0;           // occluded targets (method 2: level-ℓ cells)
  std::size_t segments = 0;          // candidate–target lines within the scanner's limits
  std::size_t blocked_by_cache = 0;  // of which found blocked without a traversal
  std::size_t visible = 0;           // of which not blocked (score > 0)
  double cpu_seconds = 0;            // CPU time of all scoring threads (hardly load-dependent)
};

struct NbvResult {
  std::optional<NbvCandidate> best;      // highest score (first in grid order on ties)
  std::vector<NbvCandidate> candidates;  // all feasible candidates, scored, in grid order
  CandidateReport candidate_report;
  ScoringStats scoring;
  double stop_percent = 0;  // from the best candidate; 0 when there is none
  double seconds_candidates = 0, seconds_scoring = 0, seconds_stop = 0;  // wall time
};

// The functions below throw std::invalid_argument for a method other than 1, 2
// or 3, a method-2 level finer than the tree's leaf, or a grid anchor beyond the key range.

// The height below which the candidate test drives over obstacles: the robot's
// ground clearance, or the leaf size if that is larger (0 for no clearance: then
// nothing is driven over). The floor's leaf layer
// holds what is left of the floor's points after the floor is cut (and all of
// them in an OctoMap map), and the map cannot tell an obstacle lower than a leaf
// from them: counted as obstacles, at a 0.1 m leaf they blocked every cylinder.
double floor_layer_clearance(const RobotGeometry& robot, double leaf_size);

// Feasible candidate positions (scanner positions, z = scanner height), in
// grid order (y, then x). `robot_position`: the robot on the floor (its z is
// ignored); `past_scans`: optical centres of the scans so far (blind zones).
std::vector<Point3> find_candidates(const SemiOcTree& tree, const RobotGeometry& robot,
                                    const Point3& robot_position,
                                    const std::vector<Point3>& past_scans, const NbvParams& params,
                                    CandidateReport* report = nullptr);

// Eq 3 score of each scanner position (any positions, feasible or not).
std::vector<double> score_positions(const SemiOcTree& tree, const std::vector<Point3>& positions,
                                    const NbvParams& params, ScoringStats* stats = nullptr);

// Candidates, scores, the best candidate and its stop percentage.
NbvResult next_best_view(const SemiOcTree& tree, const RobotGeometry& robot,
                         const Point3& robot_position, const std::vector<Point3>& past_scans,
                         const NbvParams& params = {});

// Eq 5 for a scanner at `nbv` (its optical centre), in percent; inside `room`
// only if given.
double stop_percentage(const SemiOcTree& tree, const Point3& nbv, const ScannerView& limits = {},
                       unsigned threads = 0, const std::optional<RoomBox>& room = std::nullopt);

}  // namespace semioctree
