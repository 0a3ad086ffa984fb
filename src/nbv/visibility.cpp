#include "visibility.h"

#include <limits>

#include "label_roles.h"

namespace semioctree::nbv_detail {

Los los_octants(const SemiOcTree& tree, const Point3& a, const Point3& b, BlockerCache* cache,
                bool doors_pass) {
  Los r;
  bool blocked = false, first = true, last_occluded = false;
  std::uint32_t occluded = 0;  // not counting the start octant
  const TraversalEnd end = tree.traverse(a, b, [&](const RayStep& s) {
    const Label l = s.label();
    if (first) {  // the scanner's own octant neither blocks nor counts
      first = false;
      last_occluded = false;
      return true;
    }
    if (blocks(l, doors_pass)) {
      blocked = true;
      r.blocker = BlockerCache::pack(s);
      if (cache) cache->add(s);
      return false;
    }
    last_occluded = l == Label::kOccluded;
    occluded += last_occluded;
    return true;
  });
  if (blocked || end != TraversalEnd::kReachedEnd) return r;
  r.visible = true;
  r.n = occluded - (last_occluded ? 1 : 0);  // the last octant is the target's
  return r;
}

namespace {

// Method 2: the segment as seen by a uniform grid of level-ℓ cells.
class CellCounter {
 public:
  CellCounter(const SemiOcTree& tree, unsigned level, const Point3& a, const Point3& b)
      : k_(tree.leaf_level()), level_(level), c_(std::int64_t(1) << (k_ - level)) {
    const double inv = 1.0 / tree.getResolution();  // == OctoMap's resolution_factor
    const double P[2][3] = {{a.x * inv, a.y * inv, a.z * inv}, {b.x * inv, b.y * inv, b.z * inv}};
    for (int i = 0; i < 3; ++i) {
      A_[i] = P[0][i];
      s_[i] = static_cast<std::int64_t>(std::floor(P[0][i]));
      e_[i] = static_cast<std::int64_t>(std::floor(P[1][i]));
      dir_[i] = e_[i] > s_[i] ? 1 : (e_[i] < s_[i] ? -1 : 0);
      phase_[i] = dir_[i] < 0 ? 1 : 0;
      invD_[i] = dir_[i] != 0 ? 1.0 / (P[1][i] - P[0][i]) : 0.0;
    }
  }

  // Level-ℓ cells the segment passes through inside the octant (key, level ≤ ℓ)
  // between t_in and t_out (last: up to the segment's end): one plus the
  // distinct crossing events of level-ℓ planes inside the octant, with the
  // traversal's own crossing formula, so simultaneous crossings count once.
  std::uint32_t cells_in(const octomap::OcTreeKey& key, unsigned level, double t_in, double t_out,
                         bool last) const {
    const std::int64_t m = std::int64_t(1) << (k_ - level);
    if (m == c_) return 1;
    // Per axis, the planes crossed in order: p = first, first + step, ... (count).
    std::int64_t next[3], step[3], left[3];
    for (int i = 0; i < 3; ++i) {
      left[i] = 0;
      if (dir_[i] == 0) continue;
      const std::int64_t base = leaf_cell(key.k[i]);
      // Interior planes base + j c (0 < j < m/c) with s < p <= e (up) or e < p <= s (down).
      std::int64_t lo = base + c_, hi = base + m - c_;
      if (dir_[i] > 0) {
        lo = std::max(lo, ceil_to(s_[i] + 1, base));
        hi = std::min(hi, floor_to(e_[i], base));
        step[i] = c_;
        next[i] = lo;
      } else {
        lo = std::max(lo, ceil_to(e_[i] + 1, base));
        hi = std::min(hi, floor_to(s_[i], base));
        step[i] = -c_;
        next[i] = hi;
      }
      if (hi >= lo) left[i] = (hi - lo) / c_ + 1;
    }
    std::uint32_t events = 0;
    double last_t = -std::numeric_limits<double>::infinity();
    int last_p = -1;
    for (;;) {
      int best = -1;
      double bt = 0;
      for (int i = 0; i < 3; ++i) {
        if (left[i] == 0) continue;
        const double t = (double(next[i]) - A_[i]) * invD_[i];
        if (best < 0 || t < bt || (t == bt && phase_[i] < phase_[best])) {
          best = i;
          bt = t;
        }
      }
      if (best < 0) break;
      next[best] += step[best];
      --left[best];
      if (!(bt > t_in)) continue;
      if (!last && !(bt < t_out)) continue;
      if (bt != last_t || phase_[best] != last_p) ++events;
      last_t = bt;
      last_p = phase_[best];
    }
    return 1 + events;
  }

  // Minimum-corner leaf cell of the level-ℓ cell holding the octant at `key`.
  void cell_of(const octomap::OcTreeKey& key, std::int64_t out[3]) const {
    for (int i = 0; i < 3; ++i) out[i] = floor_to(leaf_cell(key.k[i]), 0);
  }
  unsigned level() const { return level_; }

 private:
  // Smallest p >= v with p ≡ base (mod c), and largest p <= v.
  std::int64_t ceil_to(std::int64_t v, std::int64_t base) const {
    const std::int64_t d = v - base;
    const std::int64_t q = d >= 0 ? (d + c_ - 1) / c_ : -((-d) / c_);
    return base + q * c_;
  }
  std::int64_t floor_to(std::int64_t v, std::int64_t base) const {
    const std::int64_t d = v - base;
    const std::int64_t q = d >= 0 ? d / c_ : -((-d + c_ - 1) / c_);
    return base + q * c_;
  }

  unsigned k_, level_;
  std::int64_t c_;  // level-ℓ cell side in leaf cells
  double A_[3], invD_[3];
  std::int64_t s_[3], e_[3];
  int dir_[3], phase_[3];
};

}  // namespace

Los los_cells(const SemiOcTree& tree, unsigned level, const Point3& a, const Target& t,
              BlockerCache* cache, bool doors_pass) {
  Los r;
  const CellCounter cc(tree, level, a, t.center);
  bool blocked = false;
  std::size_t index = 0;  // of the step being visited
  RayStep prev;
  // The level-ℓ cell last counted; the scanner's own cell never counts.
  std::int64_t counted[3];
  {
    octomap::OcTreeKey ka;
    if (!tree.key_of(a, ka)) return r;
    cc.cell_of(ka, counted);
  }
  std::int64_t n = 0;
  auto account = [&](const RayStep& s, double t_out, bool is_first, bool is_last) {
    if (s.label() != Label::kOccluded) return;
    if (s.level > level) {  // finer than ℓ: its level-ℓ cell, once
      std::int64_t c[3];
      cc.cell_of(s.key, c);
      if (std::equal(c, c + 3, t.cell) || std::equal(c, c + 3, counted)) return;
      std::copy(c, c + 3, counted);
      ++n;
      return;
    }
    // A level-ℓ cell or bigger: the level-ℓ cells crossed inside it, less the
    // scanner's and the target's own.
    // (The first step is entered before the segment starts: a plane through
    // the start point, crossed downwards, is a crossing of its own.)
    const double t_in = is_first ? -std::numeric_limits<double>::infinity() : s.t_enter;
    std::int64_t cells = cc.cells_in(s.key, s.level, t_in, t_out, is_last);
    cells -= is_first ? 1 : 0;
    cells -= is_last ? 1 : 0;
    n += std::max<std::int64_t>(0, cells);
  };
  const TraversalEnd end = tree.traverse(a, t.center, [&](const RayStep& s) {
    if (index > 0 && blocks(s.label(), doors_pass)) {  // the scanner's own octant never blocks
      blocked = true;
      r.blocker = BlockerCache::pack(s);
      if (cache) cache->add(s);
      return false;
    }
    if (index > 0) account(prev, s.t_enter, index == 1, false);
    prev = s;
    ++index;
    return true;
  });
  if (blocked || end != TraversalEnd::kReachedEnd || index == 0) return r;
  account(prev, 1.0, index == 1, true);
  r.visible = true;
  r.n = static_cast<std::uint32_t>(n);
  return r;
}

}  // namespace semioctree::nbv_detail
