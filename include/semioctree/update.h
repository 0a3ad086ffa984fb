// Stage 8 (paper 2.3): the map carried from scan to scan. The first scan is
// discretized, its doors and windows found and its octants classified; each
// later scan, registered into the same (survey) frame, refines that map
// instead of rebuilding it: the coarse grid grows over new ground (new voxels
// unknown), its points make their leaves occupied (the finer resolution wins),
// openings are detected again on the merged cloud and replace the map's doors
// and windows, space new to the map (and the leaves of openings no longer
// found) is classified from every position, and only what is still occluded or
// out is re-tested, from the new position (its direct view wins). Space whose
// classification depended on an opening that came or went is tested again:
// out space from every position when an opening shrank or went, empty space
// when one grew or came (what is seen only through it becomes out). Because the coarse
// grid is fixed to the world, the voxels of every scan coincide.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/occlusion.h"
#include "semioctree/openings.h"
#include "semioctree/preprocess.h"

namespace semioctree {

struct SurveyMapParams {
  DiscretizeParams grid;
  ScannerView limits;  // range and elevation limits of the scanner (position unused)
  OpeningParams openings;
  // The merged cloud (registration target, openings input, cloud.ply) keeps
  // one point per cell of this size, so it does not grow with every scan.
  double merged_spacing = 0.02;
  unsigned threads = 0;  // occlusion study threads (0: one per core)
  // The occlusion study's octants: judged by their 9 samples (the paper's test) or proven
  // whole (OcclusionParams::exact_octants: right behind thin occluders, slower).
  bool exact_octants = false;
};

struct ScanUpdateReport {
  std::size_t scan_index = 0;
  std::size_t new_coarse_voxels = 0;
  std::size_t occupied_leaves = 0;  // distinct leaves of this scan's points
  OpeningsReport openings;
  std::size_t openings_found = 0;
  // Later scans: door and window octants of the map that lie in no opening
  // found now (their space, and all out space, is decided again in new_space),
  // and whether the openings found now take leaves that were no opening before.
  std::size_t opening_octants_dropped = 0;
  bool opening_leaves_added = false;
  OcclusionReport new_space;  // unknown octants, from every position (later scans)
  OcclusionReport retest;     // first scan: everything; later: occluded/out from the new position
  // Later scans whose openings took new leaves: empty octants from every
  // position, those seen only through an opening becoming out.
  OcclusionReport through_openings;
  double seconds_occupancy = 0, seconds_openings = 0, seconds_occlusion = 0;
};

// The returns of one scan (points in the scanner's own frame, optical centre
// at the origin) that lie within the scanner's range and elevation limits;
// `dropped` counts the others. A real scanner also records its own mount and
// the robot's body (closer than the minimum range, below the lowest elevation
// that clears the robot). The occlusion study takes that space as unseen;
// mapped, such returns would be occupied leaves in the robot's own cylinder,
// and their shadows occluded space all around it.
// Returns `scan` itself when every point is within the limits (no copy).
Cloud::Ptr within_limits(const Cloud::Ptr& scan, const ScannerView& limits,
                         std::size_t* dropped = nullptr);

class SurveyMap {
 public:
  explicit SurveyMap(const SurveyMapParams& params);

  // Adds one scan: `points` levelled (floor at z = 0) and registered into the
  // survey frame, `scanner` its optical centre there. The first scan's
  // `ceiling_height` fixes the map's height; later calls' value is not used and
  // their points above it are left out. `returns`: the directions in which the
  // scan got returns (return_directions of the whole scan, floor included),
  // which the occlusion study then keeps to; null: every direction.
  ScanUpdateReport add_scan(const Cloud& points, const Point3& scanner, double ceiling_height,
                            std::shared_ptr<const ReturnDirections> returns = nullptr);

  bool empty() const { return !tree_; }
  // The map and the merged cloud: std::logic_error before the first add_scan.
  const SemiOcTree& tree() const;
  SemiOcTree& tree();
  const Cloud& merged_cloud() const;
  const std::vector<Point3>& scanners() const { return scanners_; }
  const std::vector<DetectedOpening>& openings() const { return openings_; }
  double ceiling_height() const { return ceiling_; }
  std::vector<ScannerView> views() const;
  // The side from which the scans saw the surface at `point` with normal `normal` (either
  // sign; survey frame): +1 along the normal, -1 against it, 0 when the map holds space
  // seen free (or seen through an opening) both a leaf and a half and three and a half
  // leaves away on both sides or on neither (SurfaceFacing::target_side). 0 before the
  // first scan.
  int seen_side(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) const;
  const SurveyMapParams& params() const { return params_; }

 private:
  SurveyMapParams params_;
  std::unique_ptr<SemiOcTree> tree_;
  Cloud::Ptr merged_;
  std::vector<Point3> scanners_;
  std::vector<std::shared_ptr<const ReturnDirections>> returns_;  // one per scanner
  std::vector<DetectedOpening> openings_;
  double ceiling_ = 0;
};

}  // namespace semioctree
