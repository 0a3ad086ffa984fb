// The lengths and polynomial angles (polynomial_atan2.h) of many vectors at once: a scan's
// returns are binned by direction in the millions, and this arithmetic, run lanes at a
// time, is half of that pass (docs/occlusion.md, "Reading a scan's returns").
#pragma once

#include <cstddef>

namespace semioctree::detail {

// For each i < n, of the vector (x[i], y[i], z[i]): horizontal[i] = sqrt(x² + y²),
// length[i] = sqrt(x² + y² + z²), up[i] = polynomial_atan2(z, horizontal[i]) and
// around[i] = polynomial_atan2(y, x), bit for bit the values computed one vector at a time
// (the same operations in the same order; lanes that polynomial_atan2 scales or hands to
// std::atan2 are computed alone). The arrays must not overlap.
void direction_angles(std::size_t n, const double* __restrict x, const double* __restrict y,
                      const double* __restrict z, double* __restrict horizontal,
                      double* __restrict length, double* __restrict up, double* __restrict around);

}  // namespace semioctree::detail
