// The visibility rule of the coverage reference, one sample and one position at a time.
#include "semioctree/sim/coverage/visibility.h"

#include <vector>

#include "coverage/visibility_rule.h"
#include "coverage/wall_culling.h"

namespace semioctree::sim {

bool segment_through_opening(const Scene& scene, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b) {
  const std::vector<detail::WallSlab> walls = detail::wall_slabs(scene);
  std::vector<double> wa(walls.size()), wb(walls.size());
  detail::wall_offsets(walls, a, wa.data());
  detail::wall_offsets(walls, b, wb.data());
  return detail::at_walls(walls, a, wa.data(), b, wb.data(), false) == detail::AtWalls::opening;
}

bool sample_in_line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                             const Eigen::Vector3d& optical_centre) {
  return detail::within_limits(detail::scanner_limits(truth.scene().scanner), sample,
                               optical_centre) &&
         detail::line_of_sight(truth, sample, optical_centre);
}

bool sample_visible_from(const GroundTruth& truth, const SurfaceSample& sample,
                         const Eigen::Vector3d& optical_centre) {
  return detail::within_limits(detail::scanner_limits(truth.scene().scanner), sample,
                               optical_centre) &&
         !segment_through_opening(truth.scene(), optical_centre, detail::segment_target(sample)) &&
         detail::line_of_sight(truth, sample, optical_centre);
}

}  // namespace semioctree::sim
