// atan2 from a polynomial: a few times cheaper than std::atan2, within a stated bound of it.
// For binning millions of directions, where the bound tells when a value lies so near a
// bin's edge that std::atan2 must decide (docs/occlusion.md, "Reading a scan's returns").
#pragma once

#include <algorithm>
#include <cmath>

namespace semioctree::detail {

// |polynomial_atan2(y, x) − std::atan2(y, x)| stays below this (radians) for finite y, x.
// The series below leaves out less than 3e-9; rounding adds ~1e-15.
constexpr double kPolynomialAtan2Error = 1e-7;

// atan2(y, x) in [−π, π], with std::atan2's quadrants and signed zeros (y = −0 gives −π
// for x < 0, −0 for x > 0); both arguments zero: std::atan2's own value.
inline double polynomial_atan2(double y, double x) {
  const double ax = std::fabs(x), ay = std::fabs(y);
  double big = std::max(ax, ay), small = std::min(ax, ay);
  if (!(big > 0)) return std::atan2(y, x);
  // Only the ratio counts: scaled by a power of two (exactly), small + big cannot overflow
  // and tan(π/8)·big is not rounded among subnormals.
  if (big > 0x1p1000) {
    small *= 0x1p-8, big *= 0x1p-8;
  } else if (big < 0x1p-900) {
    small *= 0x1p100, big *= 0x1p100;
  }
  // atan(t), t ∈ [0, 1]: above tan(π/8) through atan(t) = π/4 + atan((t − 1) / (t + 1)),
  // so that the series runs on |s| ≤ tan(π/8) ≈ 0.4142, where its terms up to s^17 leave
  // out less than 0.4143^19 / 19 < 3e-9 (an alternating series: at most its first term).
  // (t − 1) / (t + 1) with t = small / big is (small − big) / (small + big): one division.
  double s, base = 0.0;
  if (small > 0.41421356237309503 * big) {
    s = (small - big) / (small + big);
    base = M_PI / 4;
  } else {
    s = small / big;
  }
  // 1 − u/3 + u²/5 − … + u⁸/17 in u = s², by pairs (Estrin's scheme: a chain of 4
  // dependent steps, not Horner's 8; the same bound, rounding aside).
  const double u = s * s, u2 = u * u, u4 = u2 * u2;
  const double p01 = 1.0 - u * (1.0 / 3), p23 = 1.0 / 5 - u * (1.0 / 7);
  const double p45 = 1.0 / 9 - u * (1.0 / 11), p67 = 1.0 / 13 - u * (1.0 / 15);
  const double series = (p01 + u2 * p23) + u4 * ((p45 + u2 * p67) + u4 * (1.0 / 17));
  double a = base + s * series;
  if (ay > ax) a = M_PI / 2 - a;
  if (x < 0) a = M_PI - a;
  return std::signbit(y) ? -a : a;
}

}  // namespace semioctree::detail
