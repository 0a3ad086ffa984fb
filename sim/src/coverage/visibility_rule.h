// The parts of the visibility rule (semioctree/sim/coverage/visibility.h) that the
// reference and the miss analysis evaluate themselves, sample by sample (internal).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "semioctree/sim/coverage/visibility.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"

namespace semioctree::sim::detail {

// The scanner's range and elevation limits, as tested before any ray is cast.
struct ScannerLimits {
  double min_range, max_range;
  double sin_el_min, sin_el_max;  // limits on (p.z − c.z) / |p − c|
};

inline ScannerLimits scanner_limits(const ScannerConfig& s) {
  auto sin_deg = [](double deg) {
    const double clamped = std::clamp(deg, -90.0, 90.0);
    return std::sin(clamped * M_PI / 180.0);
  };
  return {s.min_range, s.max_range, sin_deg(s.elevation_min_deg), sin_deg(s.elevation_max_deg)};
}

// True if `sample` passes the range, elevation and facing tests from optical centre `c`.
inline bool within_limits(const ScannerLimits& lim, const SurfaceSample& sample,
                          const Eigen::Vector3d& c) {
  const Eigen::Vector3d v = c - sample.position;  // sample → scanner
  if (sample.normal.dot(v) <= 0) return false;
  const double r2 = v.squaredNorm();
  if (r2 < lim.min_range * lim.min_range || r2 > lim.max_range * lim.max_range) return false;
  const double r = std::sqrt(r2);
  const double sin_el = -v.z() / r;  // elevation of the sample seen from the scanner
  return sin_el >= lim.sin_el_min - 1e-12 && sin_el <= lim.sin_el_max + 1e-12;
}

// The end of the segment that the rule tests from the optical centre.
inline Eigen::Vector3d segment_target(const SurfaceSample& sample) {
  return sample.position + kCoverageSampleOffset * sample.normal;
}

// The segment from `c` to the sample's segment_target crosses no geometry.
inline bool line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                          const Eigen::Vector3d& c) {
  return truth.segment_free(c, segment_target(sample));
}

}  // namespace semioctree::sim::detail
