// Stage 5 (paper 2.2.3): the occlusion study. Every non-occupied octant is
// classified from the scanner positions so far by ray casting through the
// SemiOcTree (octant-sized steps): the segment from a scanner to it crosses an
// occupied octant → occluded; it passes through a door or window and nothing
// occupied → out; otherwise → empty. An octant whose sample points (its centre
// and corners) disagree is partly visible and is split, down to the leaf, so
// the boundary between seen and unseen space is at leaf resolution while
// wholly visible or wholly hidden space stays coarse. A point is seen if any
// scanner sees it; the scanner's range and elevation limits apply.
#pragma once

#include <cstddef>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct ScannerView {
  Point3 position;                 // optical centre, map frame
  double min_range = 0.6;          // m
  double max_range = 60.0;         // m
  double elevation_min_deg = -60;  // 0 = horizontal
  double elevation_max_deg = 90;
};

enum class Visibility : std::uint8_t { kHidden = 0, kThroughOpening = 1, kDirect = 2 };

// Which octants a study (re)classifies.
enum class OcclusionScope : std::uint8_t {
  // Every empty, occluded, out or unknown octant, from all the views given.
  kAll,
  // Only unknown octants (space new to the map), from all the views given.
  kUnknown,
  // Only occluded and out octants, from the views given (the new scanner
  // positions), keeping what their label already says: occluded means hidden
  // from the earlier positions, out means seen through an opening. The direct
  // view from a new position wins, so out can become empty and occluded
  // anything (DESIGN.md stage 8).
  kNewViews,
  // Only empty octants: those seen through a door or window, and not directly,
  // become out; the rest stay empty. For a map whose free space was known
  // before its openings were labelled (an imported OctoMap map): what was seen
  // through them lies outside the room.
  kFreeThroughOpenings,
};

struct OcclusionParams {
  OcclusionScope scope = OcclusionScope::kAll;
  // Worker threads (0: one per core); the result is the same for any count.
  unsigned threads = 0;
  // Afterwards merge the siblings left with one label (SemiOcTree::prune):
  // labels and volumes are unchanged, in fewer octants. (The NBV scores count
  // per octant, so they see the merged octants.)
  bool prune = true;
};

struct OcclusionReport {
  std::size_t octants_tested = 0;
  std::size_t octants_split = 0;
  std::size_t segments = 0;                      // segments cast
  std::size_t empty = 0, occluded = 0, out = 0;  // leaf octants labelled (before merging)
};

// One view per scanner position, each with the range and elevation limits of `limits`
// (its position ignored).
std::vector<ScannerView> scanner_views(const std::vector<Point3>& positions,
                                       const ScannerView& limits);

// How well `p` is seen from the best of `views`.
Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p);

OcclusionReport study_occlusion(SemiOcTree& tree, const std::vector<ScannerView>& views,
                                const OcclusionParams& params = {});

}  // namespace semioctree
