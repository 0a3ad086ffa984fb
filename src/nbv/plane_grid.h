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

// The 2-D grid of leaf cells over the map's coarse columns, with a border of
// one cell; cell (x, y) is leaf column (x + x0, y + y0) (key − kKeyOrigin).
struct Plane {
  CoarseIndex lo, hi;  // the coarse columns (coarse_columns)
  std::int64_t x0 = 0, y0 = 0;
  int nx = 0, ny = 0;
  std::size_t index(int x, int y) const {
    return std::size_t(y) * std::size_t(nx) + std::size_t(x);
  }
  std::size_t cells() const { return std::size_t(nx) * std::size_t(ny); }
};

// The plane over the map's coarse columns. Needs a map with at least one coarse voxel.
Plane plane_over(const SemiOcTree& tree);

// 1 for each cell of `plane` whose leaf octant at `height` has a label that
// `take(Label)` accepts; 0 elsewhere (the border, columns without a coarse voxel there).
template <class Take>
std::vector<std::uint8_t> cells_at_height(const SemiOcTree& tree, const Plane& plane, double height,
                                          Take take) {
  std::vector<std::uint8_t> cells(plane.cells(), 0);
  // The leaf layer holding `height`, found as the tree finds keys: a plane on an octant's
  // face belongs to the octant above it (comparing metres, rounding put such a plane in
  // neither octant).
  octomap::OcTreeKey key;
  if (!tree.key_of(Point3(0, 0, height), key)) return cells;
  const std::int64_t layer = leaf_cell(key.k[2]);
  const unsigned k = tree.leaf_level();
  tree.for_each_octant([&](const Octant& o) {
    const std::int64_t size = std::int64_t(1) << (k - o.level);
    const std::int64_t bottom = leaf_cell(o.key.k[2]);
    if (!take(o.label()) || layer < bottom || layer >= bottom + size) return;
    const std::int64_t cx = leaf_cell(o.key.k[0]) - plane.x0;
    const std::int64_t cy = leaf_cell(o.key.k[1]) - plane.y0;
    for (std::int64_t y = cy; y < cy + size; ++y)
      for (std::int64_t x = cx; x < cx + size; ++x) cells[plane.index(int(x), int(y))] = 1;
  });
  return cells;
}

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
