// Survey coverage: the reference samples with a measured point nearby.
#include "semioctree/sim/coverage/measure.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include "coverage/spatial_hash.h"

namespace semioctree::sim {

namespace {

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
  const detail::PointHash hash(std::move(points), tolerance);
  for (std::size_t i = 0; i < reference.points.size(); ++i)
    out[i] = hash.any_within(reference.points[i], tolerance);
  return out;
}

std::vector<Eigen::Vector3d> to_double(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(p.cast<double>());
  return out;
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

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3d>& measured_points_world,
                          double tolerance) {
  return count_covered(flags(reference, measured_points_world, tolerance));
}

Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3f>& measured_points_world,
                          double tolerance) {
  return count_covered(flags(reference, to_double(measured_points_world), tolerance));
}

std::vector<bool> covered_samples(const CoverageReference& reference,
                                  const std::vector<Eigen::Vector3f>& measured_points_world,
                                  double tolerance) {
  return flags(reference, to_double(measured_points_world), tolerance);
}

}  // namespace semioctree::sim
