// Why a survey missed the reference samples it did not cover (docs/coverage.md, "Missed
// samples"): in view of one of its scans but sampled too sparsely, or hidden from all.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/ground_truth.h"

namespace semioctree::sim {

struct MissedPart {
  PartRef part;
  std::string label;  // the element's place in the scene file, e.g. "boxes[2] (bench-3)"
  std::size_t in_view = 0;
  std::size_t hidden = 0;
};
struct MissedSamples {
  std::size_t in_view = 0;        // missed, though sample_visible_from some scan
  std::size_t hidden = 0;         // missed, visible from no scan
  std::vector<MissedPart> parts;  // elements with missed samples, most missed first
  // The missed samples, as indices into reference.points, ascending.
  std::vector<std::uint32_t> in_view_samples;
  std::vector<std::uint32_t> hidden_samples;
};

// `covered` is covered_samples of the survey's points, `optical_centres` those of its scans
// (world frame, true poses). Throws std::invalid_argument if `covered` does not match the
// reference, or if the reference was not made from this scene's samples (count differs).
MissedSamples explain_missed_samples(const GroundTruth& truth, const CoverageReference& reference,
                                     const std::vector<bool>& covered,
                                     const std::vector<Eigen::Vector3d>& optical_centres,
                                     unsigned threads = 0);

// "boxes[2] (bench-3)": where a scene element is in the scene file, with its name if any.
std::string part_label(const Scene& scene, const PartRef& part);

}  // namespace semioctree::sim
