#include "cell_places.h"

#include <cmath>

namespace semioctree::detail {

// std::floor of the double product is the integer preprocessing's floor_to_int gives; here
// in a loop the compiler runs on several points at once. On x86-64 it builds the loop for
// AVX2 (4 lanes) and for the baseline, and the loader picks one.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
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

}  // namespace semioctree::detail
