#include "cell_lanes.h"

#include <cmath>

#include "semioctree/octomap_ext/packed_key_map.h"
#include "vector_clones.h"

namespace semioctree::detail {

// std::floor of the double product is the integer preprocessing's floor_to_int gives; here
// in a loop the compiler runs on several points at once.
SEMIOCTREE_VECTOR_CLONES
void cell_places(std::size_t n, const float* __restrict x, const float* __restrict y,
                 const float* __restrict z, double inv, const double lo[3],
                 const std::uint32_t blocks[2], std::uint32_t* __restrict block,
                 std::uint8_t* __restrict word, std::uint8_t* __restrict bit) {
  const double lo0 = lo[0], lo1 = lo[1], lo2 = lo[2];
  const std::uint32_t bx = blocks[0], by = blocks[1];
  for (std::size_t j = 0; j < n; ++j) {
    // Indices from `lo`: below 2^21, so exact in a double's difference and in an int32.
    const auto c0 = std::int32_t(std::floor(double(x[j]) * inv) - lo0);
    const auto c1 = std::int32_t(std::floor(double(y[j]) * inv) - lo1);
    const auto c2 = std::int32_t(std::floor(double(z[j]) * inv) - lo2);
    block[j] = std::uint32_t(c0 >> 3) + bx * (std::uint32_t(c1 >> 3) + by * std::uint32_t(c2 >> 3));
    word[j] = std::uint8_t(c2 & 7);
    bit[j] = std::uint8_t((c0 & 7) | (c1 & 7) << 3);
  }
}

SEMIOCTREE_VECTOR_CLONES
void cell_keys(std::size_t n, const float* __restrict x, const float* __restrict y,
               const float* __restrict z, double inv, std::uint64_t* __restrict key,
               float* __restrict offset2, std::uint8_t* __restrict wide) {
  constexpr double kNarrow = 0x1p31;  // floors below this in magnitude fit an int32
  for (std::size_t j = 0; j < n; ++j) {
    const double tx = double(x[j]) * inv, ty = double(y[j]) * inv, tz = double(z[j]) * inv;
    const double fx = std::floor(tx), fy = std::floor(ty), fz = std::floor(tz);
    const double dx = tx - fx - 0.5, dy = ty - fy - 0.5, dz = tz - fz - 0.5;
    offset2[j] = float(dx * dx + dy * dy + dz * dz);
    const bool narrow =
        std::fabs(fx) < kNarrow && std::fabs(fy) < kNarrow && std::fabs(fz) < kNarrow;
    wide[j] = std::uint8_t(!narrow);
    // A floor's low bits, which pack_cell_parts keeps, are its int32's.
    const auto low = [&](double f) { return std::uint32_t(std::int32_t(narrow ? f : 0.0)); };
    key[j] = pack_cell_parts(low(fx), low(fy), low(fz));
  }
}

}  // namespace semioctree::detail
