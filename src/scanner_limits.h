// Internal: the scanner's range and elevation limits as a test on a segment, without a
// square root or trigonometry per segment; the occlusion study and the NBV share it.
#pragma once

#include <algorithm>
#include <cmath>

#include "semioctree/occlusion.h"

namespace semioctree::detail {

struct ScannerLimits {
  double min_range2, max_range2, sin_min, sin_max;
  explicit ScannerLimits(const ScannerView& v)
      : min_range2(v.min_range * v.min_range),
        max_range2(v.max_range * v.max_range),
        sin_min(std::sin(std::clamp(v.elevation_min_deg, -90.0, 90.0) * kDeg)),
        sin_max(std::sin(std::clamp(v.elevation_max_deg, -90.0, 90.0) * kDeg)) {}
  // b seen from a: a != b, within range, and sin_min <= dz / range <= sin_max.
  bool in_view(const Point3& a, const Point3& b) const {
    const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 < min_range2 || r2 > max_range2 || r2 == 0) return false;
    return at_least(dz, sin_min, r2) && at_least(-dz, -sin_max, r2);
  }
  // b in the blind zone of a scanner at a: nearer than the minimum range, or below the
  // lowest elevation.
  bool in_blind_zone(const Point3& a, const Point3& b) const {
    const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    return r2 < min_range2 || !at_least(dz, sin_min, r2);
  }
  // dz >= s * sqrt(r2)?
  static bool at_least(double dz, double s, double r2) {
    if (s <= 0) return dz >= 0 || dz * dz <= s * s * r2;
    return dz > 0 && dz * dz >= s * s * r2;
  }

 private:
  static constexpr double kDeg = M_PI / 180.0;
};

}  // namespace semioctree::detail
