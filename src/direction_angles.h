// The lengths and polynomial angles (polynomial_atan2.h) of many vectors at once: a scan's
// returns are binned by direction in the millions, and this arithmetic, run lanes at a
// time, is half of that pass (docs/occlusion.md, "Reading a scan's returns").
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace semioctree::detail {

// For each i < n, of the vector (x[i], y[i], z[i]): horizontal[i] = sqrt(x² + y²),
// length[i] = sqrt(x² + y² + z²), up[i] = polynomial_atan2(z, horizontal[i]) and
// around[i] = polynomial_atan2(y, x), bit for bit the values computed one vector at a time
// (the same operations in the same order; lanes that polynomial_atan2 scales or hands to
// std::atan2 are computed alone). The arrays must not overlap.
void direction_angles(std::size_t n, const double* __restrict x, const double* __restrict y,
                      const double* __restrict z, double* __restrict horizontal,
                      double* __restrict length, double* __restrict up, double* __restrict around);

// The maps from a direction's angles to its bin (occlusion.cpp's DirectionBins, and
// direction_bins below): its elevation (radians) in degrees above −90°, its azimuth
// (radians, −π..π) as the fraction of the turn from −π; the row of an elevation among
// `rows` rows of 1 / per_degree degree, and the column of a fraction among `count`.
inline double elevation_degrees(double up) {
  return up * (180.0 / M_PI) + 90.0;
}
inline double turn_fraction(double azimuth) {
  return (azimuth + M_PI) / (2 * M_PI);
}
inline int direction_row(double elevation, int per_degree, int rows) {
  return std::clamp(int(elevation * per_degree), 0, rows - 1);
}
inline int direction_column(double fraction, int count) {
  return std::clamp(int(fraction * count), 0, count - 1);
}

// The bins of directions given by their polynomial angles (up[j], around[j], as
// direction_angles computes them, within kPolynomialAtan2Error of std::atan2's), among
// bins of `per_degree` rows a degree of elevation (`rows` in all), row r holding count[r]
// bins of azimuth from bin first[r] on: bin[j] = first[r] + c, r the row of elevation
// (up + π/2) in degrees · per_degree, c the column of (around + π) / 2π · count[r], each
// truncated and clamped to its range. edge[j] is 1 where up or around ± the bound falls
// in another row or column (std::atan2 must decide) or is not finite, and bin[j] is then
// to be worked out alone; else 0.
void direction_bins(std::size_t n, const double* __restrict up, const double* __restrict around,
                    int per_degree, int rows, const int* __restrict count,
                    const int* __restrict first, int* __restrict bin,
                    std::uint8_t* __restrict edge);

}  // namespace semioctree::detail
