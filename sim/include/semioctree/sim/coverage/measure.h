// Survey coverage: the reference samples a survey's points come close to.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "semioctree/sim/coverage/reference.h"

namespace semioctree::sim {

struct Coverage {
  std::size_t reference_points = 0;
  std::size_t covered = 0;  // reference samples with a measured point within the tolerance
  double percent = 0.0;     // 100 · covered / reference_points (0 for an empty reference)
};

// Counts the reference samples with a measured point (world frame) within `tolerance`
// metres. Non-finite points are ignored. Throws std::invalid_argument unless tolerance > 0.
Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3d>& measured_points_world,
                          double tolerance = 0.03);
Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3f>& measured_points_world,
                          double tolerance = 0.03);

// The counts of covered_samples' flags (what measure_coverage returns).
Coverage count_covered(const std::vector<bool>& covered);

// One flag per reference sample (in the order of reference.points): a measured point
// (world frame) within `tolerance` metres. measure_coverage counts these flags.
std::vector<bool> covered_samples(const CoverageReference& reference,
                                  const std::vector<Eigen::Vector3f>& measured_points_world,
                                  double tolerance = 0.03);

namespace detail {
class PointHash;
}

// The samples a survey's scans have covered so far, one flag per reference sample. The
// reference's samples are hashed once; each measured point then flags the samples near it
// and need not be kept (a survey of 5 scans of 5.4 million points would otherwise hold
// them all to count them at the end).
class CoverageAccumulator {
 public:
  // Throws std::invalid_argument unless tolerance > 0. `reference` must outlive this.
  explicit CoverageAccumulator(const CoverageReference& reference, double tolerance = 0.03);
  ~CoverageAccumulator();

  // Flags the samples within the tolerance of a measured point (world frame); a point
  // that is not finite is ignored.
  void add(const Eigen::Vector3d& point_world);
  void add(const std::vector<Eigen::Vector3f>& points_world);
  // The same for `count` points, point i being `point_world(i)`, on `threads` workers (0:
  // one per core): the flags set do not depend on them. point_world must be thread-safe.
  void add(std::size_t count, const std::function<Eigen::Vector3d(std::size_t)>& point_world,
           unsigned threads);

  // The flags these points alone set (what add would flag), the accumulated ones untouched.
  std::vector<bool> flags_of(const std::vector<Eigen::Vector3f>& points_world) const;

  const std::vector<bool>& covered() const { return covered_; }
  Coverage count() const { return count_covered(covered_); }
  const CoverageReference& reference() const { return reference_; }

 private:
  const CoverageReference& reference_;
  double tolerance_;
  std::unique_ptr<detail::PointHash> samples_;  // the reference's points
  std::vector<bool> covered_;
};

}  // namespace semioctree::sim
