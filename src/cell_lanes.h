// The per-point arithmetic of preprocessing's cells, lanes at a time: where points' cells lie
// in a bitmap of cells (the counts of a decimation spacing's cells), and the cells and
// offsets a decimation (CellThinning) keeps points by. A scan's millions of points pass
// through these several times; the compiler runs the loops on several points at once.
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

// For the points (x[j], y[j], z[j]), j < n, and cells of side 1 / inv: key[j], the packed key
// of the point's cell (pack_cell_parts of floor(double(v) · inv) per axis), and offset2[j],
// the point's squared distance from the cell's centre in cells (per axis
// t − floor(t) − 0.5, t = double(v) · inv, squared and summed x, y, z, then rounded to a
// float). Where an axis's floor is 2^31 or more in magnitude, wide[j] is 1 and key[j] and
// offset2[j] are left for the caller to compute alone; else wide[j] is 0. Finite points.
void cell_keys(std::size_t n, const float* __restrict x, const float* __restrict y,
               const float* __restrict z, double inv, std::uint64_t* __restrict key,
               float* __restrict offset2, std::uint8_t* __restrict wide);

}  // namespace semioctree::detail
