// Survey coverage: the reference samples a survey's points come close to.
#pragma once

#include <Eigen/Core>
#include <cstddef>
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

}  // namespace semioctree::sim
