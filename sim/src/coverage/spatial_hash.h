// Points hashed by cubic cell, for "which points lie within r of q" queries (internal).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "grid_cell_key.h"

namespace semioctree::sim::detail {

// Open addressing over the keys of the occupied cells; the indices of a cell's points are
// stored together, the points themselves are read where they are given (they must outlive
// the hash and not change). At most 2^32 − 1 points.
class PointHash {
 public:
  PointHash(const std::vector<Eigen::Vector3d>& points, double cell);

  // The 2 × 2 × 2 cells nearest a point q, named by their lowest cell: a ball of radius at
  // most half the cell size about q meets no other cell (its own cell and, on each axis,
  // the neighbour on the nearer side).
  struct Block {
    long x = 0, y = 0, z = 0;
    bool operator==(const Block& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  Block block_of(const Eigen::Vector3d& q) const {
    long lo[3];
    for (int a = 0; a < 3; ++a) {
      const double u = q[a] / cell_;
      const long i = static_cast<long>(std::floor(u));
      lo[a] = u - double(i) < 0.5 ? i - 1 : i;
    }
    return {lo[0], lo[1], lo[2]};
  }

  // Calls f(i) for each point in the block's cells, i its index in the vector given to
  // the constructor.
  template <class F>
  void for_each_in_block(const Block& b, F&& f) const {
    if (slots_.empty()) return;
    for (long z = b.z; z <= b.z + 1; ++z)
      for (long y = b.y; y <= b.y + 1; ++y)
        for (long x = b.x; x <= b.x + 1; ++x) {
          const Slot* s = find(grid_cell_key(x, y, z));
          if (!s) continue;
          for (std::uint32_t k = s->begin; k < s->begin + s->count; ++k) f(by_cell_[k]);
        }
  }

  // Calls f(i) for each point within `radius` (at most half the cell size) of q.
  template <class F>
  void for_each_within(const Eigen::Vector3d& q, double radius, F&& f) const {
    const double r2 = radius * radius;
    for_each_in_block(block_of(q), [&](std::uint32_t i) {
      if ((points_[i] - q).squaredNorm() <= r2) f(i);
    });
  }

  const Eigen::Vector3d& point(std::uint32_t i) const { return points_[i]; }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t begin = 0;
    std::uint32_t count = 0;  // 0: empty slot
  };
  long index(double v) const;
  std::uint64_t cell_key(const Eigen::Vector3d& p) const;
  const Slot* find(std::uint64_t key) const;

  double cell_;
  const std::vector<Eigen::Vector3d>& points_;
  std::vector<std::uint32_t> by_cell_;  // the points' indices, ordered by cell key
  std::vector<Slot> slots_;
};

}  // namespace semioctree::sim::detail
