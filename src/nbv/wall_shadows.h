// Internal: lines of sight proven blocked on the plane, by the walls around a scanner
// position (docs/nbv.md, "Cost: wall shadows").
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <utility>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

// The map's columns of leaf cells over a rectangle of the plane, each with its run of
// blocking leaf cells (blocks(): occupied, unknown, door unless `doors_pass`, window)
// that holds the leaf at `height`, found on first use. Thread-safe.
class BlockingColumns {
 public:
  // The columns holding the points of [lo, hi] (x, y, m; none when more than 2^24);
  // runs are followed from `height` up to `z_max` and down to `z_min` (m) at most.
  BlockingColumns(const SemiOcTree& tree, bool doors_pass, double height, const Point3& lo,
                  const Point3& hi, double z_min, double z_max);
  // Whether column (i, j) (leaf indices) lies in the rectangle.
  bool inside(std::int64_t i, std::int64_t j) const {
    return i >= i0_ && j >= j0_ && i < i0_ + ni_ && j < j0_ + nj_;
  }
  // Its run [lo, hi) of leaf indices (lo == hi: the leaf at `height` does not block);
  // a run that reaches z_min or z_max is cut there. Requires inside(i, j).
  std::pair<std::int64_t, std::int64_t> run(std::int64_t i, std::int64_t j) const;
  std::int64_t extent() const { return std::max(ni_, nj_); }  // leaves
  double inv() const { return inv_; }                         // leaf cells per metre

 private:
  const SemiOcTree& tree_;
  bool doors_pass_;
  double inv_;
  std::int64_t height_, z_lo_, z_hi_;  // leaf indices; runs within [z_lo_, z_hi_)
  std::int64_t i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  mutable std::vector<std::atomic<std::uint32_t>> runs_;  // (lo, hi) − z_lo_ + 1; 0: not found
};

// From one scanner position: per wedge of directions on the plane, the distance beyond
// which every line of sight in the wedge crosses the interior of a block of blocking
// columns (one column, or a row of them along x or y), and the heights it blocks over.
// A segment from the position to a point beyond that distance with both ends strictly
// within those heights passes through the interior of blocking leaf cells, so the
// octree traversal of it meets a blocking octant: blocked, exactly as traversed.
// Wedges are worked out on first use. Not thread-safe: one per worker.
class WallShadows {
 public:
  explicit WallShadows(const BlockingColumns& columns);
  // A new scanner position (m). `own_octant_blocks`: the octant holding it blocks (a
  // doorway position on a door); the traversal passes that one, so nothing is proven.
  void reset(const Point3& a, bool own_octant_blocks);
  // Is the segment from the position to b (m) proven blocked?
  bool hides(const Point3& b);

 private:
  struct Wedge {
    bool done = false, found = false;
    double far2 = 0;              // squared distance (leaf units) beyond the block
    std::int64_t lo = 0, hi = 0;  // the block's blocking heights [lo, hi), leaf indices
  };
  void work_out(std::size_t w);
  bool block_covers(std::size_t w, std::int64_t x0, std::int64_t y0, std::int64_t x1,
                    std::int64_t y1) const;

  const BlockingColumns* columns_;
  double inv_;
  std::size_t wedges_count_;
  std::vector<Wedge> wedges_;
  std::vector<std::size_t> touched_;
  double A_[3] = {0, 0, 0};
  bool off_ = true;
};

}  // namespace semioctree::nbv_detail
