// Points hashed by cubic cell, for "is any point within r of q" queries (internal).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace semioctree::sim::detail {

// Open addressing over the keys of the occupied cells; the points of a cell are stored
// together. At most 2^32 − 1 points.
class PointHash {
 public:
  PointHash(std::vector<Eigen::Vector3d> points, double cell);

  // True if a point lies within `radius` (at most the cell size) of q.
  bool any_within(const Eigen::Vector3d& q, double radius) const;

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
  std::vector<Eigen::Vector3d> points_;  // ordered by cell key
  std::vector<Slot> slots_;
};

}  // namespace semioctree::sim::detail
