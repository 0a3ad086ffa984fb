#include "wall_shadows.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "label_roles.h"

namespace semioctree::nbv_detail {

namespace {

// A monotone stand-in for the direction's angle on the plane, in [0, 4): one unit per
// quadrant, linear in y / (|x| + |y|) within it. (0, 0) has none.
double diamond_angle(double x, double y) {
  if (y >= 0) return x >= 0 ? y / (x + y) : 1 - x / (-x + y);
  return x < 0 ? 2 - y / (-x - y) : 3 + x / (x - y);
}

// A direction with that diamond angle.
void direction_of(double p, double d[2]) {
  p = std::clamp(p, 0.0, 4.0);
  const int q = std::min(3, static_cast<int>(std::floor(p)));
  const double f = p - q;
  switch (q) {
    case 0:
      d[0] = 1 - f, d[1] = f;
      break;
    case 1:
      d[0] = -f, d[1] = 1 - f;
      break;
    case 2:
      d[0] = f - 1, d[1] = -f;
      break;
    default:
      d[0] = f, d[1] = f - 1;
      break;
  }
}

// The most columns a block reaches on each side of the column the wedge's centre meets.
constexpr std::int64_t kMaxRow = 8;
// The most columns kept (4 bytes each, 64 MiB): a plane of 4096 × 4096 leaves.
constexpr std::int64_t kMaxColumns = std::int64_t(1) << 24;

}  // namespace

BlockingColumns::BlockingColumns(const SemiOcTree& tree, bool doors_pass, double height,
                                 const Point3& lo, const Point3& hi, double z_min, double z_max)
    : tree_(tree), doors_pass_(doors_pass), inv_(1.0 / tree.getResolution()) {
  const auto cell = [&](double v) { return static_cast<std::int64_t>(std::floor(v * inv_)); };
  height_ = cell(height);
  z_lo_ = cell(z_min) - 1;
  z_hi_ = static_cast<std::int64_t>(std::ceil(z_max * inv_)) + 1;
  i0_ = cell(lo.x);
  j0_ = cell(lo.y);
  ni_ = std::max<std::int64_t>(0, cell(hi.x) - i0_ + 1);
  nj_ = std::max<std::int64_t>(0, cell(hi.y) - j0_ + 1);
  // Runs are packed in 16 bits each: a taller span gets no columns, and neither does a
  // plane of more than kMaxColumns (no line is then proven blocked on the plane).
  if (!(height_ > z_lo_ && height_ < z_hi_) || z_hi_ - z_lo_ >= 0xfff0 || ni_ * nj_ > kMaxColumns)
    ni_ = nj_ = 0;
  runs_ = std::vector<std::atomic<std::uint32_t>>(std::size_t(ni_ * nj_));
  for (auto& r : runs_) r.store(0, std::memory_order_relaxed);
}

std::pair<std::int64_t, std::int64_t> BlockingColumns::run(std::int64_t i, std::int64_t j) const {
  std::atomic<std::uint32_t>& slot = runs_[std::size_t((j - j0_) * ni_ + (i - i0_))];
  std::uint32_t v = slot.load(std::memory_order_relaxed);
  if (v == 0) {
    const unsigned k = tree_.leaf_level();
    // The blocking octant holding leaf (i, j, z): its bottom and top (leaf indices), or
    // none. Space outside every coarse voxel is unknown to the traversal: it blocks.
    auto blocking_at = [&](std::int64_t z, std::int64_t& bottom, std::int64_t& top) {
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(i + kKeyOrigin),
                                   static_cast<octomap::key_type>(j + kKeyOrigin),
                                   static_cast<octomap::key_type>(z + kKeyOrigin));
      const std::optional<Octant> o = tree_.find_octant(key);
      if (o && !blocks(o->label(), doors_pass_)) return false;
      const unsigned shift = k - (o ? o->level : 0);       // the octant's side: 2^shift leaves
      bottom = (z >> shift) * (std::int64_t(1) << shift);  // arithmetic shift: floor
      top = bottom + (std::int64_t(1) << shift);
      return true;
    };
    std::int64_t lo = height_, hi = height_, bottom = 0, top = 0;
    if (blocking_at(height_, bottom, top)) {
      lo = bottom, hi = top;
      while (hi < z_hi_ && blocking_at(hi, bottom, top)) hi = top;
      while (lo > z_lo_ && blocking_at(lo - 1, bottom, top)) lo = bottom;
      lo = std::max(lo, z_lo_), hi = std::min(hi, z_hi_);
    }
    v = std::uint32_t(lo - z_lo_ + 1) | (std::uint32_t(hi - z_lo_ + 1) << 16);
    slot.store(v, std::memory_order_relaxed);
  }
  return {std::int64_t(v & 0xffffu) - 1 + z_lo_, std::int64_t(v >> 16) - 1 + z_lo_};
}

WallShadows::WallShadows(const BlockingColumns& columns)
    : columns_(&columns),
      inv_(columns.inv()),
      // Wedges at most about 6 leaves wide at the far corner of the plane (a diamond-
      // angle unit is 1 to 2 radians wide).
      wedges_count_(std::size_t(4 * std::max<std::int64_t>(16, (columns.extent() + 1) / 2))),
      wedges_(wedges_count_) {}

void WallShadows::reset(const Point3& a, bool own_octant_blocks) {
  for (std::size_t w : touched_) wedges_[w] = Wedge{};
  touched_.clear();
  A_[0] = a.x * inv_, A_[1] = a.y * inv_, A_[2] = a.z * inv_;
  off_ = own_octant_blocks || columns_->extent() == 0;
}

bool WallShadows::hides(const Point3& b) {
  if (off_) return false;
  const double dx = b.x * inv_ - A_[0], dy = b.y * inv_ - A_[1], bz = b.z * inv_;
  if (dx == 0 && dy == 0) return false;
  const double p = diamond_angle(dx, dy);
  const std::size_t w =
      std::min(wedges_count_ - 1, static_cast<std::size_t>(p * double(wedges_count_) / 4.0));
  Wedge& wedge = wedges_[w];
  if (!wedge.done) work_out(w);
  if (!wedge.found) return false;
  return dx * dx + dy * dy > wedge.far2 && bz > double(wedge.lo) && bz < double(wedge.hi);
}

bool WallShadows::block_covers(std::size_t w, std::int64_t x0, std::int64_t y0, std::int64_t x1,
                               std::int64_t y1) const {
  const double lo[2] = {double(x0), double(y0)}, hi[2] = {double(x1), double(y1)};
  if (A_[0] >= lo[0] && A_[0] <= hi[0] && A_[1] >= lo[1] && A_[1] <= hi[1]) return false;
  // Both of the wedge's sides (widened by a hair, for the rounding of the angle a
  // target is put in a wedge by) cross the block's interior: so does every direction
  // between them (the block is convex and the wedge narrower than a half-turn).
  constexpr double kHair = 1e-9;
  for (const double p : {4.0 * double(w) / double(wedges_count_) - kHair,
                         4.0 * double(w + 1) / double(wedges_count_) + kHair}) {
    double d[2];
    direction_of(p < 0 ? p + 4 : p >= 4 ? p - 4 : p, d);
    double t0 = 0, t1 = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 2; ++i) {
      if (d[i] == 0) {
        if (!(A_[i] > lo[i] && A_[i] < hi[i])) return false;
        continue;
      }
      double ta = (lo[i] - A_[i]) / d[i], tb = (hi[i] - A_[i]) / d[i];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (!(t0 < t1)) return false;
  }
  return true;
}

void WallShadows::work_out(std::size_t w) {
  Wedge& wedge = wedges_[w];
  wedge.done = true;
  touched_.push_back(w);
  double d[2];
  direction_of(4.0 * (double(w) + 0.5) / double(wedges_count_), d);
  // Cells along the wedge's centre line, nearest first (a 2-D traversal of the grid).
  std::int64_t c[2], step[2];
  double t_next[2], t_delta[2];
  for (int i = 0; i < 2; ++i) {
    c[i] = static_cast<std::int64_t>(std::floor(A_[i]));
    step[i] = d[i] > 0 ? 1 : -1;
    t_delta[i] = d[i] != 0 ? std::abs(1.0 / d[i]) : std::numeric_limits<double>::infinity();
    t_next[i] = d[i] > 0   ? (double(c[i] + 1) - A_[i]) / d[i]
                : d[i] < 0 ? (double(c[i]) - A_[i]) / d[i]
                           : std::numeric_limits<double>::infinity();
  }
  const auto holds_scanner = [&](std::int64_t lo, std::int64_t hi) {
    return double(lo) < A_[2] && A_[2] < double(hi);
  };
  for (;;) {
    const int axis = t_next[0] < t_next[1] ? 0 : 1;
    c[axis] += step[axis];
    t_next[axis] += t_delta[axis];
    if (!columns_->inside(c[0], c[1])) return;
    const auto [lo, hi] = columns_->run(c[0], c[1]);
    if (lo == hi || !holds_scanner(lo, hi)) continue;
    // The seed column's heights, and the columns beside it along x, then y, that block
    // over them all.
    const auto covers = [&, lo = lo, hi = hi](std::int64_t i, std::int64_t j) {
      if (!columns_->inside(i, j)) return false;
      const auto [l, h] = columns_->run(i, j);
      return l <= lo && h >= hi;
    };
    for (int along = 0; along < 2; ++along) {
      std::int64_t first = c[along], last = c[along];
      std::int64_t at[2] = {c[0], c[1]};
      for (at[along] = c[along] - 1; c[along] - at[along] <= kMaxRow && covers(at[0], at[1]);
           --at[along])
        first = at[along];
      for (at[along] = c[along] + 1; at[along] - c[along] <= kMaxRow && covers(at[0], at[1]);
           ++at[along])
        last = at[along];
      std::int64_t x0 = c[0], y0 = c[1], x1 = c[0] + 1, y1 = c[1] + 1;
      (along == 0 ? x0 : y0) = first;
      (along == 0 ? x1 : y1) = last + 1;
      if (!block_covers(w, x0, y0, x1, y1)) continue;
      double far2 = 0;
      for (const double x : {double(x0), double(x1)})
        for (const double y : {double(y0), double(y1)})
          far2 = std::max(far2, (x - A_[0]) * (x - A_[0]) + (y - A_[1]) * (y - A_[1]));
      wedge.found = true;
      wedge.far2 = far2;
      wedge.lo = lo;
      wedge.hi = hi;
      return;
    }
  }
}

}  // namespace semioctree::nbv_detail
