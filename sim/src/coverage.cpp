// Survey coverage against a cached reference of the visible surface samples.
#include "semioctree/sim/coverage.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <type_traits>
#include <utility>

namespace semioctree::sim {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Bump when the visibility rule, the grid of positions or the file layout changes: old
// cache files then get another name and are never read. 2: nothing seen through an
// opening; 3: reachable positions only.
constexpr std::uint32_t kRuleVersion = 3;
constexpr double kPlanCell = 0.05;  // floor-plan cell used for the survey area

// The scanner-limit part of the rule, before any ray is cast.
struct Limits {
  double min_range, max_range;
  double sin_el_min, sin_el_max;  // limits on (p.z − c.z) / |p − c|
};

Limits limits_of(const ScannerConfig& s) {
  auto sin_deg = [](double deg) {
    const double clamped = std::clamp(deg, -90.0, 90.0);
    return std::sin(clamped * M_PI / 180.0);
  };
  return {s.min_range, s.max_range, sin_deg(s.elevation_min_deg), sin_deg(s.elevation_max_deg)};
}

// True if `sample` passes the range, elevation and facing tests from `c`.
inline bool within_limits(const Limits& lim, const SurfaceSample& sample,
                          const Eigen::Vector3d& c) {
  const Eigen::Vector3d v = c - sample.position;  // sample → scanner
  if (sample.normal.dot(v) <= 0) return false;
  const double r2 = v.squaredNorm();
  if (r2 < lim.min_range * lim.min_range || r2 > lim.max_range * lim.max_range) return false;
  const double r = std::sqrt(r2);
  const double sin_el = -v.z() / r;  // elevation of the sample seen from the scanner
  return sin_el >= lim.sin_el_min - 1e-12 && sin_el <= lim.sin_el_max + 1e-12;
}

// The end of the segment that the rule tests from the optical centre.
inline Eigen::Vector3d target_of(const SurfaceSample& sample) {
  return sample.position + kCoverageSampleOffset * sample.normal;
}

inline bool line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                          const Eigen::Vector3d& c) {
  return truth.segment_free(c, target_of(sample));
}

// A wall as the slab |dot(normal, x − origin)| ≤ half, with its face rectangle
// u ∈ [0, length] (u = dot(along, x − origin)), z ∈ [z0, z1] and the rectangles of its
// openings (from opening_rects) in the same (u, z) coordinates.
struct WallSlab {
  struct Rect {
    double u0, u1, z0, z1;
  };
  Eigen::Vector3d origin, along, normal;  // origin: wall.from at z = 0, on the centre plane
  double length, z0, z1, half;
  std::vector<Rect> holes;
};

std::vector<WallSlab> wall_slabs(const Scene& scene) {
  std::vector<WallSlab> out;
  out.reserve(scene.walls.size());
  for (const Wall& w : scene.walls) {
    // A wall of no length keeps a zero normal: no segment crosses it.
    const double length = w.length();
    const Eigen::Vector2d d = length > 0 ? w.direction() : Eigen::Vector2d::Zero();
    const Eigen::Vector2d n(-d.y(), d.x());
    out.push_back({{w.from.x(), w.from.y(), 0.0},
                   {d.x(), d.y(), 0.0},
                   {n.x(), n.y(), 0.0},
                   length,
                   w.z0,
                   w.z1,
                   std::max(0.0, w.thickness / 2),
                   {}});
  }
  for (const OpeningRect& r : opening_rects(scene)) {
    if (r.wall < 0 || static_cast<std::size_t>(r.wall) >= out.size()) continue;
    WallSlab& w = out[static_cast<std::size_t>(r.wall)];
    const double ua = w.along.dot(r.corners[0] - w.origin);
    const double ub = w.along.dot(r.corners[1] - w.origin);
    // The part of the opening within the wall (as the wall's mesh cuts it).
    const WallSlab::Rect h{std::max(0.0, std::min(ua, ub)), std::min(w.length, std::max(ua, ub)),
                           std::max(w.z0, r.corners[0].z()), std::min(w.z1, r.corners[3].z())};
    if (h.u1 > h.u0 && h.z1 > h.z0) w.holes.push_back(h);
  }
  return out;
}

// Tolerances of the wall tests. A crossing within kHoleEps of a hole counts as in it:
// a segment that passes that close to the hole's edge is either through it or blocked by
// the jamb, and the tolerance takes the ray caster's float rounding out of the choice.
constexpr double kHoleEps = 1e-3;
constexpr double kFaceMargin = 1e-3;  // "certainly on the solid": this far inside a face
constexpr double kEndMargin = 2e-3;   // and the segment's ends this far beyond the faces

inline bool in_hole(const WallSlab& w, double u, double z) {
  for (const WallSlab::Rect& h : w.holes)
    if (u >= h.u0 - kHoleEps && u <= h.u1 + kHoleEps && z >= h.z0 - kHoleEps &&
        z <= h.z1 + kHoleEps)
      return true;
  return false;
}

inline bool inside_face(const WallSlab& w, double u, double z) {
  return u >= kFaceMargin && u <= w.length - kFaceMargin && z >= w.z0 + kFaceMargin &&
         z <= w.z1 - kFaceMargin;
}

void wall_offsets(const std::vector<WallSlab>& walls, const Eigen::Vector3d& p, double* out) {
  for (std::size_t k = 0; k < walls.size(); ++k) out[k] = walls[k].normal.dot(p - walls[k].origin);
}

// What a segment does at the walls (see segment_through_opening for `opening`).
enum class AtWalls { nothing_known, opening, solid };

// `opening` if a→b passes through an opening of a wall: its ends lie strictly beyond the
// wall's two faces, on opposite sides, and it crosses each face within a hole of that
// wall. With `find_solid`, `solid` if it certainly crosses a wall's solid part: its ends
// lie kEndMargin or more beyond the faces and it crosses a face kFaceMargin or more inside
// the face's rectangle and outside every hole, so that the ray caster (float coordinates,
// first and last millimetre not tested) reports that hit too. Either way nothing beyond
// is visible; otherwise only the ray caster can tell.
//
// `wa[k]` and `wb[k]` are the signed distances of a and b from the centre plane of
// walls[k] (wall_offsets): the reference computes them once per position and sample.
AtWalls at_walls(const std::vector<WallSlab>& walls, const Eigen::Vector3d& a, const double* wa,
                 const Eigen::Vector3d& b, const double* wb, bool find_solid) {
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const WallSlab& w = walls[k];
    const double lo = std::min(wa[k], wb[k]), hi = std::max(wa[k], wb[k]);
    if (lo >= -w.half || hi <= w.half || (w.holes.empty() && !find_solid)) continue;
    bool in_holes = true, on_solid = false;
    for (double face : {-w.half, w.half}) {
      const Eigen::Vector3d q = a + (face - wa[k]) / (wb[k] - wa[k]) * (b - a);
      const double u = w.along.dot(q - w.origin), z = q.z();
      const bool hole = in_hole(w, u, z);
      in_holes = in_holes && hole;
      on_solid = on_solid || (!hole && inside_face(w, u, z));
    }
    if (in_holes) return AtWalls::opening;
    if (find_solid && on_solid && lo <= -w.half - kEndMargin && hi >= w.half + kEndMargin)
      return AtWalls::solid;
  }
  return AtWalls::nothing_known;
}

// The corners of the bounding box of some positions (4 when they share one height).
struct Hull {
  std::vector<Eigen::Vector3d> corners;
};

Hull hull_of(const std::vector<Eigen::Vector3d>& positions,
             const std::vector<std::uint32_t>& members) {
  Eigen::Vector3d lo = positions[members.front()], hi = lo;
  for (std::uint32_t m : members) {
    lo = lo.cwiseMin(positions[m]);
    hi = hi.cwiseMax(positions[m]);
  }
  Hull h;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d c((k & 1 ? hi : lo).x(), (k & 2 ? hi : lo).y(), (k & 4 ? hi : lo).z());
    if (std::find(h.corners.begin(), h.corners.end(), c) == h.corners.end()) h.corners.push_back(c);
  }
  return h;
}

// True if no optical centre in `hull` can see `sample` (whose segments end at `target`,
// `target_offsets` as in at_walls): none faces it, or each segment crosses some wall
// inside its face rectangle (kFaceMargin in) with its ends kEndMargin beyond the faces —
// at each face, through a hole or on the solid: at_walls says `opening` or `solid` for
// every one. The crossings of a face plane by the segments from the hull are the hull
// of the corners' crossings (a central projection keeps convexity), and the face
// rectangle is convex, so the corners decide.
bool hidden_from_hull(const SurfaceSample& sample, const Eigen::Vector3d& target,
                      const double* target_offsets, const Hull& hull,
                      const std::vector<WallSlab>& walls) {
  bool faces = false;
  for (const auto& k : hull.corners) faces = faces || sample.normal.dot(k - sample.position) > 0;
  if (!faces) return true;
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const WallSlab& w = walls[i];
    const double wt = target_offsets[i];
    if (std::abs(wt) < w.half + kEndMargin) continue;
    const double side = wt > 0 ? 1.0 : -1.0;
    bool all = true;
    for (const auto& k : hull.corners) {
      const double wk = w.normal.dot(k - w.origin);
      if (side * wk > -(w.half + kEndMargin)) {
        all = false;
        break;
      }
      for (double face : {-w.half, w.half}) {
        const Eigen::Vector3d q = target + (face - wt) / (wk - wt) * (k - target);
        if (!inside_face(w, w.along.dot(q - w.origin), q.z())) {
          all = false;
          break;
        }
      }
      if (!all) break;
    }
    if (all) return true;
  }
  return false;
}

unsigned thread_count(unsigned requested) {
  return requested ? requested : std::max(1u, std::thread::hardware_concurrency());
}

// --- hashing ------------------------------------------------------------------------

// Two independent 64-bit hashes of a byte stream, taken 8 bytes at a time through a
// full-avalanche mix, printed as 32 hex digits. The same sequence of calls gives the
// same hash on any run of the same build.
class Hasher {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (; n >= 8; p += 8, n -= 8) {
      std::uint64_t w;
      std::memcpy(&w, p, 8);
      word(w);
    }
    std::uint64_t tail = 0x80;  // marks the end, so that trailing zero bytes count
    for (std::size_t i = 0; i < n; ++i) tail = (tail << 8) | p[i];
    if (n) word(tail);
  }
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof v);
  }
  void text(const std::string& s) {
    value(static_cast<std::uint64_t>(s.size()));
    bytes(s.data(), s.size());
  }
  std::uint64_t first() const { return mix(a_ ^ count_); }
  std::string hex() const {
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(first()),
                  static_cast<unsigned long long>(mix(b_ + count_)));
    return buf;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static std::uint64_t mix(std::uint64_t x) {  // splitmix64's finalizer
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
  }
  void word(std::uint64_t w) {
    ++count_;
    a_ = rotl(a_ ^ mix(w), 29) * 0x9e3779b97f4a7c15ull;
    b_ = rotl(b_ + mix(w ^ 0x6a09e667f3bcc909ull), 37) * 0xc2b2ae3d27d4eb4full;
  }
  std::uint64_t a_ = 0xcbf29ce484222325ull;
  std::uint64_t b_ = 0x84222325cbf29ce4ull;
  std::uint64_t count_ = 0;
};

std::string key_of(const GroundTruth& truth, const std::vector<SurfaceSample>& samples,
                   double grid_spacing, double sample_spacing) {
  Hasher h;
  h.text("semioctree-coverage-reference");
  h.value(kRuleVersion);
  h.value(kCoverageSampleOffset);
  h.value(kPlanCell);
  h.value(grid_spacing);
  h.value(sample_spacing);
  const Scene& scene = truth.scene();
  const ScannerConfig& s = scene.scanner;
  for (double v : {s.height, s.elevation_min_deg, s.elevation_max_deg, s.min_range, s.max_range})
    h.value(v);
  h.value(scene.robot.start.x());
  h.value(scene.robot.start.y());
  h.value(scene.robot.radius);
  h.value(static_cast<std::uint8_t>(scene.survey_area.has_value()));
  if (scene.survey_area) {
    h.value(static_cast<std::uint64_t>(scene.survey_area->size()));
    for (const auto& p : *scene.survey_area) h.bytes(p.data(), 2 * sizeof(double));
  }
  const SceneTriangles& tri = truth.triangles();
  h.value(static_cast<std::uint64_t>(tri.vertices.size()));
  for (const auto& v : tri.vertices) h.bytes(v.data(), 3 * sizeof(float));
  h.value(static_cast<std::uint64_t>(tri.triangles.size()));
  for (const auto& t : tri.triangles) h.bytes(t.data(), 3 * sizeof(std::uint32_t));
  h.value(static_cast<std::uint64_t>(samples.size()));
  for (const auto& smp : samples) {
    h.bytes(smp.position.data(), 3 * sizeof(double));
    h.bytes(smp.normal.data(), 3 * sizeof(double));
  }
  return h.hex();
}

// --- the reference ------------------------------------------------------------------

void fill_points(const std::vector<SurfaceSample>& samples, CoverageReference& ref) {
  ref.points.clear();
  ref.points.reserve(ref.visible.size());
  for (std::uint32_t i : ref.visible) ref.points.push_back(samples[i].position);
}

CoverageReference compute(const GroundTruth& truth, const std::vector<SurfaceSample>& samples,
                          double grid_spacing, double sample_spacing, unsigned threads) {
  CoverageReference ref;
  ref.grid_spacing = grid_spacing;
  ref.sample_spacing = sample_spacing;
  ref.sample_count = samples.size();
  ref.positions = coverage_grid_positions(truth, grid_spacing);
  if (samples.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("coverage reference: too many surface samples");
  const std::size_t n = samples.size();
  const std::size_t np = ref.positions.size();
  if (n == 0 || np == 0) return ref;

  // Positions nearest first: one order per square bucket of the xy-plane, sorted by the
  // distance from the bucket's centre (close enough to each sample's own order).
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& s : samples) {
    lo = lo.cwiseMin(s.position.head<2>());
    hi = hi.cwiseMax(s.position.head<2>());
  }
  const double bucket = std::max({grid_spacing, (hi - lo).maxCoeff() / 256.0, 1e-3});
  const long bx = static_cast<long>((hi.x() - lo.x()) / bucket) + 1;
  auto bucket_of = [&](const Eigen::Vector3d& p) {
    const long ix = static_cast<long>((p.x() - lo.x()) / bucket);
    const long iy = static_cast<long>((p.y() - lo.y()) / bucket);
    return iy * bx + ix;
  };
  std::vector<long> used;
  used.reserve(n);
  for (const auto& s : samples) used.push_back(bucket_of(s.position));
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::vector<std::vector<std::uint32_t>> orders(used.size());
  for (std::size_t k = 0; k < used.size(); ++k) {
    const Eigen::Vector2d centre =
        lo + bucket * Eigen::Vector2d(used[k] % bx + 0.5, static_cast<double>(used[k] / bx) + 0.5);
    std::vector<std::pair<double, std::uint32_t>> by_distance(np);
    for (std::size_t i = 0; i < np; ++i)
      by_distance[i] = {(ref.positions[i].head<2>() - centre).squaredNorm(),
                        static_cast<std::uint32_t>(i)};
    std::sort(by_distance.begin(), by_distance.end());
    orders[k].reserve(np);
    for (const auto& d : by_distance) orders[k].push_back(d.second);
  }
  auto order_of = [&](const Eigen::Vector3d& p) -> const std::vector<std::uint32_t>& {
    const long b = bucket_of(p);
    return orders[static_cast<std::size_t>(std::lower_bound(used.begin(), used.end(), b) -
                                           used.begin())];
  };

  // Each sample is tested on its own (early exit at the first position that sees it),
  // so the result does not depend on how samples are split among threads. The position
  // that saw the previous sample is tried first: samples come face by face.
  const Limits lim = limits_of(truth.scene().scanner);
  const std::vector<WallSlab> walls = wall_slabs(truth.scene());
  // Boxes of the positions, all of them and tiles of 4 x 4 grid steps: a sample hidden
  // from a box is not tested position by position there (the surfaces behind the room's
  // walls and the outer faces: most samples of a building).
  std::vector<std::uint32_t> all_positions(np);
  for (std::size_t p = 0; p < np; ++p) all_positions[p] = static_cast<std::uint32_t>(p);
  const Hull whole = hull_of(ref.positions, all_positions);
  std::vector<std::uint32_t> tile_of(np);
  std::vector<Hull> tiles;
  {
    const double side = 4 * grid_spacing;
    std::vector<std::pair<std::pair<long, long>, std::uint32_t>> keyed;
    for (std::size_t p = 0; p < np; ++p)
      keyed.push_back({{static_cast<long>(std::floor(ref.positions[p].y() / side)),
                        static_cast<long>(std::floor(ref.positions[p].x() / side))},
                       static_cast<std::uint32_t>(p)});
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t i = 0; i < keyed.size();) {
      std::vector<std::uint32_t> members;
      std::size_t j = i;
      for (; j < keyed.size() && keyed[j].first == keyed[i].first; ++j) {
        members.push_back(keyed[j].second);
        tile_of[keyed[j].second] = static_cast<std::uint32_t>(tiles.size());
      }
      tiles.push_back(hull_of(ref.positions, members));
      i = j;
    }
  }
  const std::size_t nw = walls.size();
  std::vector<double> position_offsets(np * nw);
  for (std::size_t p = 0; p < np; ++p)
    wall_offsets(walls, ref.positions[p], position_offsets.data() + p * nw);
  std::vector<std::uint8_t> seen(n, 0);
  std::atomic<std::size_t> next{0};
  std::atomic<std::uint64_t> queries{0};
  constexpr std::size_t kChunk = 2048;
  auto work = [&] {
    std::uint64_t local_queries = 0;
    std::vector<double> target_offsets(nw);
    std::vector<std::uint8_t> tile_hidden(tiles.size());  // 0 not known, 1 hidden, 2 not
    for (std::size_t begin = next.fetch_add(kChunk); begin < n; begin = next.fetch_add(kChunk)) {
      std::uint32_t last = std::numeric_limits<std::uint32_t>::max();
      const std::size_t end = std::min(n, begin + kChunk);
      for (std::size_t i = begin; i < end; ++i) {
        const SurfaceSample& s = samples[i];
        const Eigen::Vector3d target = target_of(s);
        wall_offsets(walls, target, target_offsets.data());
        if (hidden_from_hull(s, target, target_offsets.data(), whole, walls)) continue;
        std::fill(tile_hidden.begin(), tile_hidden.end(), 0);
        auto test = [&](std::uint32_t p) {
          const Eigen::Vector3d& c = ref.positions[p];
          if (!within_limits(lim, s, c)) return false;
          std::uint8_t& hidden = tile_hidden[tile_of[p]];
          if (!hidden)
            hidden = hidden_from_hull(s, target, target_offsets.data(), tiles[tile_of[p]], walls)
                         ? 1
                         : 2;
          if (hidden == 1) return false;
          // Through an opening (not visible by the rule) or into a wall (not visible
          // either, known without a ray query: most samples outside the room).
          if (at_walls(walls, c, position_offsets.data() + p * nw, target, target_offsets.data(),
                       true) != AtWalls::nothing_known)
            return false;
          ++local_queries;
          return truth.segment_free(c, target);
        };
        bool visible = false;
        if (last != std::numeric_limits<std::uint32_t>::max() && test(last)) visible = true;
        if (!visible)
          for (std::uint32_t p : order_of(s.position)) {
            if (p == last || !test(p)) continue;
            visible = true;
            last = p;
            break;
          }
        seen[i] = visible;
      }
    }
    queries += local_queries;
  };
  const unsigned nt =
      std::min<unsigned>(thread_count(threads), static_cast<unsigned>((n + kChunk - 1) / kChunk));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < nt; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();

  for (std::size_t i = 0; i < n; ++i)
    if (seen[i]) ref.visible.push_back(static_cast<std::uint32_t>(i));
  ref.segment_queries = queries;
  fill_points(samples, ref);
  return ref;
}

// --- the cache file -----------------------------------------------------------------

constexpr char kMagic[8] = {'S', 'O', 'C', 'O', 'V', 'R', 'E', 'F'};

class Writer {
 public:
  template <typename T>
  void value(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    out_.append(p, sizeof v);
  }
  void raw(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(const std::string& in, std::size_t end) : in_(in), end_(end) {}
  template <typename T>
  bool value(T& v) {
    return raw(&v, sizeof v);
  }
  bool raw(void* p, std::size_t n) {
    if (n > end_ - pos_) return false;
    std::memcpy(p, in_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  std::size_t remaining() const { return end_ - pos_; }

 private:
  const std::string& in_;
  std::size_t end_;
  std::size_t pos_ = 0;
};

std::uint64_t checksum(const char* data, std::size_t n) {
  Hasher h;
  h.bytes(data, n);
  return h.first();
}

std::string serialize(const CoverageReference& ref) {
  Writer w;
  w.raw(kMagic, sizeof kMagic);
  w.value(kRuleVersion);
  w.value(static_cast<std::uint32_t>(ref.key.size()));
  w.raw(ref.key.data(), ref.key.size());
  w.value(ref.grid_spacing);
  w.value(ref.sample_spacing);
  w.value(static_cast<std::uint64_t>(ref.sample_count));
  w.value(static_cast<std::uint64_t>(ref.positions.size()));
  for (const auto& p : ref.positions) w.raw(p.data(), 3 * sizeof(double));
  w.value(static_cast<std::uint64_t>(ref.visible.size()));
  w.raw(ref.visible.data(), ref.visible.size() * sizeof(std::uint32_t));
  w.value(checksum(w.str().data(), w.str().size()));
  return std::move(w.str());
}

// Parses a cache file; false (and `ref` unusable) unless every check passes.
bool deserialize(const std::string& data, const std::string& key, double grid_spacing,
                 double sample_spacing, std::size_t sample_count, CoverageReference& ref) {
  constexpr std::size_t kSum = sizeof(std::uint64_t);
  if (data.size() < sizeof kMagic + kSum) return false;
  std::uint64_t stored = 0;
  std::memcpy(&stored, data.data() + data.size() - kSum, kSum);
  if (stored != checksum(data.data(), data.size() - kSum)) return false;
  Reader r(data, data.size() - kSum);
  char magic[sizeof kMagic];
  std::uint32_t version = 0, key_len = 0;
  if (!r.raw(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0) return false;
  if (!r.value(version) || version != kRuleVersion) return false;
  if (!r.value(key_len) || key_len != key.size()) return false;
  std::string stored_key(key_len, '\0');
  if (!r.raw(stored_key.data(), key_len) || stored_key != key) return false;
  double g = 0, s = 0;
  std::uint64_t count = 0, np = 0, nv = 0;
  if (!r.value(g) || !r.value(s) || g != grid_spacing || s != sample_spacing) return false;
  if (!r.value(count) || count != sample_count) return false;
  if (!r.value(np) || np > r.remaining() / (3 * sizeof(double))) return false;
  ref.positions.resize(np);
  for (auto& p : ref.positions)
    if (!r.raw(p.data(), 3 * sizeof(double))) return false;
  if (!r.value(nv) || nv > count || nv * sizeof(std::uint32_t) != r.remaining()) return false;
  ref.visible.resize(nv);
  if (!r.raw(ref.visible.data(), nv * sizeof(std::uint32_t))) return false;
  for (std::size_t i = 0; i < ref.visible.size(); ++i)
    if (ref.visible[i] >= count || (i > 0 && ref.visible[i] <= ref.visible[i - 1])) return false;
  ref.grid_spacing = g;
  ref.sample_spacing = s;
  ref.sample_count = count;
  return true;
}

bool read_file(const fs::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return false;
  out = ss.str();
  return true;
}

// Writes `data` to a temporary name in the same directory, then renames it over `path`.
bool write_atomically(const fs::path& path, const std::string& data) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  std::random_device rd;
  const fs::path tmp =
      path.string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(rd());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return false;
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    out.flush();
    if (!out) {
      out.close();
      fs::remove(tmp, ec);
      return false;
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return false;
  }
  return true;
}

// --- measuring ----------------------------------------------------------------------

// Points hashed by cell (open addressing over the sorted cell keys).
class PointGrid {
 public:
  PointGrid(std::vector<Eigen::Vector3d> points, double cell) : cell_(cell) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    keyed.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
      keyed.emplace_back(cell_key(points[i]), static_cast<std::uint32_t>(i));
    std::sort(keyed.begin(), keyed.end());
    points_.reserve(points.size());
    for (const auto& k : keyed) points_.push_back(points[k.second]);
    std::size_t capacity = 16;
    std::size_t cells = 0;
    for (std::size_t i = 0; i < keyed.size(); ++i)
      if (i == 0 || keyed[i].first != keyed[i - 1].first) ++cells;
    while (capacity < 2 * cells) capacity *= 2;
    slots_.assign(capacity, Slot{});
    for (std::size_t i = 0; i < keyed.size();) {
      std::size_t j = i;
      while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
      std::size_t h = mix(keyed[i].first) & (capacity - 1);
      while (slots_[h].count) h = (h + 1) & (capacity - 1);
      slots_[h] = {keyed[i].first, static_cast<std::uint32_t>(i),
                   static_cast<std::uint32_t>(j - i)};
      i = j;
    }
  }

  bool any_within(const Eigen::Vector3d& q, double radius) const {
    if (slots_.empty()) return false;
    const double r2 = radius * radius;
    const long ix = index(q.x()), iy = index(q.y()), iz = index(q.z());
    // Own cell first: it holds the match in most cases.
    for (int pass = 0; pass < 2; ++pass)
      for (long dz = -1; dz <= 1; ++dz)
        for (long dy = -1; dy <= 1; ++dy)
          for (long dx = -1; dx <= 1; ++dx) {
            const bool own = dx == 0 && dy == 0 && dz == 0;
            if (own != (pass == 0)) continue;
            const Slot* s = find(pack(ix + dx, iy + dy, iz + dz));
            if (!s) continue;
            for (std::uint32_t k = s->begin; k < s->begin + s->count; ++k)
              if ((points_[k] - q).squaredNorm() <= r2) return true;
          }
    return false;
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t begin = 0;
    std::uint32_t count = 0;  // 0: empty slot
  };
  long index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  static std::uint64_t pack(long x, long y, long z) {
    constexpr long kBias = 1L << 20;  // ±1 M cells a side
    auto part = [](long v) {
      return static_cast<std::uint64_t>(std::clamp(v + kBias, 0L, (1L << 21) - 1));
    };
    return part(x) | part(y) << 21 | part(z) << 42;
  }
  std::uint64_t cell_key(const Eigen::Vector3d& p) const {
    return pack(index(p.x()), index(p.y()), index(p.z()));
  }
  static std::uint64_t mix(std::uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ull;
    return x ^ (x >> 33);
  }
  const Slot* find(std::uint64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t h = mix(key) & mask;; h = (h + 1) & mask) {
      if (!slots_[h].count) return nullptr;
      if (slots_[h].key == key) return &slots_[h];
    }
  }

  double cell_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<Slot> slots_;
};

std::vector<bool> flags(const CoverageReference& reference, std::vector<Eigen::Vector3d> points,
                        double tolerance) {
  if (!(tolerance > 0)) throw std::invalid_argument("measure_coverage: tolerance must be > 0");
  points.erase(std::remove_if(points.begin(), points.end(),
                              [](const Eigen::Vector3d& p) { return !p.allFinite(); }),
               points.end());
  if (points.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("measure_coverage: too many points");
  std::vector<bool> out(reference.points.size(), false);
  if (points.empty()) return out;
  const PointGrid grid(std::move(points), tolerance);
  for (std::size_t i = 0; i < reference.points.size(); ++i)
    out[i] = grid.any_within(reference.points[i], tolerance);
  return out;
}

Coverage measure(const CoverageReference& reference, std::vector<Eigen::Vector3d> points,
                 double tolerance) {
  return count_covered(flags(reference, std::move(points), tolerance));
}

}  // namespace

Coverage count_covered(const std::vector<bool>& covered) {
  Coverage c;
  c.reference_points = covered.size();
  for (bool f : covered) c.covered += f;
  c.percent = c.reference_points
                  ? 100.0 * static_cast<double>(c.covered) / static_cast<double>(c.reference_points)
                  : 0.0;
  return c;
}

bool segment_through_opening(const Scene& scene, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b) {
  const std::vector<WallSlab> walls = wall_slabs(scene);
  std::vector<double> wa(walls.size()), wb(walls.size());
  wall_offsets(walls, a, wa.data());
  wall_offsets(walls, b, wb.data());
  return at_walls(walls, a, wa.data(), b, wb.data(), false) == AtWalls::opening;
}

bool sample_in_line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                             const Eigen::Vector3d& optical_centre) {
  return within_limits(limits_of(truth.scene().scanner), sample, optical_centre) &&
         line_of_sight(truth, sample, optical_centre);
}

bool sample_visible_from(const GroundTruth& truth, const SurfaceSample& sample,
                         const Eigen::Vector3d& optical_centre) {
  return within_limits(limits_of(truth.scene().scanner), sample, optical_centre) &&
         !segment_through_opening(truth.scene(), optical_centre, target_of(sample)) &&
         line_of_sight(truth, sample, optical_centre);
}

std::vector<Eigen::Vector3d> coverage_grid_positions(const GroundTruth& truth,
                                                     double grid_spacing) {
  if (!(grid_spacing > 0))
    throw std::invalid_argument("coverage reference: grid spacing must be > 0");
  const FloorPlan plan = truth.floor_plan(kPlanCell);
  const Scene& scene = truth.scene();
  const Eigen::Vector2d start = scene.robot.start;
  const Eigen::Vector2d far = plan.origin + plan.cell * Eigen::Vector2d(plan.nx, plan.ny);
  const long i0 = static_cast<long>(std::ceil((plan.origin.x() - start.x()) / grid_spacing));
  const long i1 = static_cast<long>(std::floor((far.x() - start.x()) / grid_spacing));
  const long j0 = static_cast<long>(std::ceil((plan.origin.y() - start.y()) / grid_spacing));
  const long j1 = static_cast<long>(std::floor((far.y() - start.y()) / grid_spacing));
  std::vector<Eigen::Vector3d> out;
  for (long j = j0; j <= j1; ++j)
    for (long i = i0; i <= i1; ++i) {
      const Eigen::Vector2d p = start + grid_spacing * Eigen::Vector2d(i, j);
      if (plan.in_survey_area(p) && plan.reachable_near(p) && truth.standing_free(p))
        out.emplace_back(p.x(), p.y(), scene.scanner.height);
    }
  return out;
}

CoverageReference compute_coverage_reference(const GroundTruth& truth, double grid_spacing,
                                             double sample_spacing, unsigned threads) {
  if (!(sample_spacing > 0))
    throw std::invalid_argument("coverage reference: sample spacing must be > 0");
  const auto t0 = Clock::now();
  const std::vector<SurfaceSample> samples = truth.surface_samples(sample_spacing);
  CoverageReference ref = compute(truth, samples, grid_spacing, sample_spacing, threads);
  ref.key = key_of(truth, samples, grid_spacing, sample_spacing);
  ref.seconds = seconds_since(t0);
  return ref;
}

std::string coverage_cache_key(const GroundTruth& truth, double grid_spacing,
                               double sample_spacing) {
  return key_of(truth, truth.surface_samples(sample_spacing), grid_spacing, sample_spacing);
}

CoverageReference load_or_compute_coverage_reference(const GroundTruth& truth,
                                                     const std::string& cache_dir,
                                                     double grid_spacing, double sample_spacing,
                                                     unsigned threads) {
  if (!(sample_spacing > 0))
    throw std::invalid_argument("coverage reference: sample spacing must be > 0");
  const auto t0 = Clock::now();
  const std::vector<SurfaceSample> samples = truth.surface_samples(sample_spacing);
  const std::string key = key_of(truth, samples, grid_spacing, sample_spacing);
  if (cache_dir.empty()) {
    CoverageReference ref = compute(truth, samples, grid_spacing, sample_spacing, threads);
    ref.key = key;
    ref.seconds = seconds_since(t0);
    return ref;
  }
  const fs::path file = fs::path(cache_dir) / ("coverage-" + key + ".bin");

  std::string data;
  CoverageReference ref;
  if (read_file(file, data) &&
      deserialize(data, key, grid_spacing, sample_spacing, samples.size(), ref)) {
    ref.key = key;
    ref.from_cache = true;
    ref.cache_file = file.string();
    fill_points(samples, ref);
    ref.seconds = seconds_since(t0);
    return ref;
  }
  ref = compute(truth, samples, grid_spacing, sample_spacing, threads);
  ref.key = key;
  if (write_atomically(file, serialize(ref))) ref.cache_file = file.string();
  ref.seconds = seconds_since(t0);
  return ref;
}

std::string default_cache_dir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && xdg[0] == '/') return (fs::path(xdg) / "semioctree").string();
  const char* home = std::getenv("HOME");
  if (home && home[0] != '\0') return (fs::path(home) / ".cache" / "semioctree").string();
  std::error_code ec;
  const fs::path tmp = fs::temp_directory_path(ec);
  return ((ec ? fs::path("/tmp") : tmp) / "semioctree-cache").string();
}

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3d>& measured_points_world,
                          double tolerance) {
  return measure(reference, measured_points_world, tolerance);
}

namespace {
std::vector<Eigen::Vector3d> to_double(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(p.cast<double>());
  return out;
}
}  // namespace

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3f>& measured_points_world,
                          double tolerance) {
  return measure(reference, to_double(measured_points_world), tolerance);
}

std::vector<bool> covered_samples(const CoverageReference& reference,
                                  const std::vector<Eigen::Vector3f>& measured_points_world,
                                  double tolerance) {
  return flags(reference, to_double(measured_points_world), tolerance);
}

std::string part_label(const Scene& scene, const PartRef& part) {
  std::string label = std::string(to_string(part.kind)) + "[" + std::to_string(part.index) + "]";
  const auto i = static_cast<std::size_t>(part.index);
  std::string name;
  if (part.kind == PartKind::box && i < scene.boxes.size()) name = scene.boxes[i].name;
  if (part.kind == PartKind::cylinder && i < scene.cylinders.size()) name = scene.cylinders[i].name;
  if (part.kind == PartKind::mesh && i < scene.meshes.size()) name = scene.meshes[i].file;
  return name.empty() ? label : label + " (" + name + ")";
}

MissedSamples explain_missed_samples(const GroundTruth& truth, const CoverageReference& reference,
                                     const std::vector<bool>& covered,
                                     const std::vector<Eigen::Vector3d>& optical_centres,
                                     unsigned threads) {
  if (covered.size() != reference.visible.size())
    throw std::invalid_argument("explain_missed_samples: one covered flag per reference sample");
  const std::vector<SurfaceSample> samples = truth.surface_samples(reference.sample_spacing);
  if (samples.size() != reference.sample_count)
    throw std::invalid_argument("explain_missed_samples: the reference is of another scene");
  std::vector<std::size_t> missed;
  for (std::size_t i = 0; i < covered.size(); ++i)
    if (!covered[i]) missed.push_back(i);

  // The reference's rule, with the walls prepared once.
  const Limits lim = limits_of(truth.scene().scanner);
  const std::vector<WallSlab> walls = wall_slabs(truth.scene());
  std::vector<std::vector<double>> centre_offsets;
  for (const Eigen::Vector3d& c : optical_centres) {
    centre_offsets.emplace_back(walls.size());
    wall_offsets(walls, c, centre_offsets.back().data());
  }
  std::vector<std::uint8_t> in_view(missed.size(), 0);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    std::vector<double> target_offsets(walls.size());
    for (std::size_t m; (m = next.fetch_add(1)) < missed.size();) {
      const SurfaceSample& s = samples[reference.visible[missed[m]]];
      const Eigen::Vector3d target = target_of(s);
      wall_offsets(walls, target, target_offsets.data());
      for (std::size_t k = 0; k < optical_centres.size() && !in_view[m]; ++k) {
        const Eigen::Vector3d& c = optical_centres[k];
        in_view[m] = within_limits(lim, s, c) &&
                     at_walls(walls, c, centre_offsets[k].data(), target, target_offsets.data(),
                              false) != AtWalls::opening &&
                     line_of_sight(truth, s, c);
      }
    }
  };
  const unsigned nt = std::min<unsigned>(
      thread_count(threads), static_cast<unsigned>(std::max<std::size_t>(1, missed.size() / 256)));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < nt; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();

  MissedSamples out;
  std::vector<MissedPart> parts;
  auto part_of = [&](const PartRef& p) -> MissedPart& {
    for (MissedPart& q : parts)
      if (q.part.kind == p.kind && q.part.index == p.index) return q;
    parts.push_back({p, part_label(truth.scene(), p), 0, 0});
    return parts.back();
  };
  for (std::size_t m = 0; m < missed.size(); ++m) {
    MissedPart& part = part_of(samples[reference.visible[missed[m]]].part);
    if (in_view[m]) {
      ++out.in_view;
      ++part.in_view;
      out.in_view_samples.push_back(static_cast<std::uint32_t>(missed[m]));
    } else {
      ++out.hidden;
      ++part.hidden;
      out.hidden_samples.push_back(static_cast<std::uint32_t>(missed[m]));
    }
  }
  std::stable_sort(parts.begin(), parts.end(), [](const MissedPart& a, const MissedPart& b) {
    return a.in_view + a.hidden > b.in_view + b.hidden;
  });
  out.parts = std::move(parts);
  return out;
}

namespace {

// The sets as 64-bit words: the plan searches take unions and counts of them many times.
struct PackedSets {
  std::size_t words = 0, samples = 0;
  std::vector<std::uint64_t> bits;  // sets × words
  explicit PackedSets(const std::vector<std::vector<bool>>& covered) {
    if (covered.empty()) throw std::invalid_argument("coverage plan: no scan positions");
    samples = covered[0].size();
    words = (samples + 63) / 64;
    bits.assign(covered.size() * words, 0);
    for (std::size_t v = 0; v < covered.size(); ++v) {
      if (covered[v].size() != samples)
        throw std::invalid_argument("coverage plan: the sets differ in size");
      for (std::size_t i = 0; i < samples; ++i)
        if (covered[v][i]) bits[v * words + i / 64] |= std::uint64_t(1) << (i % 64);
    }
  }
  std::size_t sets() const { return bits.size() / std::max<std::size_t>(words, 1); }
  const std::uint64_t* set(std::size_t v) const { return bits.data() + v * words; }
  std::vector<std::uint64_t> union_of(const std::vector<std::size_t>& views,
                                      std::size_t skip = SIZE_MAX) const {
    std::vector<std::uint64_t> u(words, 0);
    for (std::size_t k = 0; k < views.size(); ++k)
      if (k != skip)
        for (std::size_t w = 0; w < words; ++w) u[w] |= set(views[k])[w];
    return u;
  }
  // The position adding most to `u` (lowest index on ties) and the size of the union.
  std::pair<std::size_t, std::size_t> best_addition(const std::vector<std::uint64_t>& u) const {
    std::size_t base = 0;
    for (std::uint64_t x : u) base += std::size_t(__builtin_popcountll(x));
    std::size_t best = 0, best_gain = 0;
    for (std::size_t v = 0; v < sets(); ++v) {
      std::size_t gain = 0;
      for (std::size_t w = 0; w < words; ++w)
        gain += std::size_t(__builtin_popcountll(set(v)[w] & ~u[w]));
      if (gain > best_gain) best = v, best_gain = gain;
    }
    return {best, base + best_gain};
  }
  double percent(std::size_t count) const {
    return samples ? 100.0 * double(count) / double(samples) : 0.0;
  }
};

}  // namespace

CoveragePlan greedy_coverage_plan(const std::vector<std::vector<bool>>& covered, std::size_t first,
                                  std::size_t scans) {
  const PackedSets sets(covered);
  if (first >= sets.sets()) throw std::invalid_argument("coverage plan: no such first position");
  CoveragePlan plan;
  plan.views.push_back(first);
  std::size_t count = 0;
  for (std::size_t w = 0; w < sets.words; ++w)
    count += std::size_t(__builtin_popcountll(sets.set(first)[w]));
  while (plan.views.size() < scans) {
    const auto [v, n] = sets.best_addition(sets.union_of(plan.views));
    plan.views.push_back(v);
    count = n;
  }
  plan.percent = sets.percent(count);
  return plan;
}

CoveragePlan improve_coverage_plan(const std::vector<std::vector<bool>>& covered,
                                   CoveragePlan plan) {
  const PackedSets sets(covered);
  if (plan.views.empty()) throw std::invalid_argument("coverage plan: no first position");
  auto count_of = [&](const std::vector<std::size_t>& views) {
    std::size_t n = 0;
    for (std::uint64_t x : sets.union_of(views)) n += std::size_t(__builtin_popcountll(x));
    return n;
  };
  std::size_t count = count_of(plan.views);
  for (bool improved = true; improved;) {
    improved = false;
    for (std::size_t k = 1; k < plan.views.size(); ++k) {
      const auto [v, n] = sets.best_addition(sets.union_of(plan.views, k));
      if (n > count) {
        plan.views[k] = v;
        count = n;
        improved = true;
      }
    }
  }
  plan.percent = sets.percent(count);
  return plan;
}

}  // namespace semioctree::sim
