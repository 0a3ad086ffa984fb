// Internal: the blind zone of past scan positions (docs/nbv.md, "Blind zone of
// past scans").
#pragma once

#include <cstdint>
#include <vector>

#include "../scanner_limits.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

// Whether the part of `o` within the leaf layers [z_lo, z_hi] (leaf-cell indices, as
// leaf_cell gives them; the layers the safety cylinder spans) is blind: all its sample
// points (the centre of that part and, above one leaf, the centres of its 8 corner
// leaves) lie in the blind zone (closer than the minimum range or below the minimum
// elevation of `limits`) of some scanner in `scans`. Only that part matters to the
// cylinder: a coarse octant reaching above the robot's head (where the scanner's upper
// elevation limit hides it) is judged by what lies beside the robot.
bool blind_octant(const Octant& o, unsigned leaf_level, std::int64_t z_lo, std::int64_t z_hi,
                  const std::vector<Point3>& scans, const detail::ScannerLimits& limits);

}  // namespace semioctree::nbv_detail
