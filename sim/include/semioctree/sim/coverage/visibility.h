// The visibility rule of the coverage reference: whether a scan position sees a surface
// sample (docs/coverage.md, "The visibility rule").
#pragma once

#include <Eigen/Core>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"

namespace semioctree::sim {

// The rule tests the segment from the optical centre to p + kCoverageSampleOffset · normal.
constexpr double kCoverageSampleOffset = 0.005;

// True if `sample` is visible from the optical centre c: within the scanner's range and
// elevation limits seen from c, facing c (dot(normal, c − p) > 0), and the tested segment
// crosses no geometry and does not pass through a door or window (segment_through_opening).
bool sample_visible_from(const GroundTruth& truth, const SurfaceSample& sample,
                         const Eigen::Vector3d& optical_centre);

// The same rule without the condition on openings: what the scanner itself measures.
bool sample_in_line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                             const Eigen::Vector3d& optical_centre);

// True if the segment from the position a to the sample b passes through a door or
// window: b lies strictly beyond a face of a wall, a short of that face (beyond the other
// face, or inside the wall's slab or on a face plane: standing in a doorway), and each
// face the segment crosses it crosses within an opening of that wall (1 mm tolerance).
// A sample inside the hole (on a jamb, the sill or the lintel) or on a face plane is not
// beyond. No ray query.
bool segment_through_opening(const Scene& scene, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b);

}  // namespace semioctree::sim
