// Survey coverage: the reference samples with a measured point nearby.
#include "semioctree/sim/coverage/measure.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "coverage/spatial_hash.h"
#include "parallel.h"

namespace semioctree::sim {

namespace {

// Flags the samples within the tolerance of points given one after another. A scan's
// points come in sweep order, so many in a row share the block of cells a point's ball
// can meet: the block's samples not flagged yet are gathered once, and a sample, once
// flagged, is not tested again. The flags set are those of a test of every sample of the
// block for every point, whatever the order.
template <class Flags>
class SampleFlagger {
 public:
  SampleFlagger(const detail::PointHash& samples, double tolerance, Flags& flags)
      : samples_(samples), r2_(tolerance * tolerance), flags_(flags) {}

  void add(const Eigen::Vector3d& p) {
    const detail::PointHash::Block b = samples_.block_of(p);
    if (!have_block_ || !(b == block_)) {
      block_ = b;
      have_block_ = true;
      open_.clear();
      samples_.for_each_in_block(b, [&](std::uint32_t i) {
        if (!flags_[i]) open_.push_back(i);
      });
    }
    for (std::size_t k = 0; k < open_.size();) {
      if ((samples_.point(open_[k]) - p).squaredNorm() <= r2_) {
        flags_[open_[k]] = true;
        open_[k] = open_.back();
        open_.pop_back();
      } else {
        ++k;
      }
    }
  }

 private:
  const detail::PointHash& samples_;
  double r2_;
  Flags& flags_;
  detail::PointHash::Block block_;
  bool have_block_ = false;
  std::vector<std::uint32_t> open_;  // the block's samples not flagged yet
};

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

CoverageAccumulator::CoverageAccumulator(const CoverageReference& reference, double tolerance)
    : reference_(reference), tolerance_(tolerance), covered_(reference.points.size(), false) {
  if (!(tolerance > 0)) throw std::invalid_argument("measure_coverage: tolerance must be > 0");
  if (reference.points.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("measure_coverage: too many reference samples");
  samples_ = std::make_unique<detail::PointHash>(reference.points, 2 * tolerance);
}

CoverageAccumulator::~CoverageAccumulator() = default;

void CoverageAccumulator::add(const Eigen::Vector3d& point_world) {
  if (!point_world.allFinite()) return;
  samples_->for_each_within(point_world, tolerance_, [&](std::uint32_t i) { covered_[i] = true; });
}

void CoverageAccumulator::add(const std::vector<Eigen::Vector3f>& points_world) {
  add(
      points_world.size(),
      [&](std::size_t i) { return Eigen::Vector3d(points_world[i].cast<double>()); }, 1);
}

void CoverageAccumulator::add(std::size_t count,
                              const std::function<Eigen::Vector3d(std::size_t)>& point_world,
                              unsigned threads) {
  // Each worker flags what its share of the points covers in flags of its own, then ORs
  // them into the accumulated ones.
  constexpr std::size_t kChunk = 1 << 14;
  std::atomic<std::size_t> next{0};
  std::mutex merge;
  detail::run_on_threads(std::min<unsigned>(detail::thread_count(threads),
                                            unsigned(std::max<std::size_t>(1, count / kChunk))),
                         [&](bool) {
                           std::vector<std::uint8_t> flags(covered_.size(), 0);
                           SampleFlagger<std::vector<std::uint8_t>> flagger(*samples_, tolerance_,
                                                                            flags);
                           for (std::size_t first; (first = next.fetch_add(kChunk)) < count;)
                             for (std::size_t i = first; i < std::min(count, first + kChunk); ++i) {
                               const Eigen::Vector3d p = point_world(i);
                               if (p.allFinite()) flagger.add(p);
                             }
                           const std::lock_guard<std::mutex> lock(merge);
                           for (std::size_t j = 0; j < flags.size(); ++j)
                             if (flags[j]) covered_[j] = true;
                         });
}

std::vector<bool> CoverageAccumulator::flags_of(
    const std::vector<Eigen::Vector3f>& points_world) const {
  std::vector<bool> out(covered_.size(), false);
  SampleFlagger<std::vector<bool>> flagger(*samples_, tolerance_, out);
  for (const Eigen::Vector3f& p : points_world)
    if (p.allFinite()) flagger.add(p.cast<double>());
  return out;
}

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3d>& measured_points_world,
                          double tolerance) {
  CoverageAccumulator acc(reference, tolerance);
  for (const Eigen::Vector3d& p : measured_points_world) acc.add(p);
  return acc.count();
}

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3f>& measured_points_world,
                          double tolerance) {
  return count_covered(covered_samples(reference, measured_points_world, tolerance));
}

std::vector<bool> covered_samples(const CoverageReference& reference,
                                  const std::vector<Eigen::Vector3f>& measured_points_world,
                                  double tolerance) {
  return CoverageAccumulator(reference, tolerance).flags_of(measured_points_world);
}

}  // namespace semioctree::sim
