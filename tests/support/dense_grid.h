// A baseline of the benchmarks (not the library): the homogeneous grid as a dense array, one
// label byte per leaf voxel in a flat std::vector over the map's axis-aligned bounds, and its
// occlusion study by 3D DDA (Amanatides & Woo) through the array. What a semioctree is
// measured against when "homogeneous" means the plainest grid there is, not a SemiOcTree
// with coarse = leaf.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "semioctree/occlusion.h"
#include "semioctree/scan_io.h"
#include "src/parallel_for.h"
#include "src/scanner_limits.h"

namespace semioctree::testing {

// Voxel (i, j, k) of the grid is the leaf cell [(x0 + i)·r, (x0 + i + 1)·r) × … in world
// coordinates: the cells of OctoMap's key grid at resolution r, as the SemiOcTree's leaves.
class DenseGrid {
 public:
  DenseGrid(double leaf, std::int64_t x0, std::int64_t y0, std::int64_t z0, int nx, int ny, int nz)
      : leaf_(leaf),
        inverse_leaf_(1.0 / leaf),
        origin_{x0, y0, z0},
        size_{nx, ny, nz},
        labels_(std::size_t(nx) * std::size_t(ny) * std::size_t(nz),
                static_cast<std::uint8_t>(Label::kEmpty)) {
    if (!(leaf > 0) || nx <= 0 || ny <= 0 || nz <= 0)
      throw std::invalid_argument("dense grid: leaf and sizes must be positive");
  }

  // The grid of a levelled cloud (floor at z = 0) over the region discretize covers with
  // DiscretizeParams{leaf, coarse, extent_snap}, extent_snap > 0: the bounds of the points
  // with 0 ≤ z < ceiling_height, x and y snapped outwards to multiples of extent_snap, z
  // from 0 up to the ceiling rounded up to a multiple of extent_snap. The voxel of every
  // such point is occupied, the others empty.
  static DenseGrid from_cloud(const Cloud& cloud, double ceiling_height, double leaf,
                              double extent_snap) {
    const std::int64_t snap = std::llround(extent_snap / leaf);  // cells per snap
    if (snap < 1 || std::fabs(double(snap) * leaf - extent_snap) > 1e-9 * extent_snap)
      throw std::invalid_argument("dense grid: the extent snap must be a multiple of the leaf");
    double lo[2] = {std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[2] = {-lo[0], -lo[1]};
    std::size_t inside = 0;
    for (const auto& p : cloud) {
      if (p.z < 0 || p.z >= ceiling_height) continue;
      lo[0] = std::min(lo[0], double(p.x));
      lo[1] = std::min(lo[1], double(p.y));
      hi[0] = std::max(hi[0], double(p.x));
      hi[1] = std::max(hi[1], double(p.y));
      ++inside;
    }
    if (inside == 0) throw std::invalid_argument("dense grid: no point below the ceiling");
    auto snapped_down = [&](double v) { return std::int64_t(std::floor(v / extent_snap)) * snap; };
    const std::int64_t x0 = snapped_down(lo[0]), y0 = snapped_down(lo[1]);
    const std::int64_t x1 = snapped_down(hi[0]) + snap, y1 = snapped_down(hi[1]) + snap;
    const std::int64_t z1 =
        std::int64_t(std::ceil(std::nextafter(ceiling_height, 0.0) / extent_snap)) * snap;
    DenseGrid grid(leaf, x0, y0, 0, int(x1 - x0), int(y1 - y0), int(z1));
    for (const auto& p : cloud) {
      if (p.z < 0 || p.z >= ceiling_height) continue;
      std::int64_t i, j, k;
      if (grid.voxel_of({p.x, p.y, p.z}, i, j, k))
        grid.labels_[grid.index(i, j, k)] = static_cast<std::uint8_t>(Label::kOccupied);
    }
    return grid;
  }

  double leaf() const { return leaf_; }
  int size(int axis) const { return size_[axis]; }
  std::size_t voxels() const { return labels_.size(); }
  std::size_t memory_bytes() const { return labels_.capacity(); }
  std::size_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return (std::size_t(k) * std::size_t(size_[1]) + std::size_t(j)) * std::size_t(size_[0]) +
           std::size_t(i);
  }
  bool inside(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < size_[0] && j < size_[1] && k < size_[2];
  }
  // The voxel (grid indices) holding p, as OctoMap's coordToKey cuts space; false outside.
  bool voxel_of(const Point3& p, std::int64_t& i, std::int64_t& j, std::int64_t& k) const {
    i = cell(p.x) - origin_[0];
    j = cell(p.y) - origin_[1];
    k = cell(p.z) - origin_[2];
    return inside(i, j, k);
  }
  Point3 centre(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return {(double(origin_[0] + i) + 0.5) * leaf_, (double(origin_[1] + j) + 0.5) * leaf_,
            (double(origin_[2] + k) + 0.5) * leaf_};
  }
  Label label(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<Label>(labels_[index(i, j, k)]);
  }
  void set_label(std::int64_t i, std::int64_t j, std::int64_t k, Label l) {
    labels_[index(i, j, k)] = static_cast<std::uint8_t>(l);
  }
  // Occupied voxels block; space outside the grid holds nothing (unknown, as in the map).
  bool occupied(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return inside(i, j, k) &&
           labels_[index(i, j, k)] == static_cast<std::uint8_t>(Label::kOccupied);
  }
  std::size_t count(Label l) const {
    return std::size_t(std::count(labels_.begin(), labels_.end(), static_cast<std::uint8_t>(l)));
  }

  // Whether the segment a → b crosses an occupied voxel other than a's (the scanner's own
  // voxel hides nothing, as in study_occlusion) and b's: 3D DDA, voxel by voxel in the
  // order the segment enters them.
  bool segment_blocked(const Point3& a, const Point3& b) const {
    const double from[3] = {a.x * inverse_leaf_, a.y * inverse_leaf_, a.z * inverse_leaf_};
    const double d[3] = {(b.x - a.x) * inverse_leaf_, (b.y - a.y) * inverse_leaf_,
                         (b.z - a.z) * inverse_leaf_};  // in cells
    std::int64_t c[3], end[3], step[3];
    double t_next[3], t_delta[3];  // segment parameter of the next boundary, per axis
    const double to[3] = {b.x * inverse_leaf_, b.y * inverse_leaf_, b.z * inverse_leaf_};
    for (int axis = 0; axis < 3; ++axis) {
      c[axis] = std::int64_t(std::floor(from[axis])) - origin_[axis];
      end[axis] = std::int64_t(std::floor(to[axis])) - origin_[axis];
      const double f = from[axis] - std::floor(from[axis]);  // offset inside the cell
      if (d[axis] > 0) {
        step[axis] = 1;
        t_delta[axis] = 1.0 / d[axis];
        t_next[axis] = (1.0 - f) * t_delta[axis];
      } else if (d[axis] < 0) {
        step[axis] = -1;
        t_delta[axis] = -1.0 / d[axis];
        t_next[axis] = f * t_delta[axis];
      } else {
        step[axis] = 0;
        t_delta[axis] = t_next[axis] = std::numeric_limits<double>::infinity();
      }
    }
    // A segment with both ends in the grid stays in it (a box is convex): its voxels are
    // read by a flat index stepped along, without bounds checks.
    const bool contained = inside(c[0], c[1], c[2]) && inside(end[0], end[1], end[2]);
    const std::int64_t stride[3] = {1, size_[0], std::int64_t(size_[0]) * size_[1]};
    std::int64_t at = contained ? std::int64_t(index(c[0], c[1], c[2])) : 0;
    const std::uint8_t occupied_label = static_cast<std::uint8_t>(Label::kOccupied);
    while (!(c[0] == end[0] && c[1] == end[1] && c[2] == end[2])) {
      const int axis =
          t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
      // A voxel entered at the very end only touches b: it hides nothing.
      if (t_next[axis] >= 1.0 - kEndTolerance) return false;
      c[axis] += step[axis];
      at += step[axis] * stride[axis];
      t_next[axis] += t_delta[axis];
      if (c[0] == end[0] && c[1] == end[1] && c[2] == end[2]) return false;
      if (contained ? labels_[std::size_t(at)] == occupied_label : occupied(c[0], c[1], c[2]))
        return true;
    }
    return false;
  }

 private:
  static constexpr double kEndTolerance = 1e-9;
  std::int64_t cell(double v) const { return std::int64_t(std::floor(v * inverse_leaf_)); }

  double leaf_, inverse_leaf_;
  std::int64_t origin_[3];  // world cell index of voxel (0, 0, 0)
  int size_[3];
  std::vector<std::uint8_t> labels_;  // Label per voxel, x fastest
};

struct DenseOcclusionReport {
  std::size_t visible = 0, occluded = 0, occupied = 0;
  std::size_t segments = 0;  // segments traversed (voxels within the scanner's limits)
  DenseOcclusionReport& operator+=(const DenseOcclusionReport& o) {
    visible += o.visible, occluded += o.occluded, occupied += o.occupied, segments += o.segments;
    return *this;
  }
};

// The occlusion study of the dense grid from one scanner: every voxel that is not occupied
// is empty (visible) if its centre lies within the view's range and elevation limits and
// the segment from the optical centre to it crosses no occupied voxel, else occluded.
// The view's return directions are not used. Runs on `threads` threads, over rows of
// voxels; the labels are written once every segment has been cast (the segments read the
// grid while it is being studied).
inline DenseOcclusionReport study_occlusion_dense(DenseGrid& grid, const ScannerView& view,
                                                  unsigned threads) {
  threads = std::max(1u, threads);
  const detail::ScannerLimits limits(view);
  const std::int64_t nx = grid.size(0), ny = grid.size(1), nz = grid.size(2);
  std::vector<std::uint8_t> visible(grid.voxels(), 0);
  std::vector<DenseOcclusionReport> per_worker(threads);
  detail::parallel_for(std::size_t(ny * nz), threads, 16, [&](std::size_t row, unsigned worker) {
    const std::int64_t j = std::int64_t(row) % ny, k = std::int64_t(row) / ny;
    DenseOcclusionReport r;  // this row's counts (the workers' totals share cache lines)
    for (std::int64_t i = 0; i < nx; ++i) {
      if (grid.label(i, j, k) == Label::kOccupied) {
        ++r.occupied;
        continue;
      }
      const Point3 p = grid.centre(i, j, k);
      if (!limits.in_view(view.position, p)) {
        ++r.occluded;
        continue;
      }
      ++r.segments;
      const bool seen = !grid.segment_blocked(view.position, p);
      visible[grid.index(i, j, k)] = seen;
      ++(seen ? r.visible : r.occluded);
    }
    per_worker[worker] += r;
  });
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i)
        if (grid.label(i, j, k) != Label::kOccupied)
          grid.set_label(i, j, k, visible[grid.index(i, j, k)] ? Label::kEmpty : Label::kOccluded);
  DenseOcclusionReport total;
  for (const DenseOcclusionReport& r : per_worker) total += r;
  return total;
}

}  // namespace semioctree::testing
