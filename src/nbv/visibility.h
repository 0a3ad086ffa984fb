// Internal: lines of sight from a scanner position to the targets
// (docs/nbv.md, "Score" and "Cost: the blocker cache").
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "targets.h"

namespace semioctree::nbv_detail {

struct Los {
  bool visible = false;       // not blocked
  std::uint32_t n = 0;        // occluded octants (method 2: level-ℓ cells) crossed
  std::uint64_t blocker = 0;  // the blocking octant, packed (BlockerCache::pack)
};

// Blocking octants found from one scanner position, binned by direction (a
// cube map around the scanner, a few octants per bin). A segment that passes
// through the interior of a blocking octant is blocked whatever else it
// crosses, so testing the segment to the next target against the blockers
// found in its direction first is exact, and it saves the traversal of most
// blocked lines (those to targets behind walls and under furniture). Boxes
// are shrunk by a hair so that a segment merely touching a face never counts.
class BlockerCache {
 public:
  explicit BlockerCache(const SemiOcTree& tree)
      : inv_(1.0 / tree.getResolution()), k_(tree.leaf_level()), bins_(6 * kN * kN) {}
  // A new scanner position: forget the blockers. (Keeping those found from
  // the previous, neighbouring position would be as exact, but measured no
  // faster: the per-target memo already catches them.)
  void reset(const Point3& a) {
    A_[0] = a.x * inv_, A_[1] = a.y * inv_, A_[2] = a.z * inv_;
    std::fill(bins_.begin(), bins_.end(), Bin{});
  }
  // The segment from the scanner to b, for the tests below and add().
  void aim(const Point3& b) {
    for (int i = 0; i < 3; ++i) {
      D_[i] = (i == 0 ? b.x : i == 1 ? b.y : b.z) * inv_ - A_[i];
      invD_[i] = D_[i] != 0 ? 1.0 / D_[i] : 0.0;
    }
    bin_ = &bins_[bin_index()];
  }
  // Does it pass through a blocker found in its direction?
  bool blocked_in_bin() const {
    for (unsigned j = 0; j < bin_->used; ++j)
      if (passes_through(bin_->entry[j])) return true;
    return false;
  }
  // A blocker packed in 64 bits (0: none), for the per-target memo.
  // (Bit 56 set: never 0.)
  static std::uint64_t pack(const RayStep& s) {
    return (std::uint64_t(1) << 56) | pack_octant_key(s.key, s.level);
  }
  // Does it pass through this packed blocker?
  bool passes_through(std::uint64_t packed) const {
    if (!packed) return false;
    const octomap::OcTreeKey key = unpack_octant_key(packed);
    Entry e;
    for (int i = 0; i < 3; ++i) e.key[i] = key.k[i];
    e.level = static_cast<std::uint8_t>(unpack_octant_level(packed));
    return passes_through(e);
  }
  void add(const RayStep& s) {
    Entry& e = bin_->entry[bin_->next++ % kPerBin];
    for (int i = 0; i < 3; ++i) e.key[i] = s.key.k[i];
    e.level = static_cast<std::uint8_t>(s.level);
    bin_->used = static_cast<std::uint8_t>(std::min<unsigned>(bin_->used + 1u, kPerBin));
  }

 private:
  static constexpr int kN = 48;  // bins per cube face side
  static constexpr unsigned kPerBin = 3;
  static constexpr double kShrink = 1e-6;  // leaf cells
  struct Entry {
    std::uint16_t key[3];
    std::uint8_t level;
  };
  struct Bin {
    Entry entry[kPerBin];
    std::uint8_t used = 0, next = 0;
  };

  std::size_t bin_index() const {
    const double ax = std::fabs(D_[0]), ay = std::fabs(D_[1]), az = std::fabs(D_[2]);
    int face, u_axis, v_axis;
    double m;
    if (ax >= ay && ax >= az) {
      face = D_[0] >= 0 ? 0 : 1, u_axis = 1, v_axis = 2, m = ax;
    } else if (ay >= az) {
      face = D_[1] >= 0 ? 2 : 3, u_axis = 0, v_axis = 2, m = ay;
    } else {
      face = D_[2] >= 0 ? 4 : 5, u_axis = 0, v_axis = 1, m = az;
    }
    if (m == 0) return 0;
    const double scale = 0.5 * kN / m;
    auto cell = [&](double c) { return std::clamp(static_cast<int>((c + m) * scale), 0, kN - 1); };
    return (std::size_t(face) * kN + std::size_t(cell(D_[u_axis]))) * kN +
           std::size_t(cell(D_[v_axis]));
  }
  bool passes_through(const Entry& e) const {
    const double size = double(std::int64_t(1) << (k_ - e.level));
    // The scanner's own octant never blocks: reject a box holding the start.
    bool holds_start = true;
    for (int i = 0; i < 3 && holds_start; ++i) {
      const double lo = double(std::int64_t(e.key[i]) - kKeyOrigin);
      holds_start = A_[i] >= lo && A_[i] <= lo + size;
    }
    if (holds_start) return false;
    const double m = size - 2 * kShrink;
    double t0 = 0, t1 = 1;
    for (int i = 0; i < 3; ++i) {
      const double lo = double(std::int64_t(e.key[i]) - kKeyOrigin) + kShrink, hi = lo + m;
      if (D_[i] == 0) {
        if (!(A_[i] > lo && A_[i] < hi)) return false;
        continue;
      }
      double ta = (lo - A_[i]) * invD_[i], tb = (hi - A_[i]) * invD_[i];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (!(t0 < t1)) return false;
    }
    return true;
  }

  double inv_;
  unsigned k_;
  double A_[3] = {0, 0, 0}, D_[3] = {0, 0, 0}, invD_[3] = {0, 0, 0};
  std::vector<Bin> bins_;
  Bin* bin_ = nullptr;
};

// Method 1 (and 3): the line a → b through the tree's octants. Blocked by an
// occupied, unknown, door (unless `doors_pass`) or window octant other than the
// scanner's own (the blocker is then packed in `blocker` and added to `cache`, if
// given); not visible either when an end lies outside the key range. Otherwise
// visible, with n = occluded octants crossed, not counting the scanner's octant nor
// the target's (the last one visited).
Los los_octants(const SemiOcTree& tree, const Point3& a, const Point3& b,
                BlockerCache* cache = nullptr, bool doors_pass = false);

// Method 2 (level ℓ = `level`): the line a → t.center, blocked as los_octants,
// with n = the level-ℓ cells crossed that hold occluded space on the line, not
// counting the scanner's level-ℓ cell nor the target's (t.cell).
Los los_cells(const SemiOcTree& tree, unsigned level, const Point3& a, const Target& t,
              BlockerCache* cache = nullptr, bool doors_pass = false);

}  // namespace semioctree::nbv_detail
