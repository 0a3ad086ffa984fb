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
                           for (std::size_t first; (first = next.fetch_add(kChunk)) < count;)
                             for (std::size_t i = first; i < std::min(count, first + kChunk); ++i) {
                               const Eigen::Vector3d p = point_world(i);
                               if (p.allFinite())
                                 samples_->for_each_within(p, tolerance_,
                                                           [&](std::uint32_t j) { flags[j] = 1; });
                             }
                           const std::lock_guard<std::mutex> lock(merge);
                           for (std::size_t j = 0; j < flags.size(); ++j)
                             if (flags[j]) covered_[j] = true;
                         });
}

std::vector<bool> CoverageAccumulator::flags_of(
    const std::vector<Eigen::Vector3f>& points_world) const {
  std::vector<bool> out(covered_.size(), false);
  for (const Eigen::Vector3f& p : points_world)
    if (p.allFinite())
      samples_->for_each_within(p.cast<double>(), tolerance_,
                                [&](std::uint32_t i) { out[i] = true; });
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
