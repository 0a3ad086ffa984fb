#include "direction_angles.h"

#include <algorithm>
#include <cmath>

#include "polynomial_atan2.h"
#include "vector_clones.h"

namespace semioctree::detail {

namespace {

// Whether polynomial_atan2 computes a pair whose larger magnitude is `big` without scaling
// it or asking std::atan2 (false for 0 and NaN).
inline bool unscaled(double big) {
  return big >= 0x1p-900 && big <= 0x1p1000;
}

// The larger of |y| and |x| as polynomial_atan2 takes it (std::max: NaN when x is).
inline double larger(double y, double x) {
  const double ax = std::fabs(x), ay = std::fabs(y);
  return ax < ay ? ay : ax;
}

// polynomial_atan2(y, x) for an unscaled pair, without branches (selects the vectorizer
// turns into blends): the same operations as polynomial_atan2's, in the same order.
inline double unscaled_atan2(double y, double x) {
  const double ax = std::fabs(x), ay = std::fabs(y);
  const double big = larger(y, x);
  const double small = ay < ax ? ay : ax;  // std::min(ax, ay)
  const bool folded = small > 0.41421356237309503 * big;
  const double s = (folded ? small - big : small) / (folded ? small + big : big);
  const double base = folded ? M_PI / 4 : 0.0;
  const double u = s * s, u2 = u * u, u4 = u2 * u2;
  const double p01 = 1.0 - u * (1.0 / 3), p23 = 1.0 / 5 - u * (1.0 / 7);
  const double p45 = 1.0 / 9 - u * (1.0 / 11), p67 = 1.0 / 13 - u * (1.0 / 15);
  const double series = (p01 + u2 * p23) + u4 * ((p45 + u2 * p67) + u4 * (1.0 / 17));
  double a = base + s * series;  // ≥ +0: s ≥ 0
  a = ay > ax ? M_PI / 2 - a : a;
  a = x < 0 ? M_PI - a : a;
  return std::copysign(a, y);  // a ≥ +0, so this is polynomial_atan2's signbit(y) ? −a : a
}

}  // namespace

SEMIOCTREE_VECTOR_CLONES
void direction_angles(std::size_t n, const double* __restrict x, const double* __restrict y,
                      const double* __restrict z, double* __restrict horizontal,
                      double* __restrict length, double* __restrict up, double* __restrict around) {
  for (std::size_t i = 0; i < n; ++i) {
    const double h2 = x[i] * x[i] + y[i] * y[i];
    horizontal[i] = std::sqrt(h2);
    length[i] = std::sqrt(h2 + z[i] * z[i]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    up[i] = unscaled_atan2(z[i], horizontal[i]);
    around[i] = unscaled_atan2(y[i], x[i]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!unscaled(larger(z[i], horizontal[i]))) up[i] = polynomial_atan2(z[i], horizontal[i]);
    if (!unscaled(larger(y[i], x[i]))) around[i] = polynomial_atan2(y[i], x[i]);
  }
}

SEMIOCTREE_VECTOR_CLONES
void direction_bins(std::size_t n, const double* __restrict up, const double* __restrict around,
                    int per_degree, int rows, const int* __restrict count,
                    const int* __restrict first, int* __restrict bin,
                    std::uint8_t* __restrict edge) {
  constexpr double e = kPolynomialAtan2Error;
  const auto row = [&](double u) { return direction_row(elevation_degrees(u), per_degree, rows); };
  const auto column = [](double a, int c) { return direction_column(turn_fraction(a), c); };
  for (std::size_t j = 0; j < n; ++j) {
    // Angles lie within ±π (not finite: a zero or non-finite vector, worked out alone).
    const bool finite = std::fabs(up[j]) <= 4.0 && std::fabs(around[j]) <= 4.0;
    const double u = finite ? up[j] : 0.0, a = finite ? around[j] : 0.0;
    const int r = row(u - e), c_count = count[r];
    const int c = column(a - e, c_count);
    bin[j] = first[r] + c;
    edge[j] = std::uint8_t(!finite || r != row(u + e) || c != column(a + e, c_count));
  }
}

}  // namespace semioctree::detail
