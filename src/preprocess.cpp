#include "semioctree/preprocess.h"

#include <pcl/common/centroid.h>
#include <pcl/common/transforms.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <vector>

#include "cell_lanes.h"
#include "parallel_for.h"
#include "plane_segmentation.h"
#include "random_subset.h"
#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree {

namespace {

bool finite(const pcl::PointXYZ& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

// floor(t) for a finite t within ±2^62 (the cells of finite floats): std::floor is a call
// into libm on the baseline x86-64 this builds for, once per axis of every point a
// decimation or a count reads.
std::int64_t floor_to_int(double t) {
  const auto i = std::int64_t(t);  // towards zero
  return i - std::int64_t(double(i) > t);
}

// Along one axis, the index of the world-aligned cell of side 1 / inv holding coordinate v
// (finite): every cell of decimation, counting and the RANSAC's spread is made of these.
std::int64_t cell_index(float v, double inv) {
  return floor_to_int(double(v) * inv);
}

// The world-aligned cell of side 1 / inv holding q (finite), packed (decimate, count_cells and
// the RANSAC's spread share it, so that a count is the count of what decimate keeps).
std::uint64_t cell_key(const pcl::PointXYZ& q, double inv) {
  auto part = [inv](float v) { return std::uint64_t(cell_index(v, inv)); };
  return pack_cell_parts(part(q.x), part(q.y), part(q.z));
}

struct HorizontalPlane {
  Eigen::Vector3d normal;   // oriented to +z
  double d = 0;             // normal·p + d = 0
  std::size_t inliers = 0;  // on the full cloud (estimated from a random subset)
  // Its band of heights holds at least twice as many points as either band of the same
  // width next to it: a horizontal surface, not a band of wall (docs/data-flow.md).
  bool stands_out = false;
  double height_at(const Eigen::Vector2d& xy) const {
    return -(d + normal.x() * xy.x() + normal.y() * xy.y()) / normal.z();
  }
};

// `count` points of `cloud` drawn at random (all of them if it has no more).
Cloud::Ptr random_subset(const Cloud& cloud, std::size_t count) {
  return detail::random_subset(cloud, count, 12345);
}

// The points RANSAC searches the first plane among: one per cube whose side is the
// thickness of a plane's inlier band (2 · ransac_distance), then a random subset of those
// if still too many. A scanner's returns are dense near it and sparse far off, so among
// the returns themselves the walls beside the scanner count many times over and a floor
// beyond its lowest elevation (or its blind zone) hardly at all: a plane tilted through
// those near walls out-counted the floor, and the floor alone levelled a ceiling-less
// scan 10° askew. One point per cube makes a plane's inlier count its area within the
// band, whatever the scan's density (docs/data-flow.md).
Cloud::Ptr area_uniform_subset(const Cloud& input, const PreprocessParams& p) {
  Cloud spread;
  const double inv = 1.0 / (2.0 * p.ransac_distance);
  PackedKeyMap<std::uint8_t> cubes(std::min<std::size_t>(input.size(), 4 * p.ransac_sample));
  for (const auto& q : input) {
    if (!finite(q)) continue;
    if (cubes.insert(cell_key(q, inv))) spread.push_back(q);
  }
  return random_subset(spread, p.ransac_sample);
}

// Where RANSAC searches the first horizontal plane: among the returns (a random subset
// of them), or among points spread evenly over the surfaces (area_uniform_subset).
enum class FirstPlaneAmong { kReturns, kSurfaces };

// Horizontal planes, largest first: the first found by RANSAC (among `among`), the others
// parallel to it. Their sizes (`inliers`, which the choice of the floor compares) are
// counted among the returns either way: a floor seen all round the scanner holds more
// returns than the ground beyond a window, however far that ground stretches.
// `work`: random_subset(input, p.ransac_sample), drawn once for both searches.
std::vector<HorizontalPlane> find_horizontal_planes(const Cloud& input, const Cloud::Ptr& work,
                                                    const PreprocessParams& p,
                                                    FirstPlaneAmong among) {
  const Cloud::Ptr search =
      among == FirstPlaneAmong::kReturns ? work : area_uniform_subset(input, p);
  if (work->empty() || search->empty()) return {};
  const double scale = double(input.size()) / double(work->size());
  detail::PlaneSegmentation seg;  // PCL's, counting lanes at a time; a fixed seed
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(Eigen::Vector3f::UnitZ());
  seg.setEpsAngle(p.max_tilt_deg * M_PI / 180.0);
  seg.setDistanceThreshold(p.ransac_distance);
  seg.setMaxIterations(p.ransac_iterations);

  std::vector<HorizontalPlane> planes;
  auto min_inliers_of = [&](const Cloud& c) {
    return std::max<std::size_t>(std::size_t(p.min_plane_fraction * double(c.size())), 50);
  };
  const std::size_t min_inliers = min_inliers_of(*work);
  pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
  pcl::ModelCoefficients coeffs;
  seg.setInputCloud(search);
  seg.segment(*inliers, coeffs);
  if (inliers->indices.size() < min_inliers_of(*search) || coeffs.values.size() != 4) return planes;
  HorizontalPlane first;
  first.normal = Eigen::Vector3d(coeffs.values[0], coeffs.values[1], coeffs.values[2]);
  first.d = coeffs.values[3];
  const double len = first.normal.norm();
  first.normal /= len;
  first.d /= len;
  if (first.normal.z() < 0) {
    first.normal = -first.normal;
    first.d = -first.d;
  }
  std::size_t first_inliers = inliers->indices.size();
  if (among == FirstPlaneAmong::kSurfaces) {  // counted among the returns
    first_inliers = 0;
    for (const auto& q : *work)
      first_inliers += std::fabs(first.normal.dot(Eigen::Vector3d(q.x, q.y, q.z)) + first.d) <=
                       p.ransac_distance;
  }
  first.inliers = std::size_t(double(first_inliers) * scale);
  planes.push_back(first);

  // The other planes are parallel to the first (floor and ceiling of one room):
  // peaks of the points' heights along its normal, largest first. A second
  // RANSAC over all tilts would instead find planes tilted by ~10° cutting two
  // near walls along dense bands before the floor in a scan taken in a corner
  // (whose floor nearby lies in the blind zone).
  std::vector<double> h(work->size());
  for (std::size_t i = 0; i < work->size(); ++i) {
    const auto& q = (*work)[i];
    h[i] = first.normal.dot(Eigen::Vector3d(q.x, q.y, q.z));
  }
  std::sort(h.begin(), h.end());
  const double w = p.ransac_distance;
  auto within = [&](double c) {  // points within ±w of height c
    return std::size_t(std::upper_bound(h.begin(), h.end(), c + w) -
                       std::lower_bound(h.begin(), h.end(), c - w));
  };
  auto mean_within = [&](double c) {
    const auto lo = std::lower_bound(h.begin(), h.end(), c - w);
    const auto hi = std::upper_bound(h.begin(), h.end(), c + w);
    return lo == hi ? c : std::accumulate(lo, hi, 0.0) / double(hi - lo);
  };
  // The plane at height c holds at least as many points as the background (the walls)
  // within its band: twice as many as either neighbouring band.
  auto stands_out = [&](double c) {
    return within(c) >= 2 * std::max(within(c - 2 * w), within(c + 2 * w));
  };
  planes.front().stands_out = stands_out(-first.d);
  std::vector<double> taken{-first.d};
  while (planes.size() < 8) {
    double best_c = 0;
    std::size_t best_n = 0;
    for (double c = h.front(); c <= h.back(); c += 0.5 * w) {
      bool near_taken = false;
      for (double t : taken) near_taken |= std::fabs(c - t) < p.peak_window;
      if (near_taken) continue;
      const std::size_t n = within(c);
      if (n > best_n) best_n = n, best_c = c;
    }
    if (best_n < min_inliers) break;
    const double c = mean_within(mean_within(best_c));
    taken.push_back(c);
    HorizontalPlane plane = first;
    plane.d = -c;
    plane.inliers = std::size_t(double(within(c)) * scale);
    plane.stands_out = stands_out(c);
    planes.push_back(plane);
  }
  return planes;
}

// Normal of the least-squares plane through the points within `distance` of
// `plane` (oriented to +z).
Eigen::Vector3d refine_normal(const Cloud& cloud, const HorizontalPlane& plane, double distance) {
  // The inliers by index (a floor holds millions of a scan's points: not copied), room
  // made for about as many as RANSAC's sample estimated.
  pcl::Indices near;
  near.reserve(std::min(cloud.size(), plane.inliers + plane.inliers / 8));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const pcl::PointXYZ& q = cloud[i];
    if (std::fabs(plane.normal.dot(Eigen::Vector3d(q.x, q.y, q.z)) + plane.d) <= distance)
      near.push_back(pcl::index_t(i));
  }
  if (near.size() < 10) return plane.normal;
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  Eigen::Vector4f centroid;
  pcl::computeMeanAndCovarianceMatrix(cloud, near, cov, centroid);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> es(cov);
  Eigen::Vector3d n = es.eigenvectors().col(0).cast<double>().normalized();
  return n.z() < 0 ? -n : n;
}

// What fitting a peak near `guess` starts from: the heights near it (within `near`), in
// their order, and their histogram over the search window. Fed a batch of heights at a
// time, so that one pass over a scan's heights serves the floor's and the ceiling's.
struct PeakStart {
  static constexpr std::size_t kBatch = 1024;
  PeakStart(double guess, const PreprocessParams& p)
      : guess(guess),
        lo(guess - p.peak_window),
        near(3 * p.peak_window),
        bin(p.histogram_bin),
        hist(std::size_t(std::max(1, int(std::ceil(2 * p.peak_window / p.histogram_bin)))), 0) {}
  // Room for the heights near the guess among `count` like those of `sample`: a scan's
  // floor and the walls around it give millions, which growing by doubling copies again.
  void reserve_like(const std::vector<float>& sample, std::size_t count) {
    std::size_t n = 0;
    for (const float v : sample) n += is_near(v);
    z.reserve(std::size_t(1.1 * double(n) / double(std::max<std::size_t>(sample.size(), 1)) *
                          double(count)));
  }
  // Adds the heights v[0, n), n <= kBatch, in order.
  void add(const float* v, std::size_t n) {
    float near_v[kBatch];  // those near the guess, gathered without a branch on each
    std::size_t m = 0;
    for (std::size_t j = 0; j < n; ++j) {
      near_v[m] = v[j];
      m += is_near(v[j]);
    }
    z.insert(z.end(), near_v, near_v + m);
    for (std::size_t j = 0; j < m; ++j) {
      const std::int64_t b = floor_to_int((near_v[j] - lo) / bin);
      if (b >= 0 && b < std::int64_t(hist.size())) ++hist[std::size_t(b)];
    }
  }
  bool is_near(float v) const { return std::fabs(double(v) - guess) <= near; }
  double guess, lo, near, bin;
  std::vector<std::size_t> hist;
  std::vector<float> z;
};

// Mean and σ of the z values near the start's guess, re-centred a few times (a Gaussian
// fitted to one peak of the z histogram by its moments). each_height(f) calls f(z) for
// every height, in order (a scan's levelled heights are streamed, not stored).
template <class EachHeight>
HeightPeak fit_peak(const PeakStart& start, const EachHeight& each_height,
                    const PreprocessParams& p) {
  // Histogram mode within the search window first: the peak itself. The heights near the
  // guess: each pass below reads these instead of all of a scan's millions while its
  // window lies within them (always, on a peak), the same values in the same order, so
  // the same sums.
  const std::vector<std::size_t>& hist = start.hist;
  const std::vector<float>& z = start.z;
  const double guess = start.guess, lo = start.lo, near = start.near;
  const auto mode = std::max_element(hist.begin(), hist.end()) - hist.begin();
  HeightPeak peak;
  peak.center = lo + (double(mode) + 0.5) * p.histogram_bin;
  double window = 3 * p.histogram_bin;
  for (int it = 0; it < 8; ++it) {
    double sum = 0, sum2 = 0;
    std::size_t n = 0;
    const bool within_near = std::fabs(peak.center - guess) + window < near - p.histogram_bin;
    auto add = [&](float v) {
      const double dz = v - peak.center;
      if (std::fabs(dz) <= window) {
        sum += dz;
        sum2 += dz * dz;
        ++n;
      }
    };
    if (within_near)
      for (float v : z) add(v);
    else
      each_height(add);
    if (n < 10) break;
    const double mean = sum / double(n);
    const double center_before = peak.center, window_before = window;
    peak.center += mean;
    peak.sigma = std::sqrt(std::max(0.0, sum2 / double(n) - mean * mean));
    // A ±w window truncates the Gaussian; 3σ keeps 99.7 % of it.
    window = std::max(3.0 * peak.sigma, 2 * p.histogram_bin);
    // The same window and a centre that moved less than a thousandth of a bin: the passes
    // after this one would move it by less still (the fit has settled).
    constexpr double kSettled = 1e-3;
    if (window == window_before &&
        std::fabs(peak.center - center_before) < kSettled * p.histogram_bin)
      break;
  }
  peak.sigma = std::max(peak.sigma, p.min_sigma);
  return peak;
}

// The q-quantile of the heights, nudged just above so that its point itself lies below
// it (the map keeps z < height); none for no heights.
std::optional<double> top_of_heights(std::vector<float> z, double q) {
  if (z.empty()) return std::nullopt;
  const auto k = std::size_t(std::clamp(q, 0.0, 1.0) * double(z.size() - 1));
  std::nth_element(z.begin(), z.begin() + std::ptrdiff_t(k), z.end());
  return std::nextafter(double(z[k]), std::numeric_limits<double>::infinity());
}

// Inserts keys into a table a batch at a time, each batch's slots prefetched first: a
// table of hundreds of thousands of cells misses the cache on nearly every insertion, and
// the misses of a batch then overlap. The keys go in in the order given.
class BatchedInsert {
 public:
  explicit BatchedInsert(PackedKeyMap<std::uint8_t>& cells) : cells_(cells) {}
  // Queues `key`; `go_on()` is asked after each key goes in, in order, and returns false
  // to stop (add and flush then return false).
  template <class GoOn>
  bool add(std::uint64_t key, const GoOn& go_on) {
    keys_[n_++] = key;
    return n_ < kBatch || flush(go_on);
  }
  template <class GoOn>
  bool flush(const GoOn& go_on) {
    for (std::size_t j = 0; j < n_; ++j) cells_.prefetch(keys_[j]);
    const std::size_t n = n_;
    n_ = 0;
    for (std::size_t j = 0; j < n; ++j) {
      cells_.insert(keys_[j]);
      if (!go_on()) return false;
    }
    return true;
  }

 private:
  static constexpr std::size_t kBatch = 16;
  PackedKeyMap<std::uint8_t>& cells_;
  std::uint64_t keys_[kBatch];
  std::size_t n_ = 0;
};

// Whether `key` is new to `recent`, which then remembers it: a cell met a moment before is
// in the count's table already.
bool first_met(RecentKeys<std::uint8_t>& recent, std::uint64_t key) {
  if (recent.find(key)) return false;
  recent.remember(key, 0);
  return true;
}

// Fewer points than this a thread are not worth starting one for.
constexpr std::size_t kMinThreadShare = std::size_t(1) << 16;

// The part of a count (of `parts`) a key falls in.
std::size_t part_of(std::uint64_t key, std::uint64_t parts) {
  return std::size_t((key * 0x9E3779B97F4A7C15ull >> 32) % parts);
}

// The bounds of a cloud's finite points.
struct PointBounds {
  float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                 std::numeric_limits<float>::infinity()};
  float hi[3] = {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                 -std::numeric_limits<float>::infinity()};
  void add(const pcl::PointXYZ& q) {
    if (!finite(q)) return;
    const float v[3] = {q.x, q.y, q.z};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  }
  bool empty() const { return !(lo[0] <= hi[0]); }
};

// A set of the cells of spacing 1 / inv within bounds, as bits: blocks of 8 × 8 × 8 cells
// (64 bytes), each allocated when one of its cells is first set, found through an index
// of all the bounds' blocks (4 bytes each). A scan's points lie on surfaces, so the blocks
// they touch are few and full; setting a bit is one look-up in the index and one in a
// block, where a hash table probes megabytes at a hashed place. It holds cell_key's cells
// exactly while the bounds span fewer than 2^21 cells along each axis (where no two of
// cell_key's keys alias).
class CellBits {
 public:
  // A set for the cells of the points within `bounds` (not empty) whose index and blocks
  // may take up to `budget` bytes: valid() is false if the index alone would take more,
  // or the bounds span 2^21 cells or more along an axis.
  CellBits(const PointBounds& bounds, double inv, std::size_t budget) : inv_(inv) {
    double blocks = 1;
    for (int a = 0; a < 3; ++a) {
      lo_[a] = cell_index(bounds.lo[a], inv);
      const std::int64_t cells = cell_index(bounds.hi[a], inv) - lo_[a] + 1;
      if (!(cells > 0 && cells < (std::int64_t(1) << 21))) return;
      if (!(std::abs(lo_[a]) < (std::int64_t(1) << 52))) return;  // (detail::cell_places)
      blocks_[a] = std::uint64_t(cells + 7) / 8;
      blocks *= double(blocks_[a]);
    }
    // (detail::cell_places computes the index's places in 32 bits.)
    if (blocks * sizeof(std::uint32_t) > double(budget) || blocks >= 0x1p32) return;
    // Zeroed pages from the system (calloc): only those the points' blocks reach are
    // touched.
    index_.reset(static_cast<std::uint32_t*>(std::calloc(std::size_t(blocks), 4)));
    if (!index_) throw std::bad_alloc();
    index_size_ = std::size_t(blocks);
    budget_ = budget;
  }
  bool valid() const { return index_size_ > 0; }
  // Adds the cell of q, a finite point within the bounds: buffered, the buffer's cells set
  // when it fills (flush). False once the blocks set outgrow the budget (only a new block
  // may). No branch hangs on whether a cell was set before (a scan's points revisit cells
  // unpredictably): size() counts the bits.
  bool add(const pcl::PointXYZ& q) {
    x_[buffered_] = q.x, y_[buffered_] = q.y, z_[buffered_] = q.z;
    return ++buffered_ < kBatch || flush();
  }
  // Sets the cells of the points buffered; false as add().
  bool flush() {
    const double lo[3] = {double(lo_[0]), double(lo_[1]), double(lo_[2])};
    const std::uint32_t blocks[2] = {std::uint32_t(blocks_[0]), std::uint32_t(blocks_[1])};
    std::uint32_t at[kBatch];
    std::uint8_t word[kBatch], bit[kBatch];
    detail::cell_places(buffered_, x_, y_, z_, inv_, lo, blocks, at, word, bit);
    const std::size_t n = buffered_;
    buffered_ = 0;
    for (std::size_t j = 0; j < n; ++j) {
      std::uint32_t& block = index_[at[j]];
      if (block == 0) {
        bits_.resize(bits_.size() + 8, 0);
        placed_.push_back(at[j]);
        block = std::uint32_t(placed_.size());
        if (!within_budget()) return false;
      }
      bits_[std::size_t(block - 1) * 8 + word[j]] |= std::uint64_t(1) << bit[j];
    }
    return true;
  }
  // The cells set.
  std::size_t size() const {
    std::size_t n = 0;
    for (const std::uint64_t word : bits_) n += std::size_t(__builtin_popcountll(word));
    return n;
  }
  // The cells set in any of `sets` (of the same bounds and spacing): each set's cells that
  // no set before it holds, over the blocks it set.
  static std::size_t union_size(const std::vector<CellBits>& sets) {
    std::size_t n = sets.empty() ? 0 : sets[0].size();
    for (std::size_t s = 1; s < sets.size(); ++s)
      for (std::size_t k = 0; k < sets[s].placed_.size(); ++k)
        for (std::size_t w = 0; w < 8; ++w) {
          std::uint64_t before = 0;
          for (std::size_t t = 0; t < s; ++t)
            if (const std::uint32_t block = sets[t].index_[sets[s].placed_[k]])
              before |= sets[t].bits_[std::size_t(block - 1) * 8 + w];
          n += std::size_t(__builtin_popcountll(sets[s].bits_[k * 8 + w] & ~before));
        }
    return n;
  }

 private:
  struct Free {
    void operator()(std::uint32_t* p) const { std::free(p); }
  };
  double inv_;
  std::int64_t lo_[3] = {0, 0, 0};       // the bounds' first cell
  std::uint64_t blocks_[3] = {0, 0, 0};  // blocks along each axis
  std::size_t budget_ = 0;
  // Per block of the bounds: 0, or 1 + its place among the blocks set.
  std::unique_ptr<std::uint32_t[], Free> index_;
  std::size_t index_size_ = 0;
  std::vector<std::uint64_t> bits_;  // 8 words a block set: word z, bit x + 8·y within it
  std::vector<std::size_t> placed_;  // per block set: its place in the index
  static constexpr std::size_t kBatch = 256;
  float x_[kBatch], y_[kBatch], z_[kBatch];  // points added, their cells not set yet
  std::size_t buffered_ = 0;

  // Whether the blocks set so far keep the set within its budget.
  bool within_budget() const {
    return index_size_ * sizeof(std::uint32_t) + bits_.capacity() * sizeof(std::uint64_t) +
               placed_.capacity() * sizeof(std::size_t) <=
           budget_;
  }
};

// The bytes a count's hash tables take: `tables` of them for up to cap + 1 keys each.
std::size_t table_bytes(std::size_t cap, std::size_t tables) {
  return tables * PackedKeyMap<std::uint8_t>::bytes_for(cap + 1);
}

// count_cells over the points `each_point` streams: each_point(begin, end, f) calls
// f(i, q) for each point q, at position i, of the positions [begin, end) of `size`, in
// order, and stops when f returns false. Contiguous shares of the positions are counted on
// `threads` workers, each into a table of its own, and the keys of their union counted:
// the count is exact whatever the threads.
// `tables`: the tables of an earlier count to fill again (their keys forgotten), or none.
// `bounds`: the points' bounds, if known: where a CellBits set a worker fits in the memory
// the tables would take, the cells are counted in those (the same count), and the tables
// are let go.
template <class EachPoint>
std::size_t count_cells_of(std::size_t size, const EachPoint& each_point, double spacing,
                           std::size_t cap, unsigned threads,
                           std::vector<PackedKeyMap<std::uint8_t>>& tables,
                           const PointBounds* bounds) {
  // One table of at most cap + 1 keys a worker first (their union counted by looking
  // keys up); past that, the parts are as many as keep each table near the cap, from the
  // share of the points read when a table filled (a scan's points sweep its surfaces in
  // order). One worker alone takes two tables, its keys split between them by their hash
  // (the memory two workers take): a count up to twice the cap (a trial spacing much
  // finer than the target's) then takes one pass, not a pass and three parts.
  cap = std::max<std::size_t>(cap, 1);
  const double inv = 1.0 / spacing;
  const std::size_t workers =
      std::max<std::size_t>(1, std::min<std::size_t>(threads, size / kMinThreadShare));
  const std::size_t split = workers == 1 ? 2 : 1;  // tables a worker
  if (bounds && !bounds->empty()) {
    // The tables' memory, a share a worker; or all of it for one set, on one thread, where
    // a share cannot hold the index of the bounds (a scan that sees far through a window):
    // one pass beats the tables' passes by parts.
    const std::size_t budget = table_bytes(cap, workers * split);
    for (int attempt = 0; attempt < (workers > 1 ? 2 : 1); ++attempt) {
      const std::size_t set_count = attempt == 0 ? workers : 1;
      std::vector<CellBits> sets;
      for (std::size_t w = 0; w < set_count; ++w)
        sets.emplace_back(*bounds, inv, budget / set_count);
      if (!sets[0].valid()) continue;
      std::vector<std::uint8_t> fits(set_count, 1);
      detail::parallel_for(set_count, unsigned(set_count), 1, [&](std::size_t w, unsigned) {
        CellBits& set = sets[w];
        each_point(size * w / set_count, size * (w + 1) / set_count,
                   [&](std::size_t, const pcl::PointXYZ& q) {
                     if (!finite(q) || set.add(q)) return true;
                     fits[w] = 0;
                     return false;
                   });
        if (fits[w] && !set.flush()) fits[w] = 0;
      });
      if (std::all_of(fits.begin(), fits.end(), [](std::uint8_t f) { return f != 0; })) {
        tables.clear();
        return CellBits::union_size(sets);
      }
    }
  }
  double estimate = 0;  // cells in all, extrapolated from the tables' fill
  {
    tables.resize(workers * split);
    std::vector<double> share_read(workers, 1.0);  // of the worker's positions, when it stopped
    detail::parallel_for(workers, unsigned(workers), 1, [&](std::size_t w, unsigned) {
      const std::size_t begin = size * w / workers, end = size * (w + 1) / workers;
      PackedKeyMap<std::uint8_t>* own = &tables[w * split];
      std::vector<BatchedInsert> batches;
      for (std::size_t t = 0; t < split; ++t) {
        own[t].forget_keys();
        own[t].reserve(std::min(end - begin, cap + 1));
        batches.emplace_back(own[t]);
      }
      RecentKeys<std::uint8_t> recent;
      auto counted = [&] {
        for (std::size_t t = 0; t < split; ++t)
          if (own[t].size() > cap) return false;
        return true;
      };
      std::size_t last = begin;  // the position of the last point read
      bool more = true;
      each_point(begin, end, [&](std::size_t i, const pcl::PointXYZ& q) {
        last = i;
        if (!finite(q)) return true;
        const std::uint64_t k = cell_key(q, inv);
        return !first_met(recent, k) ||
               (more = batches[split == 1 ? 0 : part_of(k, split)].add(k, counted));
      });
      for (BatchedInsert& batch : batches)
        if (more) more = batch.flush(counted);
      if (!more) share_read[w] = double(last + 1 - begin) / double(end - begin);
    });
    bool over = false;
    for (std::size_t t = 0; t < tables.size(); ++t) {
      over = over || tables[t].size() > cap;
      estimate += double(tables[t].size()) / std::max(share_read[t / split], 1e-9);
    }
    if (!over && split > 1)  // one worker's tables: their keys apart
      return std::accumulate(tables.begin(), tables.end(), std::size_t(0),
                             [](std::size_t n, const auto& t) { return n + t.size(); });
    if (!over) {
      // The workers' union: each table's keys that no table before it holds (looked up,
      // not inserted: no table grows).
      std::size_t n = tables[0].size();
      for (std::size_t w = 1; w < workers; ++w)
        tables[w].for_each_key([&](std::uint64_t k) {
          bool before = false;
          for (std::size_t v = 0; v < w && !before; ++v) before = tables[v].find(k) != nullptr;
          n += !before;
          return true;
        });
      return n;
    }
  }
  const std::uint64_t parts =
      std::max<std::uint64_t>(2, std::uint64_t(std::ceil(1.25 * estimate / double(cap))));
  std::vector<std::size_t> counts(parts);
  auto go_on = [] { return true; };
  tables.resize(workers);  // one a worker, each part after the other
  detail::parallel_for(parts, unsigned(workers), 1, [&](std::size_t part, unsigned worker) {
    PackedKeyMap<std::uint8_t>& cells = tables[worker];
    cells.forget_keys();
    cells.reserve(cap);
    BatchedInsert batch(cells);
    RecentKeys<std::uint8_t> recent;
    each_point(0, size, [&](std::size_t, const pcl::PointXYZ& q) {
      if (!finite(q)) return true;
      const std::uint64_t k = cell_key(q, inv);
      return part_of(k, parts) != part || !first_met(recent, k) || batch.add(k, go_on);
    });
    batch.flush(go_on);
    counts[part] = cells.size();
  });
  return std::accumulate(counts.begin(), counts.end(), std::size_t(0));
}

// The points of `cloud` at positions [begin, end), in order, for count_cells_of.
auto points_of(const Cloud& cloud) {
  return [&cloud](std::size_t begin, std::size_t end, auto&& f) {
    for (std::size_t i = begin; i < end; ++i)
      if (!f(i, cloud[i])) return;
  };
}

}  // namespace

std::size_t count_cells(const Cloud& cloud, double spacing, std::size_t cap, unsigned threads) {
  std::vector<PackedKeyMap<std::uint8_t>> tables;
  PointBounds bounds;
  for (const pcl::PointXYZ& q : cloud) bounds.add(q);
  return count_cells_of(cloud.size(), points_of(cloud), spacing, cap, detail::thread_count(threads),
                        tables, &bounds);
}

CellThinning::CellThinning(double spacing) : inv_(1.0 / spacing), kept_(new Cloud) {
  if (!(spacing > 0)) throw std::invalid_argument("CellThinning: the spacing must be > 0");
  kept_->is_dense = true;
}

float CellThinning::centre_offset2(const pcl::PointXYZ& p) const {
  auto d = [&](float v) {
    const double t = double(v) * inv_;
    return t - double(floor_to_int(t)) - 0.5;
  };
  return float(d(p.x) * d(p.x) + d(p.y) * d(p.y) + d(p.z) * d(p.z));
}

void CellThinning::add(const pcl::PointXYZ& q) {
  if (!finite(q)) return;
  Pending& p = pending_;
  p.points[p.size] = q;
  p.x[p.size] = q.x, p.y[p.size] = q.y, p.z[p.size] = q.z;
  if (++p.size == kBatch) place_pending();
}

void CellThinning::cells_of(std::size_t n, const float* x, const float* y, const float* z,
                            std::uint64_t* keys, float* offsets2) const {
  std::uint8_t wide[kBatch];
  detail::cell_keys(n, x, y, z, inv_, keys, offsets2, wide);
  for (std::size_t j = 0; j < n; ++j)
    if (wide[j]) {
      const pcl::PointXYZ q(x[j], y[j], z[j]);
      keys[j] = cell_key(q, inv_);
      offsets2[j] = centre_offset2(q);
    }
}

void CellThinning::place_pending() {
  Pending& p = pending_;
  std::uint64_t keys[kBatch];
  float offsets2[kBatch];
  cells_of(p.size, p.x, p.y, p.z, keys, offsets2);
  for (std::size_t j = 0; j < p.size; ++j) place(p.points[j], keys[j], offsets2[j]);
  p.size = 0;
}

void CellThinning::place(const pcl::PointXYZ& q, std::uint64_t key, float o2) {
  // Per cell, the index of its point in kept_ and that point's squared distance from the
  // cell's centre (in cells); a point nearer the centre replaces it (PCL's UniformSampling
  // keeps the same points, at three times the time: docs/data-flow.md, "Decimation").
  // A cell's index never changes once given, so recent_ may answer for slot_.
  Cloud& kept = *kept_;
  std::uint32_t index;
  if (const std::uint32_t* known = recent_.find(key)) {
    index = *known;
  } else {
    const auto [slot, added] = slot_.try_emplace(key, std::uint32_t(kept.size()));
    index = *slot;
    recent_.remember(key, index);
    if (added) {
      kept.push_back(q);
      offset2_.push_back(o2);
      return;
    }
  }
  if (o2 < offset2_[index]) {
    kept[index] = q;
    offset2_[index] = o2;
  }
}

void CellThinning::reserve(std::size_t cells) {
  slot_.reserve(cells);
  kept_->reserve(cells);
  offset2_.reserve(cells);
}

const Cloud& CellThinning::cloud() {
  place_pending();
  return *kept_;
}

void CellThinning::add(const Cloud& points) {
  for (const pcl::PointXYZ& q : points) add(q);
}

Cloud::Ptr CellThinning::release() {
  place_pending();
  Cloud::Ptr out = std::move(kept_);
  out->points.shrink_to_fit();  // grown by doubling: up to twice what it holds
  empty();
  return out;
}

void CellThinning::empty() {
  kept_.reset(new Cloud);
  kept_->is_dense = true;
  slot_.clear();
  recent_.forget_all();
  offset2_ = {};
  pending_.size = 0;
}

void CellThinning::release_after(Cloud& earlier) {
  // Each of earlier's points is the first of its cell in the union's order, so it stays
  // unless this thinning's point of that cell is strictly nearer the centre (add keeps the
  // earlier on ties); the cells earlier holds are taken off what follows it.
  place_pending();
  Cloud& kept = *kept_;
  std::vector<std::uint8_t> taken(kept.size(), 0);
  // A batch of earlier's points at a time, their cells worked out as add's (the pending
  // points' arrays, empty now, hold their coordinates).
  Pending& b = pending_;
  std::uint64_t keys[kBatch];
  float offsets2[kBatch];
  for (std::size_t begin = 0; begin < earlier.size(); begin += kBatch) {
    const std::size_t n = std::min(kBatch, earlier.size() - begin);
    for (std::size_t j = 0; j < n; ++j) {
      const pcl::PointXYZ& p = earlier[begin + j];
      const bool f = finite(p);  // (a non-finite point is skipped below)
      b.x[j] = f ? p.x : 0.0f, b.y[j] = f ? p.y : 0.0f, b.z[j] = f ? p.z : 0.0f;
    }
    cells_of(n, b.x, b.y, b.z, keys, offsets2);
    for (std::size_t j = 0; j < n; ++j) {
      pcl::PointXYZ& p = earlier[begin + j];
      if (!finite(p)) continue;
      const std::uint32_t* slot = slot_.find(keys[j]);
      if (!slot) continue;
      taken[*slot] = 1;
      if (offset2_[*slot] < offsets2[j]) p = kept[*slot];
    }
  }
  earlier.reserve(earlier.size() + std::size_t(std::count(taken.begin(), taken.end(), 0)));
  for (std::size_t i = 0; i < kept.size(); ++i)
    if (!taken[i]) earlier.push_back(kept[i]);
  empty();
}

Cloud::Ptr decimate(const Cloud& cloud, double spacing) {
  if (!(spacing > 0)) return Cloud::Ptr(new Cloud(cloud));
  CellThinning thinning(spacing);
  thinning.add(cloud);
  return thinning.release();
}

namespace {

// A set of positions below 2^32, as runs of consecutive ones, added in increasing order.
class PositionRuns {
 public:
  void add(std::size_t i) {
    if (ends_.empty() || ends_.back() != i) {
      starts_.push_back(std::uint32_t(i));
      ends_.push_back(std::uint32_t(i + 1));
    } else {
      ++ends_.back();
    }
  }
  // f(i) for the positions held within [begin, end), in order, until f returns false.
  template <class F>
  void for_each_in(std::size_t begin, std::size_t end, const F& f) const {
    // The first run ending after begin.
    auto run = std::size_t(std::upper_bound(ends_.begin(), ends_.end(), begin) - ends_.begin());
    for (; run < starts_.size() && starts_[run] < end; ++run)
      for (std::size_t i = std::max<std::size_t>(begin, starts_[run]),
                       stop = std::min<std::size_t>(end, ends_[run]);
           i < stop; ++i)
        if (!f(i)) return;
  }

 private:
  std::vector<std::uint32_t> starts_, ends_;  // run k holds [starts_[k], ends_[k])
};

// The floor and the ceiling among the planes (indices into them).
struct FloorAndCeiling {
  std::size_t floor = 0;
  std::optional<std::size_t> ceiling;  // none: no ceiling found
};

FloorAndCeiling choose_floor_and_ceiling(const std::vector<HorizontalPlane>& planes,
                                         const Eigen::Vector4f& centroid,
                                         const PreprocessParams& p) {
  // Floor: the lowest horizontal plane below the cloud's centroid that holds
  // at least a third as many points as the largest one there. Not simply the
  // lowest: a scanner near a window also sees the ground outside, lower than
  // the floor but a small plane (the floor lies all around the scanner).
  // Not simply the largest: a big table can out-count a cluttered floor.
  // Heights compared at the centroid.
  const Eigen::Vector2d c(centroid.x(), centroid.y());
  auto by_height = [&](const auto& a, const auto& b) { return a.height_at(c) < b.height_at(c); };
  auto lowest = std::min_element(planes.begin(), planes.end(), by_height);
  std::size_t largest_below = 0;
  for (const auto& pl : planes)
    if (pl.height_at(c) < centroid.z()) largest_below = std::max(largest_below, pl.inliers);
  for (auto it = planes.begin(); it != planes.end(); ++it) {
    const bool big = 3 * it->inliers >= largest_below;
    const bool lowest_big = 3 * lowest->inliers >= largest_below;
    if (it->height_at(c) < centroid.z() && big && (!lowest_big || by_height(*it, *lowest)))
      lowest = it;
  }
  // Ceiling: the highest plane, if it is a horizontal surface (not a band of
  // wall) at least min_room_height above the floor. Without one (an open
  // ceiling, one beyond the scanner's range or elevation) the floor alone
  // levels the cloud.
  auto highest = planes.end();
  for (auto it = planes.begin(); it != planes.end(); ++it)
    if (it->stands_out && (highest == planes.end() || by_height(*highest, *it))) highest = it;
  FloorAndCeiling fc;
  fc.floor = std::size_t(lowest - planes.begin());
  if (highest != planes.end() && highest->height_at(c) - lowest->height_at(c) >= p.min_room_height)
    fc.ceiling = std::size_t(highest - planes.begin());
  return fc;
}

}  // namespace

PreprocessResult preprocess(const Cloud& input, const PreprocessParams& p) {
  const unsigned threads = detail::thread_count(p.threads);
  PreprocessResult r;
  r.input_points = input.size();
  if (input.size() > std::numeric_limits<std::uint32_t>::max()) {
    std::ostringstream m;
    m << "too many points to preprocess at once: " << input.size() << " (at most "
      << std::numeric_limits<std::uint32_t>::max() << "; split the scan)";
    throw PreprocessError(m.str());
  }
  if (input.size() < p.min_points) {
    std::ostringstream m;
    m << "too few points to preprocess: " << input.size() << " (need at least " << p.min_points
      << ")";
    throw PreprocessError(m.str());
  }
  // The first plane is searched among the returns. A ceiling found parallel to it, a
  // room height above the floor, confirms its tilt. Without one the floor alone must
  // level the cloud, and a floor seen beyond the scanner's lowest elevation is sparse
  // among returns that crowd on the walls beside it: the first plane is then searched
  // again among points spread evenly over the surfaces (area_uniform_subset), and that
  // search decides (docs/data-flow.md).
  const Cloud::Ptr work = random_subset(input, p.ransac_sample);
  std::vector<HorizontalPlane> planes =
      find_horizontal_planes(input, work, p, FirstPlaneAmong::kReturns);
  if (planes.empty())
    throw PreprocessError("no horizontal plane found (no floor and no ceiling in the cloud?)");
  Eigen::Vector4f centroid;
  pcl::compute3DCentroid(input, centroid);
  const Eigen::Vector2d c(centroid.x(), centroid.y());
  FloorAndCeiling fc = choose_floor_and_ceiling(planes, centroid, p);
  if (!fc.ceiling) {
    std::vector<HorizontalPlane> spread =
        find_horizontal_planes(input, work, p, FirstPlaneAmong::kSurfaces);
    if (!spread.empty()) {
      planes = std::move(spread);
      fc = choose_floor_and_ceiling(planes, centroid, p);
    }
  }
  const HorizontalPlane* lowest = &planes[fc.floor];
  const HorizontalPlane* highest = fc.ceiling ? &planes[*fc.ceiling] : nullptr;
  r.ceiling_found = highest != nullptr;
  // Level by the floor: its normal refined by a least-squares fit to all its
  // inliers in the full cloud (RANSAC saw a subset only).
  const Eigen::Vector3d n = refine_normal(input, *lowest, p.ransac_distance);
  r.normal_input = n;
  r.alpha_deg = std::atan(n.x() / n.z()) * 180.0 / M_PI;  // Eq 1
  r.beta_deg = std::atan(n.y() / n.z()) * 180.0 / M_PI;
  const Eigen::Quaterniond level = Eigen::Quaterniond::FromTwoVectors(n, Eigen::Vector3d::UnitZ());

  // Rotate, then find the peaks of the z histogram near the planes' heights.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = level.toRotationMatrix();
  // The levelled heights are streamed, each point levelled again as it is read, and only
  // the points kept are levelled into the cut cloud: a scan runs to millions of points,
  // and neither its heights nor its levelled copy are stored (docs/data-flow.md, "Memory").
  const Eigen::Affine3f rotate(T.matrix().cast<float>());
  auto levelled = [&](std::size_t i) { return pcl::transformPoint(input[i], rotate); };
  auto each_height = [&](auto&& f) {
    for (std::size_t i = 0; i < input.size(); ++i) f(levelled(i).z);
  };
  {
    // Both peaks' starts from one pass over the heights.
    const Eigen::Vector3d on_floor = T * Eigen::Vector3d(c.x(), c.y(), lowest->height_at(c));
    std::vector<PeakStart> starts{PeakStart(on_floor.z(), p)};
    if (r.ceiling_found)
      starts.emplace_back((T * Eigen::Vector3d(c.x(), c.y(), highest->height_at(c))).z(), p);
    std::vector<float> sample_heights;
    sample_heights.reserve(work->size());
    for (const pcl::PointXYZ& q : *work) sample_heights.push_back(pcl::transformPoint(q, rotate).z);
    for (PeakStart& start : starts) start.reserve_like(sample_heights, input.size());
    float heights[PeakStart::kBatch];
    for (std::size_t begin = 0; begin < input.size(); begin += PeakStart::kBatch) {
      const std::size_t n = std::min(PeakStart::kBatch, input.size() - begin);
      for (std::size_t j = 0; j < n; ++j) heights[j] = levelled(begin + j).z;
      for (PeakStart& start : starts) start.add(heights, n);
    }
    r.floor = fit_peak(starts[0], each_height, p);
    r.floor.plane_inliers = lowest->inliers;
    if (r.ceiling_found) {
      r.ceiling = fit_peak(starts[1], each_height, p);
      r.ceiling.plane_inliers = highest->inliers;
    }
  }

  // Floor to z = 0.
  T.pretranslate(Eigen::Vector3d(0, 0, -r.floor.center));
  r.transform = T;
  if (r.ceiling_found) r.ceiling.center -= r.floor.center;
  r.floor.center = 0;

  const double zf = p.sigma_factor * r.floor.sigma, zc = p.sigma_factor * r.ceiling.sigma;
  const double dz = T.translation().z();
  // The points off the floor's and the ceiling's bands, as runs of consecutive positions:
  // a scan's sweeps cross each band in one stretch, so a lab scan of 5.4 M points makes
  // about 50 000 runs, and the passes below skip a band a run at a time.
  PositionRuns kept_runs;
  PointBounds cut_bounds;  // of the points kept, levelled
  for (std::size_t i = 0; i < input.size(); ++i) {
    pcl::PointXYZ q = levelled(i);
    q.z = float(double(q.z) + dz);
    if (std::fabs(q.z - r.floor.center) <= zf) {
      ++r.floor.removed;
    } else if (r.ceiling_found && std::fabs(q.z - r.ceiling.center) <= zc) {
      ++r.ceiling.removed;
    } else {
      kept_runs.add(i);
      cut_bounds.add(q);
    }
  }
  // The cut cloud (the points kept, levelled) is streamed, not stored: decimation reads it
  // a few times, levelling each point again, and keeps only what it decimates to (a scan
  // of 5.4 M points would hold another 4.5 M beside it: docs/data-flow.md, "Memory").
  const std::size_t after_cut = input.size() - r.floor.removed - r.ceiling.removed;
  // each_cut_in(begin, end, f): f(i, v) for the cut cloud's points among the input's
  // [begin, end), in order, until f returns false; each_cut(f): f(v) for all of them.
  auto each_cut_in = [&](std::size_t begin, std::size_t end, auto&& f) {
    kept_runs.for_each_in(begin, end, [&](std::size_t i) {
      pcl::PointXYZ v = levelled(i);
      v.z = float(double(v.z) + dz);
      return f(i, v);
    });
  };
  auto each_cut = [&](auto&& f) {
    each_cut_in(0, input.size(), [&](std::size_t, const pcl::PointXYZ& v) { return f(v); });
  };
  // The room's height: given, the ceiling's, or the top of the points left.
  if (p.ceiling_height > 0) {
    r.ceiling_height = p.ceiling_height;
    r.height_from = RoomHeightFrom::kGiven;
  } else if (r.ceiling_found) {
    r.ceiling_height = r.ceiling.center;
    r.height_from = RoomHeightFrom::kCeiling;
  } else {
    std::vector<float> heights;
    heights.reserve(after_cut);
    each_cut([&](const pcl::PointXYZ& v) {
      heights.push_back(v.z);
      return true;
    });
    const std::optional<double> top = top_of_heights(std::move(heights), p.top_quantile);
    if (!top || !(*top > 0)) {
      std::ostringstream m;
      m << "found a floor but no ceiling (no horizontal surface at least " << p.min_room_height
        << " m above it) and no point above the floor to take the room's height from; give "
           "the ceiling height";
      throw PreprocessError(m.str());
    }
    r.ceiling_height = *top;
    r.height_from = RoomHeightFrom::kPoints;
  }
  r.after_cut = after_cut;

  // Decimation: a fixed spacing, or the spacing that gives about the target count.
  double spacing = p.min_spacing;
  if (p.target_points > 0 && after_cut > p.target_points) {
    // The spacing that leaves about the target: count the cells of a trial spacing (the
    // partition decimate keeps one point of) with a fast hash set, and update the spacing
    // by the secant of log(count) over log(spacing) (≈ −2 for surfaces). Aim 1 % under
    // the target; accept 3 % under to exactly at it, after at most kMaxCounts counts or
    // once the counts contradict each other (docs/data-flow.md, "Decimation").
    constexpr int kMaxCounts = 13;
    const double goal = 0.99 * double(p.target_points);
    const double target = double(p.target_points);
    // A table of at most twice the target at once (count_cells): as many keys as fill a
    // power of two of slots (one key more would double the table).
    using CellTable = PackedKeyMap<std::uint8_t>;
    std::size_t slots = 64;
    while (CellTable::keys_held_in(2 * slots) <= 2 * p.target_points) slots *= 2;
    const std::size_t cap = CellTable::keys_held_in(slots) - 1;
    std::vector<CellTable> tables;  // the counts' tables, filled again by each count
    auto count_cut = [&](double s) {
      const std::size_t n =
          count_cells_of(input.size(), each_cut_in, s, cap, threads, tables, &cut_bounds);
      r.spacing_counts.emplace_back(s, n);
      return double(n);
    };
    double s0 = std::max(spacing, 0.01), c0 = count_cut(s0);
    double s1 = std::max(spacing, s0 * std::sqrt(c0 / goal));
    // The finest spacing tried that keeps at most the target: on regular
    // (synthetic) grids the count jumps with the cells' phase and the secant
    // may not settle, so the result is always a spacing that was counted.
    double best = c0 <= target ? s0 : 0, best_count = c0 <= target ? c0 : 0;
    // The coarsest spacing counted over the target and the finest counted within it. A
    // finer spacing within it than one over it is a count no longer monotone in the
    // spacing: the cells' phase, not the spacing, decides it there, and further counts
    // only sample that noise, so the best so far is taken.
    double coarsest_over = c0 > target ? s0 : 0;
    double finest_within = c0 <= target ? s0 : std::numeric_limits<double>::infinity();
    for (int counts = 1; counts < kMaxCounts; ++counts) {
      const double c1 = count_cut(s1);
      if (c1 <= target && c1 > best_count) best = s1, best_count = c1;
      if (c1 <= target && c1 >= 0.97 * target) break;
      if (c1 > target)
        coarsest_over = std::max(coarsest_over, s1);
      else
        finest_within = std::min(finest_within, s1);
      if (best > 0 && finest_within < coarsest_over) break;
      double slope = (std::log(c1) - std::log(c0)) / (std::log(s1) - std::log(s0));
      if (!std::isfinite(slope) || slope > -0.5) slope = -2.0;  // flat or noisy: surfaces
      s0 = s1;
      c0 = c1;
      s1 = std::max(spacing, std::exp(std::log(s1) + (std::log(goal) - std::log(c1)) / slope));
      if (c1 > target && s1 <= s0) s1 = s0 * 1.01;  // must get coarser
    }
    for (double s = std::max(s1, s0); best == 0; s *= 1.05)  // none small enough yet
      if (count_cut(s) <= target) best = s;
    spacing = best;
  }
  if (spacing > 0) {
    // Contiguous shares of the input thinned apart, then in order into the first:
    // CellThinning keeps what decimating their union keeps, whatever the threads.
    const std::size_t shares =
        std::max<std::size_t>(1, std::min<std::size_t>(threads, input.size() / kMinThreadShare));
    // The cells the search counted at this spacing (if it did): each share's table sized
    // for its part of them at once, not grown by doubling; the first's for all of them, as
    // the later shares' points are added to it.
    std::size_t cells = 0;
    for (const auto& [s, n] : r.spacing_counts)
      if (s == spacing) cells = n;
    std::vector<CellThinning> thinned;
    for (std::size_t k = 0; k < shares; ++k) {
      thinned.emplace_back(spacing);
      thinned.back().reserve(k == 0 ? cells : cells / shares);
    }
    detail::parallel_for(shares, unsigned(shares), 1, [&](std::size_t k, unsigned) {
      each_cut_in(input.size() * k / shares, input.size() * (k + 1) / shares,
                  [&](std::size_t, const pcl::PointXYZ& v) {
                    thinned[k].add(v);
                    return true;
                  });
    });
    for (std::size_t k = 1; k < shares; ++k) thinned[0].add(*thinned[k].release());
    r.cloud = thinned[0].release();
  } else {
    Cloud::Ptr cut(new Cloud);
    cut->reserve(after_cut);
    each_cut([&](const pcl::PointXYZ& v) {
      cut->push_back(v);
      return true;
    });
    cut->is_dense = true;
    r.cloud = cut;
  }
  r.decimation_spacing = spacing;
  r.output_points = r.cloud->size();
  return r;
}

const char* to_string(RoomHeightFrom from) {
  switch (from) {
    case RoomHeightFrom::kCeiling:
      return "ceiling";
    case RoomHeightFrom::kPoints:
      return "points";
    case RoomHeightFrom::kGiven:
      return "given";
  }
  return "?";
}

std::string describe_room_height(bool ceiling_found, RoomHeightFrom from, double height) {
  char h[32];
  std::snprintf(h, sizeof h, "%.2f m", height);
  switch (from) {
    case RoomHeightFrom::kCeiling:
      return std::string("ceiling ") + h;
    case RoomHeightFrom::kPoints:
      return std::string("no ceiling found, height ") + h + " from the points";
    case RoomHeightFrom::kGiven:
      return std::string(ceiling_found ? "ceiling found and cut" : "no ceiling found") +
             ", height " + h + " given";
  }
  return h;
}

}  // namespace semioctree
