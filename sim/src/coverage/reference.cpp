// The coverage reference: the grid of scan positions, the search for the samples they
// see, and loading it from the cache or computing and caching it.
#include "semioctree/sim/coverage/reference.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "coverage/reference_cache.h"
#include "coverage/visibility_rule.h"
#include "coverage/wall_culling.h"
#include "parallel.h"

namespace semioctree::sim {

namespace {

using Clock = std::chrono::steady_clock;
using detail::PositionBox;
using detail::WallSlab;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

constexpr std::uint32_t kNoPosition = std::numeric_limits<std::uint32_t>::max();

// Where the walls shut the rooms of the floor plan off from each other (docs/coverage.md,
// "Rooms"): when every wall reaches from the lowest sample (or the scanner, if lower) to
// the highest (or the scanner), a segment from a position in one room to a sample in
// another crosses a wall within its height, so through its solid part or through an
// opening: visible by neither rule. A sample is then searched among the positions of its
// room and those standing in no room (in a doorway); a sample of no room, among all.
class RoomsOfPlan {
 public:
  RoomsOfPlan(const GroundTruth& truth, const FloorPlan& plan,
              const std::vector<SurfaceSample>& samples)
      : plan_(plan) {
    const Scene& scene = truth.scene();
    double lo = scene.scanner.height, hi = lo;
    for (const SurfaceSample& s : samples)
      lo = std::min(lo, s.position.z()), hi = std::max(hi, s.position.z());
    shut_ = !scene.walls.empty() && !plan.room_area.empty();
    for (const Wall& w : scene.walls) shut_ = shut_ && w.z0 <= lo && w.z1 >= hi;
  }

  int count() const { return static_cast<int>(plan_.room_area.size()); }

  // The room of a scan position (-1: none, in a doorway or a wall's footprint).
  int of_position(const Eigen::Vector3d& c) const {
    return shut_ ? plan_.room_at(c.head<2>()) : -1;
  }

  // The room a sample faces: walking from it along its normal, two cells in half cells,
  // past the wall footprint it may lie on, every cell then is of one room. -1 (search
  // every position) if the walk meets two rooms, a wall after a room, or none.
  int of_sample(const SurfaceSample& s) const {
    if (!shut_) return -1;
    int room = -1;
    for (int k = 0; k <= 4; ++k) {
      const Eigen::Vector3d q = s.position + (0.5 * k * plan_.cell) * s.normal;
      const int r = plan_.room_at(q.head<2>());
      if (r < 0 && room >= 0) return -1;
      if (r >= 0 && room >= 0 && r != room) return -1;
      if (r >= 0) room = r;
    }
    return room;
  }

 private:
  const FloorPlan& plan_;
  bool shut_ = false;
};

// The scan positions nearest first, per sample: one order per square bucket of the
// xy-plane and room of the sample (RoomsOfPlan; -1 for all positions), sorted by the
// distance from the bucket's centre (close enough to each sample's own order).
class NearestFirstOrders {
 public:
  NearestFirstOrders(const std::vector<SurfaceSample>& samples, const RoomsOfPlan& rooms,
                     const std::vector<Eigen::Vector3d>& positions, double grid_spacing)
      : rooms_(rooms.count() + 1) {
    lo_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d hi = -lo_;
    for (const auto& s : samples) {
      lo_ = lo_.cwiseMin(s.position.head<2>());
      hi = hi.cwiseMax(s.position.head<2>());
    }
    bucket_ = std::max({grid_spacing, (hi - lo_).maxCoeff() / 256.0, 1e-3});
    bx_ = static_cast<long>((hi.x() - lo_.x()) / bucket_) + 1;
    used_.reserve(samples.size());
    for (const auto& s : samples) used_.push_back(key_of(s.position, rooms.of_sample(s)));
    std::sort(used_.begin(), used_.end());
    used_.erase(std::unique(used_.begin(), used_.end()), used_.end());
    std::vector<int> position_room(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
      position_room[i] = rooms.of_position(positions[i]);
    orders_.resize(used_.size());
    for (std::size_t k = 0; k < used_.size(); ++k) {
      const long bucket = used_[k] / rooms_;
      const int room = static_cast<int>(used_[k] % rooms_) - 1;
      const Eigen::Vector2d centre =
          lo_ +
          bucket_ * Eigen::Vector2d(bucket % bx_ + 0.5, static_cast<double>(bucket / bx_) + 0.5);
      std::vector<std::pair<double, std::uint32_t>> by_distance;
      for (std::size_t i = 0; i < positions.size(); ++i)
        if (room < 0 || position_room[i] < 0 || position_room[i] == room)
          by_distance.emplace_back((positions[i].head<2>() - centre).squaredNorm(),
                                   static_cast<std::uint32_t>(i));
      std::sort(by_distance.begin(), by_distance.end());
      orders_[k].reserve(by_distance.size());
      for (const auto& d : by_distance) orders_[k].push_back(d.second);
    }
  }

  // The order for a sample at p facing `room` (as given to the constructor).
  const std::vector<std::uint32_t>& of(const Eigen::Vector3d& p, int room) const {
    const long key = key_of(p, room);
    return orders_[static_cast<std::size_t>(std::lower_bound(used_.begin(), used_.end(), key) -
                                            used_.begin())];
  }

 private:
  long key_of(const Eigen::Vector3d& p, int room) const {
    const long ix = static_cast<long>((p.x() - lo_.x()) / bucket_);
    const long iy = static_cast<long>((p.y() - lo_.y()) / bucket_);
    return (iy * bx_ + ix) * rooms_ + (room + 1);
  }

  long rooms_;  // rooms + 1: the keys' room part
  Eigen::Vector2d lo_;
  double bucket_ = 0;
  long bx_ = 0;
  std::vector<long> used_;                          // keys (bucket, room) of samples, ascending
  std::vector<std::vector<std::uint32_t>> orders_;  // per used key
};

// Boxes of the positions, all of them and tiles of 4 × 4 grid steps: a sample hidden from
// a box is not tested position by position there (the surfaces behind the room's walls
// and the outer faces: most samples of a building).
struct PositionTiles {
  PositionBox whole;
  std::vector<PositionBox> tiles;
  std::vector<std::uint32_t> tile_of;  // per position
};

PositionTiles position_tiles(const std::vector<Eigen::Vector3d>& positions, double grid_spacing) {
  const std::size_t np = positions.size();
  PositionTiles out;
  std::vector<std::uint32_t> all_positions(np);
  for (std::size_t p = 0; p < np; ++p) all_positions[p] = static_cast<std::uint32_t>(p);
  out.whole = detail::box_of(positions, all_positions);
  out.tile_of.resize(np);
  const double side = 4 * grid_spacing;
  std::vector<std::pair<std::pair<long, long>, std::uint32_t>> keyed;
  for (std::size_t p = 0; p < np; ++p)
    keyed.push_back({{static_cast<long>(std::floor(positions[p].y() / side)),
                      static_cast<long>(std::floor(positions[p].x() / side))},
                     static_cast<std::uint32_t>(p)});
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 0; i < keyed.size();) {
    std::vector<std::uint32_t> members;
    std::size_t j = i;
    for (; j < keyed.size() && keyed[j].first == keyed[i].first; ++j) {
      members.push_back(keyed[j].second);
      out.tile_of[keyed[j].second] = static_cast<std::uint32_t>(out.tiles.size());
    }
    out.tiles.push_back(detail::box_of(positions, members));
    i = j;
  }
  return out;
}

// What the threads of the search share (read only).
struct VisibilitySearch {
  VisibilitySearch(const GroundTruth& truth, const FloorPlan& plan,
                   const std::vector<SurfaceSample>& samples,
                   const std::vector<Eigen::Vector3d>& positions, double grid_spacing)
      : truth(truth),
        positions(positions),
        limits(detail::scanner_limits(truth.scene().scanner)),
        walls(detail::wall_slabs(truth.scene())),
        tiles(position_tiles(positions, grid_spacing)),
        rooms(truth, plan, samples),
        orders(samples, rooms, positions, grid_spacing) {
    position_offsets.resize(positions.size() * walls.size());
    for (std::size_t p = 0; p < positions.size(); ++p)
      detail::wall_offsets(walls, positions[p], position_offsets.data() + p * walls.size());
  }

  const GroundTruth& truth;
  const std::vector<Eigen::Vector3d>& positions;
  detail::ScannerLimits limits;
  std::vector<WallSlab> walls;
  std::vector<double> position_offsets;  // wall_offsets of each position, walls.size() each
  PositionTiles tiles;
  RoomsOfPlan rooms;
  NearestFirstOrders orders;
};

// One thread's state of the search.
struct SearchScratch {
  explicit SearchScratch(const VisibilitySearch& search)
      : target_offsets(search.walls.size()), tile_hidden(search.tiles.tiles.size()) {}
  std::vector<double> target_offsets;     // wall_offsets of the current sample's target
  std::vector<std::uint8_t> tile_hidden;  // per tile: 0 not known yet, 1 hidden, 2 not
  std::uint64_t queries = 0;              // ray queries made
  std::uint64_t by_room = 0;              // samples searched among their room's positions
};

// sample_visible_from(s, positions[p]), with the walls deciding where they can: the tile
// of p hidden from s, or the segment through an opening or into a wall's solid part.
bool seen_from(const VisibilitySearch& search, SearchScratch& scratch, const SurfaceSample& s,
               const Eigen::Vector3d& target, std::uint32_t p) {
  const Eigen::Vector3d& c = search.positions[p];
  if (!detail::within_limits(search.limits, s, c)) return false;
  const std::uint32_t tile = search.tiles.tile_of[p];
  std::uint8_t& hidden = scratch.tile_hidden[tile];
  if (!hidden)
    hidden = detail::hidden_from_box(s, target, scratch.target_offsets.data(),
                                     search.tiles.tiles[tile], search.walls)
                 ? 1
                 : 2;
  if (hidden == 1) return false;
  // Through an opening (not visible by the rule) or into a wall (not visible either,
  // known without a ray query: most samples outside the room).
  if (detail::at_walls(search.walls, c, search.position_offsets.data() + p * search.walls.size(),
                       target, scratch.target_offsets.data(),
                       true) != detail::AtWalls::nothing_known)
    return false;
  ++scratch.queries;
  return search.truth.segment_free(c, target);
}

// True if some position sees `s`. `last` is the position that saw the previous sample
// (kNoPosition if none): it is tried first, as samples come face by face, and is updated.
bool seen_from_any(const VisibilitySearch& search, SearchScratch& scratch, const SurfaceSample& s,
                   std::uint32_t& last) {
  const Eigen::Vector3d target = detail::segment_target(s);
  detail::wall_offsets(search.walls, target, scratch.target_offsets.data());
  if (detail::hidden_from_box(s, target, scratch.target_offsets.data(), search.tiles.whole,
                              search.walls))
    return false;
  std::fill(scratch.tile_hidden.begin(), scratch.tile_hidden.end(), 0);
  const int room = search.rooms.of_sample(s);
  scratch.by_room += room >= 0;
  const std::vector<std::uint32_t>& order = search.orders.of(s.position, room);
  // `last` may stand in another room: tried only if it is of this order's positions.
  const int last_room = last != kNoPosition ? search.rooms.of_position(search.positions[last]) : -1;
  const bool last_admitted =
      last != kNoPosition && (room < 0 || last_room < 0 || last_room == room);
  if (last_admitted && seen_from(search, scratch, s, target, last)) return true;
  for (std::uint32_t p : order) {
    if (p == last || !seen_from(search, scratch, s, target, p)) continue;
    last = p;
    return true;
  }
  return false;
}

// One flag per sample: seen from some position. Each sample is tested on its own (early
// exit at the first position that sees it) and the chunks are fixed, so the flags and
// `queries` do not depend on the number of threads.
std::vector<std::uint8_t> seen_flags(const VisibilitySearch& search,
                                     const std::vector<SurfaceSample>& samples, unsigned threads,
                                     std::uint64_t& queries, std::uint64_t& by_room) {
  const std::size_t n = samples.size();
  constexpr std::size_t kChunk = 2048;
  std::vector<std::uint8_t> seen(n, 0);
  std::atomic<std::size_t> next{0};
  std::atomic<std::uint64_t> total_queries{0}, total_by_room{0};
  auto work = [&](bool) {
    SearchScratch scratch(search);
    for (std::size_t begin = next.fetch_add(kChunk); begin < n; begin = next.fetch_add(kChunk)) {
      std::uint32_t last = kNoPosition;
      const std::size_t end = std::min(n, begin + kChunk);
      for (std::size_t i = begin; i < end; ++i)
        seen[i] = seen_from_any(search, scratch, samples[i], last);
    }
    total_queries += scratch.queries;
    total_by_room += scratch.by_room;
  };
  detail::run_on_threads(std::min<unsigned>(detail::thread_count(threads),
                                            static_cast<unsigned>((n + kChunk - 1) / kChunk)),
                         work);
  queries = total_queries;
  by_room = total_by_room;
  return seen;
}

void fill_points(const std::vector<SurfaceSample>& samples, CoverageReference& ref) {
  ref.points.clear();
  ref.points.reserve(ref.visible.size());
  for (std::uint32_t i : ref.visible) ref.points.push_back(samples[i].position);
}

// coverage_grid_positions on the floor plan `plan` of the scene.
std::vector<Eigen::Vector3d> grid_positions(const GroundTruth& truth, const FloorPlan& plan,
                                            double grid_spacing) {
  if (!(grid_spacing > 0))
    throw std::invalid_argument("coverage reference: grid spacing must be > 0");
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

// The reference of `samples` (key and seconds not set).
CoverageReference compute(const GroundTruth& truth, const std::vector<SurfaceSample>& samples,
                          double grid_spacing, double sample_spacing, unsigned threads) {
  CoverageReference ref;
  ref.grid_spacing = grid_spacing;
  ref.sample_spacing = sample_spacing;
  ref.sample_count = samples.size();
  const FloorPlan plan = truth.floor_plan(detail::kCoveragePlanCell);
  ref.positions = grid_positions(truth, plan, grid_spacing);
  if (samples.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("coverage reference: too many surface samples");
  if (samples.empty() || ref.positions.empty()) return ref;

  const VisibilitySearch search(truth, plan, samples, ref.positions, grid_spacing);
  const std::vector<std::uint8_t> seen =
      seen_flags(search, samples, threads, ref.segment_queries, ref.samples_by_room);
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (seen[i]) ref.visible.push_back(static_cast<std::uint32_t>(i));
  fill_points(samples, ref);
  return ref;
}

void check_sample_spacing(double sample_spacing) {
  if (!(sample_spacing > 0))
    throw std::invalid_argument("coverage reference: sample spacing must be > 0");
}

}  // namespace

std::vector<Eigen::Vector3d> coverage_grid_positions(const GroundTruth& truth,
                                                     double grid_spacing) {
  return grid_positions(truth, truth.floor_plan(detail::kCoveragePlanCell), grid_spacing);
}

double coverage_sample_spacing(const GroundTruth& truth, double finest, std::size_t max_samples) {
  check_sample_spacing(finest);
  // The surface's area from a coarse sampling (a sample per coarse² of surface).
  const double coarse = std::max(finest, 0.1);
  std::size_t coarse_samples = 0;
  for_each_surface_sample(truth.scene(), coarse, [&](const SurfaceSample&) { ++coarse_samples; });
  const double area = static_cast<double>(coarse_samples) * coarse * coarse;
  if (area / (finest * finest) <= static_cast<double>(max_samples)) return finest;
  return std::ceil(std::sqrt(area / static_cast<double>(std::max<std::size_t>(max_samples, 1))) *
                   1000.0) /
         1000.0;
}

CoverageReference compute_coverage_reference(const GroundTruth& truth, double grid_spacing,
                                             double finest_spacing, unsigned threads) {
  const auto t0 = Clock::now();
  const double sample_spacing = coverage_sample_spacing(truth, finest_spacing);
  const std::vector<SurfaceSample> samples = truth.surface_samples(sample_spacing);
  CoverageReference ref = compute(truth, samples, grid_spacing, sample_spacing, threads);
  ref.key = detail::reference_key(truth, detail::digest_of_samples(samples), grid_spacing,
                                  sample_spacing);
  ref.seconds = seconds_since(t0);
  return ref;
}

CoverageReference load_or_compute_coverage_reference(const GroundTruth& truth,
                                                     const std::string& cache_dir,
                                                     double grid_spacing, double finest_spacing,
                                                     unsigned threads) {
  const auto t0 = Clock::now();
  const double sample_spacing = coverage_sample_spacing(truth, finest_spacing);
  // The samples are streamed for the key and, from the cache, for the points: held only
  // when the reference is computed (a large scene's run to hundreds of MB).
  const detail::SamplesDigest digest = detail::digest_of_samples(truth, sample_spacing);
  const std::string key = detail::reference_key(truth, digest, grid_spacing, sample_spacing);
  auto compute_here = [&] {
    CoverageReference r = compute(truth, truth.surface_samples(sample_spacing), grid_spacing,
                                  sample_spacing, threads);
    r.key = key;
    return r;
  };
  CoverageReference ref;
  if (cache_dir.empty()) {
    ref = compute_here();
  } else {
    const std::filesystem::path file = detail::cache_file_path(cache_dir, key);
    if (detail::read_cached_reference(file, key, grid_spacing, sample_spacing, digest.count(),
                                      ref)) {
      ref.key = key;
      ref.from_cache = true;
      ref.cache_file = file.string();
    } else {
      ref = compute_here();
      if (detail::write_cached_reference(file, ref)) ref.cache_file = file.string();
    }
  }
  ref.seconds = seconds_since(t0);
  return ref;
}

}  // namespace semioctree::sim
