// One 64-bit key per cell of an integer 3-D grid (internal to the sim library).
#pragma once

#include <algorithm>
#include <cstdint>

namespace semioctree::sim::detail {

// 21 bits per axis, x lowest: indices in [−2^20, 2^20) map one to one; indices beyond
// are clamped to that range (cells that far out share a key).
inline std::uint64_t grid_cell_key(long x, long y, long z) {
  constexpr long kBias = 1L << 20;
  auto part = [](long v) {
    return static_cast<std::uint64_t>(std::clamp(v + kBias, 0L, (1L << 21) - 1));
  };
  return part(x) | part(y) << 21 | part(z) << 42;
}

}  // namespace semioctree::sim::detail
