// Missed reference samples: in view of a scan but sampled too sparsely, or hidden.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "semioctree/sim/coverage/measure.h"
#include "semioctree/sim/coverage/misses.h"
#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "support/coverage_scenes.h"

namespace {

using namespace semioctree::sim;
using namespace semioctree::testing;

TEST(Coverage, MissedSamplesAreSplitIntoSparselySampledAndHidden) {
  // box-room with a crate east of the start: its east face looks away from the scanner.
  Scene scene = load("box-room");
  Box crate;  // x 3.7 .. 4.3, y 1.7 .. 2.3, z 0 .. 1
  crate.center = {4.0, 2.0, 0.5};
  crate.size = {0.6, 0.6, 1.0};
  crate.name = "crate";
  scene.boxes.push_back(crate);
  const GroundTruth truth(scene);
  const CoverageReference ref = compute_coverage_reference(truth, 0.5, 0.02);
  const std::vector<SurfaceSample> samples = truth.surface_samples(0.02);
  const Eigen::Vector3d centre(scene.robot.start.x(), scene.robot.start.y(), scene.scanner.height);
  const std::vector<Eigen::Vector3d> points = scan_from_start(truth);
  std::vector<Eigen::Vector3f> measured;
  for (const auto& p : points) measured.push_back(p.cast<float>());
  const std::vector<bool> covered = covered_samples(ref, measured);
  const std::size_t n_covered = std::size_t(std::count(covered.begin(), covered.end(), true));

  const MissedSamples full = explain_missed_samples(truth, ref, covered, {centre}, 2);
  EXPECT_EQ(full.in_view + full.hidden, ref.visible.size() - n_covered);
  // The crate's east face, away from its edges (a point on the top or a side face can lie
  // within 3 cm of a sample near an edge): faces away from the scanner, so hidden.
  std::size_t east_face = 0;
  for (std::uint32_t i : ref.visible) {
    const SurfaceSample& s = samples[i];
    if (s.part.kind == PartKind::box && s.normal.x() > 0.99 && s.position.z() < 0.95 &&
        s.position.y() > 1.75 && s.position.y() < 2.25)
      ++east_face;
  }
  ASSERT_GT(east_face, 500u);  // 0.4 x 0.95 m at 2 cm
  ASSERT_FALSE(full.parts.empty());
  const auto crate_part =
      std::find_if(full.parts.begin(), full.parts.end(),
                   [](const MissedPart& p) { return p.label == "boxes[0] (crate)"; });
  ASSERT_NE(crate_part, full.parts.end());
  EXPECT_GE(crate_part->hidden, east_face);
  for (std::size_t k = 1; k < full.parts.size(); ++k)
    EXPECT_GE(full.parts[k - 1].in_view + full.parts[k - 1].hidden,
              full.parts[k].in_view + full.parts[k].hidden);
  std::size_t by_part = 0;
  for (const MissedPart& p : full.parts) by_part += p.in_view + p.hidden;
  EXPECT_EQ(by_part, full.in_view + full.hidden);
  // A small convex room at 0.2°: what the scan sees it samples densely enough.
  EXPECT_LT(full.in_view, full.hidden / 10) << full.in_view << " in view, " << full.hidden;

  // One point in 25 kept: the same view, sampled five times more sparsely each way.
  std::vector<Eigen::Vector3f> sparse;
  for (std::size_t i = 0; i < measured.size(); i += 25) sparse.push_back(measured[i]);
  const std::vector<bool> covered_sparse = covered_samples(ref, sparse);
  const MissedSamples thin = explain_missed_samples(truth, ref, covered_sparse, {centre}, 1);
  EXPECT_GT(thin.in_view, 10 * full.in_view + ref.visible.size() / 10);
  EXPECT_GE(thin.hidden, full.hidden);
  EXPECT_LT(thin.hidden, full.hidden + ref.visible.size() / 100);

  // Without any scan position every missed sample is hidden.
  const MissedSamples none = explain_missed_samples(truth, ref, covered, {});
  EXPECT_EQ(none.in_view, 0u);
  EXPECT_EQ(none.hidden, ref.visible.size() - n_covered);

  EXPECT_THROW(explain_missed_samples(truth, ref, std::vector<bool>(3), {centre}),
               std::invalid_argument);
  EXPECT_THROW(explain_missed_samples(GroundTruth(load("box-room")), ref, covered, {centre}),
               std::invalid_argument);
  EXPECT_EQ(part_label(scene, {PartKind::wall, 1}), "walls[1]");
  EXPECT_EQ(part_label(scene, {PartKind::box, 0}), "boxes[0] (crate)");
}

}  // namespace
