// Internal: the blind zone of past scan positions (docs/nbv.md, "Blind zone of
// past scans").
#pragma once

#include <vector>

#include "../scanner_limits.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

// Whether all sample points of `o` (its centre; above the leaf level
// `leaf_level` also the centres of its 8 corner leaves) lie in the blind zone
// (closer than the minimum range or below the minimum elevation of `limits`) of
// some scanner in `scans`.
bool blind_octant(const Octant& o, unsigned leaf_level, const std::vector<Point3>& scans,
                  const detail::ScannerLimits& limits);

}  // namespace semioctree::nbv_detail
