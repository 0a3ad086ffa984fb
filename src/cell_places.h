// Where points' cells lie in a bitmap of cells (preprocess.cpp's CellBits, which counts the
// cells a decimation spacing keeps): the per-point arithmetic of a count, lanes at a time.
#pragma once

#include <cstddef>
#include <cstdint>

namespace semioctree::detail {

// For the points (x[j], y[j], z[j]), j < n, in a bitmap of cells of side 1 / inv whose first
// cell is `lo` (per axis; |lo| < 2^52) and which spans `blocks` blocks of 8 cells along x
// and y: the place of each point's block in the bitmap's index (below 2^32), its word
// (z % 8) in the block and its bit (x % 8 + 8 · (y % 8)) in the word, x, y, z being the
// cell's index from `lo` along each axis. A point's cell is floor(double(v) · inv) per axis,
// the cell preprocessing's decimation keeps one point of. The points must lie within the
// bitmap's bounds (each index from `lo` below 2^21).
void cell_places(std::size_t n, const float* __restrict x, const float* __restrict y,
                 const float* __restrict z, double inv, const double lo[3],
                 const std::uint32_t blocks[2], std::uint32_t* __restrict block,
                 std::uint8_t* __restrict word, std::uint8_t* __restrict bit);

}  // namespace semioctree::detail
