// Internal: 2-D grids of leaf cells on a horizontal plane over the map's coarse
// columns, as the candidate search and room_box use them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

// The map's coarse voxels' extent in x and y (lowest, highest; z of both 0).
// Needs a map with at least one coarse voxel.
std::pair<CoarseIndex, CoarseIndex> coarse_columns(const SemiOcTree& tree);

// 4-connected flood fill on a grid of nx × ny cells (cell (x, y) at index
// y·nx + x): 1 for each cell reachable from `seeds` through cells for which
// passable(index) holds, 0 elsewhere. The seeds count as reached whatever
// `passable` says of them.
template <class Passable>
std::vector<std::uint8_t> flood_fill_4(std::size_t nx, std::size_t ny,
                                       const std::vector<std::size_t>& seeds, Passable passable) {
  std::vector<std::uint8_t> reached(nx * ny, 0);
  std::vector<std::size_t> stack;
  for (const std::size_t s : seeds)
    if (!reached[s]) {
      reached[s] = 1;
      stack.push_back(s);
    }
  auto visit = [&](std::size_t j) {
    if (reached[j] || !passable(j)) return;
    reached[j] = 1;
    stack.push_back(j);
  };
  while (!stack.empty()) {
    const std::size_t i = stack.back();
    stack.pop_back();
    const std::size_t x = i % nx, y = i / nx;
    if (x + 1 < nx) visit(i + 1);
    if (x > 0) visit(i - 1);
    if (y + 1 < ny) visit(i + nx);
    if (y > 0) visit(i - nx);
  }
  return reached;
}

}  // namespace semioctree::nbv_detail
