#include "blind_zone.h"

#include <algorithm>
#include <cmath>

namespace semioctree::nbv_detail {

bool blind_octant(const Octant& o, unsigned leaf_level, std::int64_t z_lo, std::int64_t z_hi,
                  const std::vector<Point3>& scans, const detail::ScannerLimits& limits) {
  auto blind = [&](const Point3& p) {
    for (const Point3& s : scans)
      if (limits.in_blind_zone(s, p)) return true;
    return false;
  };
  // The part of `o` in layers [z_lo, z_hi]: its corner leaves' centres, in metres.
  const double leaf = o.size / double(1u << (leaf_level - o.level));
  const std::int64_t span = std::int64_t(1) << (leaf_level - o.level);
  const std::int64_t z0 = leaf_cell(o.key.k[2]);
  const std::int64_t lo = std::max(z0, z_lo), hi = std::min(z0 + span - 1, z_hi);
  if (lo > hi) return true;                         // nothing of it in those layers
  const double bottom = o.center.z - 0.5 * o.size;  // z of layer z0's bottom face
  const double zc0 = bottom + (double(lo - z0) + 0.5) * leaf;
  const double zc1 = bottom + (double(hi - z0) + 0.5) * leaf;
  const Point3 centre(o.center.x, o.center.y, 0.5 * (zc0 + zc1));
  if (!blind(centre)) return false;
  if (o.level >= leaf_level) return true;  // a leaf is judged by its centre
  // A larger octant by the centres of its corner leaves too, so that an octant
  // merged from blind leaves (a pruned map) stays blind. Exact when one scan's
  // ball or cone holds all of them (both are convex); across the two, a leaf
  // in between might not be blind: rare, and only near a past scan position.
  const double h = 0.5 * (o.size - leaf);
  for (int k = 0; k < 8; ++k) {
    const Point3 q(o.center.x + ((k & 1) ? h : -h), o.center.y + ((k & 2) ? h : -h),
                   (k & 4) ? zc1 : zc0);
    if (!blind(q)) return false;
  }
  return true;
}

}  // namespace semioctree::nbv_detail
