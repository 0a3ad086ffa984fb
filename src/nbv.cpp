#include "semioctree/nbv.h"

#include <dynamicEDT3D/dynamicEDT3D.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <utility>

#include "parallel_for.h"

namespace semioctree {

namespace {

constexpr double kDeg = M_PI / 180.0;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

using detail::parallel_for;
using detail::thread_count;

// Space seen empty (markers of scan and NBV positions included).
bool free_space(Label l) {
  return l == Label::kEmpty || l == Label::kScan || l == Label::kNbv;
}

// In the blind zone of the scanner at `s`: closer than its minimum range or
// below its minimum elevation (same formula as the occlusion study).
bool blind_from(const Point3& s, const ScannerView& lim, const Point3& p) {
  const double dx = p.x - s.x, dy = p.y - s.y, dz = p.z - s.z;
  const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (range < lim.min_range) return true;
  const double elevation = std::asin(std::clamp(dz / range, -1.0, 1.0)) * 180.0 / M_PI;
  return elevation < lim.elevation_min_deg;
}

bool blind_octant(const Octant& o, unsigned coarse_level, const std::vector<Point3>& scans,
                  const ScannerView& lim) {
  auto blind = [&](const Point3& p) {
    for (const Point3& s : scans)
      if (blind_from(s, lim, p)) return true;
    return false;
  };
  if (!blind(o.center)) return false;
  if (o.level >= coarse_level) return true;  // a leaf is judged by its centre
  // A larger octant by the centres of its corner leaves, so that an octant
  // merged from blind leaves (a pruned map) stays blind. Exact when one scan's
  // ball or cone holds all of them (both are convex); across the two, a leaf
  // in between might not be blind: rare, and only near a past scan position.
  const double leaf = o.size / double(1u << (coarse_level - o.level));
  const double h = 0.5 * (o.size - leaf);
  for (int k = 0; k < 8; ++k) {
    const Point3 q(o.center.x + ((k & 1) ? h : -h), o.center.y + ((k & 2) ? h : -h),
                   o.center.z + ((k & 4) ? h : -h));
    if (!blind(q)) return false;
  }
  return true;
}

// --- scoring -------------------------------------------------------------------------

struct Target {
  Point3 center;
  double weight = 1;
  // Method 3: half the octant's side, and its faces on free space (bit 2a for
  // the face at −half along axis a, bit 2a+1 for the one at +half).
  double half = 0;
  unsigned free_faces = 0;
  // Method 2: minimum-corner leaf cell (relative to the origin) of the level-ℓ
  // cell holding the target.
  std::int64_t cell[3] = {0, 0, 0};
};

struct Limits {
  double min_range2, max_range2, sin_min, sin_max;
  explicit Limits(const ScannerView& v)
      : min_range2(v.min_range * v.min_range),
        max_range2(v.max_range * v.max_range),
        sin_min(std::sin(std::clamp(v.elevation_min_deg, -90.0, 90.0) * kDeg)),
        sin_max(std::sin(std::clamp(v.elevation_max_deg, -90.0, 90.0) * kDeg)) {}
  // Within range, and sin_min <= dz / range <= sin_max (without a square root).
  bool in_view(const Point3& a, const Point3& b) const {
    const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 < min_range2 || r2 > max_range2 || r2 == 0) return false;
    return at_least(dz, sin_min, r2) && at_least(-dz, -sin_max, r2);
  }
  // dz >= s * sqrt(r2)?
  static bool at_least(double dz, double s, double r2) {
    if (s <= 0) return dz >= 0 || dz * dz <= s * s * r2;
    return dz > 0 && dz * dz >= s * s * r2;
  }
};

bool blocks(Label l) {
  return l == Label::kOccupied || l == Label::kUnknown || l == Label::kDoor || l == Label::kWindow;
}

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
      : inv_(1.0 / tree.getResolution()), k_(tree.coarse_level()), bins_(6 * kN * kN) {}
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
  static std::uint64_t pack(const RayStep& s) {
    return (std::uint64_t(1) << 56) | (std::uint64_t(s.level) << 48) |
           (std::uint64_t(s.key.k[0]) << 32) | (std::uint64_t(s.key.k[1]) << 16) |
           std::uint64_t(s.key.k[2]);
  }
  // Does it pass through this packed blocker?
  bool passes_through(std::uint64_t packed) const {
    if (!packed) return false;
    Entry e;
    e.key[0] = static_cast<std::uint16_t>(packed >> 32);
    e.key[1] = static_cast<std::uint16_t>(packed >> 16);
    e.key[2] = static_cast<std::uint16_t>(packed);
    e.level = static_cast<std::uint8_t>(packed >> 48);
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
      const double lo = double(std::int64_t(e.key[i]) - 32768);
      holds_start = A_[i] >= lo && A_[i] <= lo + size;
    }
    if (holds_start) return false;
    const double m = size - 2 * kShrink;
    double t0 = 0, t1 = 1;
    for (int i = 0; i < 3; ++i) {
      const double lo = double(std::int64_t(e.key[i]) - 32768) + kShrink, hi = lo + m;
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

// Method 1: occluded octants crossed at their own size; the last octant
// visited is the target's own.
Los los_octants(const SemiOcTree& tree, const Point3& a, const Point3& b,
                BlockerCache* cache = nullptr) {
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
    if (blocks(l)) {
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

// Method 2: the segment as seen by a uniform grid of level-ℓ cells.
class CellCounter {
 public:
  CellCounter(const SemiOcTree& tree, unsigned level, const Point3& a, const Point3& b)
      : k_(tree.coarse_level()), level_(level), c_(std::int64_t(1) << (k_ - level)) {
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
      const std::int64_t base = std::int64_t(key.k[i]) - 32768;
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
    for (int i = 0; i < 3; ++i) out[i] = floor_to(std::int64_t(key.k[i]) - 32768, 0);
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

Los los_cells(const SemiOcTree& tree, unsigned level, const Point3& a, const Target& t,
              BlockerCache* cache = nullptr) {
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
    if (index > 0 && blocks(s.label())) {  // the scanner's own octant never blocks
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

unsigned resolve_level(const SemiOcTree& tree, const NbvParams& p) {
  if (p.method == 1) return tree.coarse_level();
  if (p.method == 3) return tree.coarse_level();
  if (p.method != 2) throw std::invalid_argument("NbvParams::method must be 1, 2 or 3");
  if (p.level == NbvParams::kLeafLevel) return tree.coarse_level();
  if (p.level > tree.coarse_level())
    throw std::invalid_argument("NbvParams::level is finer than the tree's leaf level");
  return p.level;
}

std::vector<Target> method1_targets(const SemiOcTree& tree, const std::optional<RoomBox>& room) {
  std::vector<Target> out;
  const unsigned k = tree.coarse_level();
  const double leaf_volume = std::pow(tree.leaf_size(), 3);
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    Target t;
    t.center = o.center;
    t.weight = double(std::uint64_t(1) << (3 * (k - o.level)));
    if (room) {
      const double inside = room->overlap(o.center, o.size);
      if (inside <= 0) return;
      t.weight = std::min(t.weight, inside / leaf_volume);
    }
    out.push_back(t);
  });
  return out;
}

// Occluded octants with a face on free space: the occlusion frontier. The
// neighbour across a face is the octant holding a point a quarter leaf beyond
// the face's centre (a finer neighbour thus stands for the whole face).
std::vector<Target> method3_targets(const SemiOcTree& tree) {
  std::vector<Target> out;
  const double step = 0.25 * tree.leaf_size();
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    Target t;
    t.center = o.center;
    t.half = 0.5 * o.size;
    for (unsigned f = 0; f < 6; ++f) {
      Point3 q = o.center;
      const double d = (f & 1 ? 1.0 : -1.0) * (t.half + step);
      (f < 2 ? q.x : f < 4 ? q.y : q.z) += d;
      const auto nb = tree.find_octant(q);
      if (nb && free_space(nb->label())) t.free_faces |= 1u << f;
    }
    if (t.free_faces == 0) return;
    t.weight = o.size * o.size;
    out.push_back(t);
  });
  return out;
}

// The free faces of a target that have `a` in front of them (beyond the face's plane).
unsigned facing_faces(const Target& t, const Point3& a) {
  const double rel[3] = {a.x - t.center.x, a.y - t.center.y, a.z - t.center.z};
  unsigned out = 0;
  for (unsigned axis = 0; axis < 3; ++axis) {
    if (rel[axis] < -t.half) out |= 1u << (2 * axis);
    if (rel[axis] > t.half) out |= 1u << (2 * axis + 1);
  }
  return out & t.free_faces;
}

// Method 3 weight of a target seen from a: the area of its free faces facing a.
double facing_area(const Target& t, const Point3& a) {
  return double(__builtin_popcount(facing_faces(t, a))) * t.weight;
}

std::vector<Target> method2_targets(const SemiOcTree& tree, unsigned level) {
  std::vector<Target> out;
  const unsigned k = tree.coarse_level();
  const std::int64_t c = std::int64_t(1) << (k - level);
  const double r = tree.leaf_size();
  auto cell_of = [&](const octomap::OcTreeKey& key, std::int64_t cell[3]) {
    for (int i = 0; i < 3; ++i) {
      const std::int64_t v = std::int64_t(key.k[i]) - 32768;
      cell[i] = v >= 0 ? (v / c) * c : -((-v + c - 1) / c) * c;
    }
  };
  auto push = [&](const std::int64_t cell[3]) {
    Target t;
    t.center =
        Point3((double(cell[0]) + 0.5 * double(c)) * r, (double(cell[1]) + 0.5 * double(c)) * r,
               (double(cell[2]) + 0.5 * double(c)) * r);
    std::copy(cell, cell + 3, t.cell);
    out.push_back(t);
  };
  // Octants finer than ℓ come in depth-first order, so the descendants of one
  // level-ℓ cell are consecutive: aggregate them, flush when the cell changes.
  bool open = false, occupied = false;
  std::int64_t cur[3] = {0, 0, 0};
  std::uint64_t occluded_cells = 0;  // leaf cells
  const std::uint64_t cell_volume = std::uint64_t(1) << (3 * (k - level));
  auto flush = [&] {
    if (open && !occupied && 2 * occluded_cells >= cell_volume) push(cur);
    open = false;
  };
  tree.for_each_octant([&](const Octant& o) {
    if (o.level > level) {
      std::int64_t cell[3];
      cell_of(o.key, cell);
      if (!open || !std::equal(cell, cell + 3, cur)) {
        flush();
        open = true;
        occupied = false;
        occluded_cells = 0;
        std::copy(cell, cell + 3, cur);
      }
      occupied |= o.label() == Label::kOccupied;
      if (o.label() == Label::kOccluded) occluded_cells += std::uint64_t(1) << (3 * (k - o.level));
      return;
    }
    flush();
    if (o.label() != Label::kOccluded) return;
    const std::int64_t sub = std::int64_t(1) << (level - o.level);
    std::int64_t base[3];
    for (int i = 0; i < 3; ++i) base[i] = std::int64_t(o.key.k[i]) - 32768;
    for (std::int64_t z = 0; z < sub; ++z)
      for (std::int64_t y = 0; y < sub; ++y)
        for (std::int64_t x = 0; x < sub; ++x) {
          const std::int64_t cell[3] = {base[0] + x * c, base[1] + y * c, base[2] + z * c};
          push(cell);
        }
  });
  flush();
  return out;
}

}  // namespace

// --- candidates -----------------------------------------------------------------------

namespace {

// The map's coarse voxels' extent in x and y (z of the results unused): the
// plane the 2-D grids below cover.
std::pair<CoarseIndex, CoarseIndex> coarse_columns(const SemiOcTree& tree) {
  CoarseIndex lo{std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), 0};
  CoarseIndex hi{std::numeric_limits<int>::min(), std::numeric_limits<int>::min(), 0};
  tree.for_each_coarse([&](const CoarseIndex& c, SemiOcTreeNode*) {
    lo.x = std::min(lo.x, c.x), lo.y = std::min(lo.y, c.y);
    hi.x = std::max(hi.x, c.x), hi.y = std::max(hi.y, c.y);
  });
  return {lo, hi};
}

}  // namespace

bool RoomBox::contains(const Point3& p) const {
  return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
         p.z <= max.z;
}

double RoomBox::overlap(const Point3& c, double size) const {
  const double h = 0.5 * size;
  auto along = [h](double lo, double hi, double v) {
    return std::max(0.0, std::min(hi, v + h) - std::max(lo, v - h));
  };
  return along(min.x, max.x, c.x) * along(min.y, max.y, c.y) * along(min.z, max.z, c.z);
}

std::optional<RoomBox> room_box(const SemiOcTree& tree, const std::vector<Point3>& scanners,
                                double height, double floor_z, double ceiling_z) {
  if (tree.coarse_count() == 0 || !(ceiling_z > floor_z)) return std::nullopt;
  const double r = tree.leaf_size();
  const unsigned k = tree.coarse_level();
  const std::int64_t span = std::int64_t(1) << k;
  // Leaf cells of the plane over the map's coarse columns (0: not free, 1: free,
  // 2: reached); cell (x, y) is key (x + x0, y + y0) − 32768.
  const std::pair<CoarseIndex, CoarseIndex> columns = coarse_columns(tree);
  const CoarseIndex &lo = columns.first, &hi = columns.second;
  const std::int64_t x0 = std::int64_t(lo.x) * span, y0 = std::int64_t(lo.y) * span;
  const std::int64_t nx = (std::int64_t(hi.x) - lo.x + 1) * span;
  const std::int64_t ny = (std::int64_t(hi.y) - lo.y + 1) * span;
  std::vector<std::uint8_t> cell(std::size_t(nx * ny), 0);
  auto idx = [&](std::int64_t x, std::int64_t y) { return std::size_t(y * nx + x); };
  tree.for_each_octant([&](const Octant& o) {
    const double h = 0.5 * o.size;
    if (!free_space(o.label()) || height < o.center.z - h || height >= o.center.z + h) return;
    const std::int64_t size = std::int64_t(1) << (k - o.level);
    const std::int64_t cx = std::int64_t(o.key.k[0]) - 32768 - x0;
    const std::int64_t cy = std::int64_t(o.key.k[1]) - 32768 - y0;
    for (std::int64_t y = cy; y < cy + size; ++y)
      for (std::int64_t x = cx; x < cx + size; ++x) cell[idx(x, y)] = 1;
  });
  // Seeds: the free cells within kSeedRadius of each scanner. Its own cell is
  // not free until another scan sees it: the blind zone (minimum range) around
  // a scanner is occluded.
  constexpr double kSeedRadius = 1.0;  // m, beyond the minimum range
  const std::int64_t reach = std::llround(std::ceil(kSeedRadius / r));
  std::vector<std::size_t> stack;
  for (const Point3& s : scanners) {
    octomap::OcTreeKey key;
    if (!tree.key_of(Point3(s.x, s.y, height), key)) continue;
    const std::int64_t sx = std::int64_t(key.k[0]) - 32768 - x0;
    const std::int64_t sy = std::int64_t(key.k[1]) - 32768 - y0;
    for (std::int64_t y = sy - reach; y <= sy + reach; ++y)
      for (std::int64_t x = sx - reach; x <= sx + reach; ++x) {
        if (x < 0 || y < 0 || x >= nx || y >= ny || cell[idx(x, y)] != 1) continue;
        if ((x - sx) * (x - sx) + (y - sy) * (y - sy) > reach * reach) continue;
        cell[idx(x, y)] = 2;
        stack.push_back(idx(x, y));
      }
  }
  if (stack.empty()) return std::nullopt;
  std::int64_t bx0 = nx, by0 = ny, bx1 = -1, by1 = -1;
  while (!stack.empty()) {
    const std::size_t i = stack.back();
    stack.pop_back();
    const std::int64_t x = std::int64_t(i) % nx, y = std::int64_t(i) / nx;
    bx0 = std::min(bx0, x), by0 = std::min(by0, y), bx1 = std::max(bx1, x), by1 = std::max(by1, y);
    const std::int64_t nbx[4] = {x + 1, x - 1, x, x}, nby[4] = {y, y, y + 1, y - 1};
    for (int d = 0; d < 4; ++d) {
      if (nbx[d] < 0 || nby[d] < 0 || nbx[d] >= nx || nby[d] >= ny) continue;
      const std::size_t j = idx(nbx[d], nby[d]);
      if (cell[j] != 1) continue;
      cell[j] = 2;
      stack.push_back(j);
    }
  }
  // Cells bx0..bx1 span [bx0, bx1 + 1) leaves; one more leaf on each side.
  RoomBox box;
  box.min = Point3(double(bx0 + x0 - 1) * r, double(by0 + y0 - 1) * r, floor_z);
  box.max = Point3(double(bx1 + x0 + 2) * r, double(by1 + y0 + 2) * r, ceiling_z);
  return box;
}

double floor_layer_clearance(const RobotGeometry& robot, double leaf_size) {
  if (!(robot.ground_clearance > 0)) return 0.0;  // no clearance: the floor layer counts too
  return std::max(robot.ground_clearance, leaf_size);
}

std::vector<Point3> find_candidates(const SemiOcTree& tree, const RobotGeometry& robot,
                                    const Point3& robot_position,
                                    const std::vector<Point3>& past_scans, const NbvParams& params,
                                    CandidateReport* report) {
  CandidateReport rep;
  std::vector<Point3> out;
  if (report) *report = rep;
  if (tree.coarse_count() == 0) return out;
  if (!(robot.radius >= 0) || !(robot.scanner_height > 0) || !(robot.top() > 0))
    throw std::invalid_argument("RobotGeometry: radius >= 0 and scanner height > 0 required");
  const double r = tree.leaf_size();
  const unsigned k = tree.coarse_level();
  const std::int64_t span = std::int64_t(1) << k;

  // The 2-D grid (leaf cells) over the map's coarse columns, with a border of
  // one obstacle cell: outside the map is unknown space.
  const std::pair<CoarseIndex, CoarseIndex> columns = coarse_columns(tree);
  const CoarseIndex &lo = columns.first, &hi = columns.second;
  const std::int64_t x0 = std::int64_t(lo.x) * span - 1, y0 = std::int64_t(lo.y) * span - 1;
  const int nx = static_cast<int>((std::int64_t(hi.x) - lo.x + 1) * span + 2);
  const int ny = static_cast<int>((std::int64_t(hi.y) - lo.y + 1) * span + 2);
  std::vector<std::uint8_t> obstacle(std::size_t(nx) * std::size_t(ny), 0);
  auto idx = [&](int x, int y) { return std::size_t(y) * std::size_t(nx) + std::size_t(x); };
  for (int x = 0; x < nx; ++x) obstacle[idx(x, 0)] = obstacle[idx(x, ny - 1)] = 1;
  for (int y = 0; y < ny; ++y) obstacle[idx(0, y)] = obstacle[idx(nx - 1, y)] = 1;
  auto mark = [&](std::int64_t cx, std::int64_t cy, std::int64_t size) {
    for (std::int64_t y = cy; y < cy + size; ++y)
      for (std::int64_t x = cx; x < cx + size; ++x) obstacle[idx(int(x - x0), int(y - y0))] = 1;
  };

  // Leaf layers of the cylinder: z ∈ [0, top); octants lying wholly below the
  // ground clearance, or within the floor's own leaf layer, are driven over.
  const std::int64_t layers =
      std::max<std::int64_t>(1, std::llround(std::ceil(robot.top() / r - 1e-9)));
  const double clearance = floor_layer_clearance(robot, r) / r + 1e-9;  // in cells
  for (int cx = lo.x; cx <= hi.x; ++cx)
    for (int cy = lo.y; cy <= hi.y; ++cy)
      for (std::int64_t cz = 0; cz <= (layers - 1) >> k; ++cz)
        if (double((cz + 1) * span) > clearance && !tree.find_coarse({cx, cy, int(cz)}))
          mark(cx * span, cy * span, span);
  tree.for_each_octant([&](const Octant& o) {
    const std::int64_t size = std::int64_t(1) << (k - o.level);
    const std::int64_t z = std::int64_t(o.key.k[2]) - 32768;
    if (z >= layers || double(z + size) <= clearance) return;
    const Label l = o.label();
    if (l == Label::kOccluded) {
      if (params.blind_zone_is_free && blind_octant(o, k, past_scans, params.limits)) {
        ++rep.blind_octants_freed;
        return;
      }
    } else if (l != Label::kOccupied && l != Label::kUnknown) {
      return;
    }
    mark(std::int64_t(o.key.k[0]) - 32768, std::int64_t(o.key.k[1]) - 32768, size);
  });

  // Clearance with dynamicEDT3D on the one-layer obstacle map: a cell is clear
  // when no obstacle cell centre lies within radius + leaf/2 of its centre.
  const double reach = (robot.radius + 0.5 * r) / r;  // in cells
  const int max_cells = static_cast<int>(std::ceil(reach)) + 2;
  DynamicEDT3D edt(max_cells * max_cells);
  edt.initializeEmpty(nx, ny, 1, true);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      if (obstacle[idx(x, y)]) edt.occupyCell(x, y, 0);
  edt.update(false);
  std::vector<std::uint8_t> clear(obstacle.size(), 0);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      clear[idx(x, y)] = double(edt.getSQCellDistance(x, y, 0)) > reach * reach;

  // Reachability: 4-connected flood fill over clear cells from the robot.
  std::vector<std::uint8_t> reached(obstacle.size(), 0);
  octomap::OcTreeKey rk;
  if (tree.key_of(robot_position, rk)) {
    const std::int64_t rx = std::int64_t(rk.k[0]) - 32768 - x0;
    const std::int64_t ry = std::int64_t(rk.k[1]) - 32768 - y0;
    if (rx > 0 && ry > 0 && rx < nx - 1 && ry < ny - 1) {
      rep.robot_in_map = true;
      std::vector<std::size_t> stack{idx(int(rx), int(ry))};
      reached[stack.back()] = 1;  // the robot stands there: always traversable
      while (!stack.empty()) {
        const std::size_t i = stack.back();
        stack.pop_back();
        const int x = int(i % std::size_t(nx)), y = int(i / std::size_t(nx));
        const int nbx[4] = {x + 1, x - 1, x, x}, nby[4] = {y, y, y + 1, y - 1};
        for (int d = 0; d < 4; ++d) {
          if (nbx[d] < 0 || nby[d] < 0 || nbx[d] >= nx || nby[d] >= ny) continue;
          const std::size_t j = idx(nbx[d], nby[d]);
          if (reached[j] || !clear[j]) continue;
          reached[j] = 1;
          stack.push_back(j);
        }
      }
    }
  }

  // The candidate grid: every m-th leaf cell (world-aligned), at its centre.
  const std::int64_t m = std::max<std::int64_t>(1, std::llround(params.candidate_spacing / r));
  std::int64_t off_x = m / 2, off_y = m / 2;  // grid points: leaf cells ≡ off (mod m)
  if (params.grid_anchor) {
    octomap::OcTreeKey ak;
    if (!tree.key_of(Point3(params.grid_anchor->x, params.grid_anchor->y, 0.0), ak))
      throw std::invalid_argument("NbvParams: the candidate grid's anchor is beyond the key range");
    off_x = ((std::int64_t(ak.k[0]) - 32768) % m + m) % m;
    off_y = ((std::int64_t(ak.k[1]) - 32768) % m + m) % m;
  }
  auto first_on_grid = [&](std::int64_t v, std::int64_t off) {  // smallest g >= v, g ≡ off
    std::int64_t d = v - off;
    std::int64_t q = d >= 0 ? (d + m - 1) / m : -((-d) / m);
    return off + q * m;
  };
  for (std::int64_t gy = first_on_grid(y0 + 1, off_y); gy < y0 + ny - 1; gy += m) {
    for (std::int64_t gx = first_on_grid(x0 + 1, off_x); gx < x0 + nx - 1; gx += m) {
      ++rep.grid_points;
      const Point3 p((double(gx) + 0.5) * r, (double(gy) + 0.5) * r, robot.scanner_height);
      const auto o = tree.find_octant(p);
      if (!o || !free_space(o->label())) {
        ++rep.not_empty;
        continue;
      }
      const std::size_t i = idx(int(gx - x0), int(gy - y0));
      if (!clear[i]) {
        ++rep.cylinder_blocked;
        continue;
      }
      if (!reached[i]) {
        ++rep.unreachable;
        continue;
      }
      ++rep.feasible;
      out.push_back(p);
    }
  }
  if (report) *report = rep;
  return out;
}

// --- scores ---------------------------------------------------------------------------

namespace {

std::vector<double> score_targets(const SemiOcTree& tree, const std::vector<Target>& targets,
                                  const std::vector<Point3>& positions, const NbvParams& params,
                                  ScoringStats* stats) {
  const unsigned level = resolve_level(tree, params);
  const Limits lim(params.limits);
  std::vector<double> scores(positions.size(), 0.0);
  std::vector<ScoringStats> per(positions.size());
  // The last blocker found on a line to each target, from any candidate: the
  // occluder that hides a target usually hides it from the neighbouring
  // candidates too. It only saves traversals (any blocker is a proof), so the
  // races between threads on it do not change any result.
  std::vector<std::atomic<std::uint64_t>> memo(2 * targets.size());
  for (auto& m : memo) m.store(0, std::memory_order_relaxed);
  const unsigned threads = thread_count(params.threads);
  std::vector<BlockerCache> caches(threads, BlockerCache(tree));
  std::atomic<std::size_t> scored{0};
  const double cpu =
      parallel_for(positions.size(), threads, 1, [&](std::size_t c, unsigned worker) {
        const Point3& a = positions[c];
        BlockerCache& cache = caches[worker];
        cache.reset(a);
        ScoringStats& st = per[c];
        double sum = 0;
        for (std::size_t i = 0; i < targets.size(); ++i) {
          const Target& t = targets[i];
          const double weight = params.method == 3 ? facing_area(t, a) : t.weight;
          if (weight == 0 || !lim.in_view(a, t.center)) continue;
          ++st.segments;
          cache.aim(t.center);
          if (cache.blocked_in_bin() ||
              cache.passes_through(memo[2 * i].load(std::memory_order_relaxed)) ||
              cache.passes_through(memo[2 * i + 1].load(std::memory_order_relaxed))) {
            ++st.blocked_by_cache;
            continue;
          }
          const Los los = params.method == 2 ? los_cells(tree, level, a, t, &cache)
                                             : los_octants(tree, a, t.center, &cache);
          if (los.blocker) {  // keep the last two
            memo[2 * i + 1].store(memo[2 * i].load(std::memory_order_relaxed),
                                  std::memory_order_relaxed);
            memo[2 * i].store(los.blocker, std::memory_order_relaxed);
          }
          if (!los.visible) continue;
          ++st.visible;
          // Method 3: a frontier face in view is new surface whatever lies on the way.
          sum += params.method == 3 ? weight : weight / (1.0 + double(los.n));
        }
        scores[c] = sum;
        const std::size_t done = scored.fetch_add(1, std::memory_order_relaxed) + 1;
        if (params.progress) params.progress(done, positions.size());
      });
  if (stats) {
    *stats = ScoringStats{};
    stats->targets = targets.size();
    stats->cpu_seconds = cpu;
    for (const ScoringStats& p : per) {
      stats->segments += p.segments;
      stats->blocked_by_cache += p.blocked_by_cache;
      stats->visible += p.visible;
    }
  }
  return scores;
}

std::vector<Target> targets_of(const SemiOcTree& tree, const NbvParams& params) {
  const unsigned level = resolve_level(tree, params);
  if (params.method == 1) return method1_targets(tree, params.room);
  std::vector<Target> t = params.method == 3 ? method3_targets(tree) : method2_targets(tree, level);
  if (params.room)
    t.erase(std::remove_if(t.begin(), t.end(),
                           [&](const Target& x) { return !params.room->contains(x.center); }),
            t.end());
  return t;
}

}  // namespace

std::vector<double> score_positions(const SemiOcTree& tree, const std::vector<Point3>& positions,
                                    const NbvParams& params, ScoringStats* stats) {
  return score_targets(tree, targets_of(tree, params), positions, params, stats);
}

double stop_percentage(const SemiOcTree& tree, const Point3& nbv, const ScannerView& limits,
                       unsigned threads, const std::optional<RoomBox>& room) {
  double total = 0;
  if (room) {
    tree.for_each_octant([&](const Octant& o) {
      if (o.label() != Label::kUnknown) total += room->overlap(o.center, o.size);
    });
  } else {
    const OctantStatistics stats = tree.statistics();
    for (Label l : {Label::kOccluded, Label::kEmpty, Label::kOccupied, Label::kOut, Label::kDoor,
                    Label::kWindow, Label::kScan, Label::kNbv})
      total += stats.volume[static_cast<int>(l)];
  }
  if (total <= 0) return 0.0;
  const std::vector<Target> targets = method1_targets(tree, room);
  const Limits lim(limits);
  // Each target's share seen: its Eq 4 term (1, 1/(1+n) or 0).
  std::vector<double> share(targets.size(), 0.0);
  parallel_for(targets.size(), thread_count(threads), 256, [&](std::size_t i, unsigned) {
    if (!lim.in_view(nbv, targets[i].center)) return;
    const Los los = los_octants(tree, nbv, targets[i].center);
    if (los.visible) share[i] = 1.0 / (1.0 + double(los.n));
  });
  const double leaf_volume = std::pow(tree.leaf_size(), 3);
  double seen = 0;
  for (std::size_t i = 0; i < targets.size(); ++i)
    seen += share[i] * targets[i].weight * leaf_volume;
  return 100.0 * seen / total;
}

NbvResult next_best_view(const SemiOcTree& tree, const RobotGeometry& robot,
                         const Point3& robot_position, const std::vector<Point3>& past_scans,
                         const NbvParams& params) {
  NbvResult res;
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<Point3> positions =
      find_candidates(tree, robot, robot_position, past_scans, params, &res.candidate_report);
  res.seconds_candidates = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  const std::vector<Target> targets = targets_of(tree, params);
  const std::vector<double> scores = score_targets(tree, targets, positions, params, &res.scoring);
  res.candidates.reserve(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    res.candidates.push_back({positions[i], scores[i]});
    if (!res.best || scores[i] > res.best->score) res.best = res.candidates.back();
  }
  res.seconds_scoring = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  if (res.best)
    res.stop_percent =
        stop_percentage(tree, res.best->position, params.limits, params.threads, params.room);
  res.seconds_stop = seconds_since(t0);
  return res;
}

}  // namespace semioctree
