#include "blind_zone.h"

#include <algorithm>
#include <cmath>

namespace semioctree::nbv_detail {

bool blind_octant(const Octant& o, unsigned leaf_level, const std::vector<Point3>& scans,
                  const detail::ScannerLimits& limits) {
  auto blind = [&](const Point3& p) {
    for (const Point3& s : scans)
      if (limits.in_blind_zone(s, p)) return true;
    return false;
  };
  if (!blind(o.center)) return false;
  if (o.level >= leaf_level) return true;  // a leaf is judged by its centre
  // A larger octant by the centres of its corner leaves, so that an octant
  // merged from blind leaves (a pruned map) stays blind. Exact when one scan's
  // ball or cone holds all of them (both are convex); across the two, a leaf
  // in between might not be blind: rare, and only near a past scan position.
  const double leaf = o.size / double(1u << (leaf_level - o.level));
  const double h = 0.5 * (o.size - leaf);
  for (int k = 0; k < 8; ++k) {
    const Point3 q(o.center.x + ((k & 1) ? h : -h), o.center.y + ((k & 2) ? h : -h),
                   o.center.z + ((k & 4) ? h : -h));
    if (!blind(q)) return false;
  }
  return true;
}

}  // namespace semioctree::nbv_detail
