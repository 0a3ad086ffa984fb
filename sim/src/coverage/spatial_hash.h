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

  // Calls f(i) for each point within `radius` (at most half the cell size) of q, i its
  // index in the vector given to the constructor. Such a ball meets at most the 2 × 2 × 2
  // cells nearest q: its own and, on each axis, the neighbour on the nearer side.
  template <class F>
  void for_each_within(const Eigen::Vector3d& q, double radius, F&& f) const {
    if (slots_.empty()) return;
    const double r2 = radius * radius;
    long lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const double u = q[a] / cell_;
      const long i = static_cast<long>(std::floor(u));
      lo[a] = u - double(i) < 0.5 ? i - 1 : i;
      hi[a] = lo[a] + 1;
    }
    for (long z = lo[2]; z <= hi[2]; ++z)
      for (long y = lo[1]; y <= hi[1]; ++y)
        for (long x = lo[0]; x <= hi[0]; ++x) {
          const Slot* s = find(grid_cell_key(x, y, z));
          if (!s) continue;
          for (std::uint32_t k = s->begin; k < s->begin + s->count; ++k)
            if ((points_[by_cell_[k]] - q).squaredNorm() <= r2) f(by_cell_[k]);
        }
  }

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
