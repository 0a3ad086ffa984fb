// The visibility rule of the coverage reference: range, elevation and facing; segments
// through a door or window.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "semioctree/sim/coverage/visibility.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "support/coverage_scenes.h"

namespace {

using namespace semioctree::sim;
using namespace semioctree::testing;

TEST(CoverageReference, ASegmentPassesThroughAnOpeningWhenItLeavesTheWallThroughTheHole) {
  const Scene scene = load("one-door-window");
  // The window: south wall y -0.2 .. 0, x 1.9 .. 3.4, z 0.9 .. 2.1. The door: east wall
  // x 6.0 .. 6.2, y 0.9 .. 1.8, z 0 .. 2.05.
  const Eigen::Vector3d c(2.65, 2.0, 1.5);
  auto through = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const bool ab = segment_through_opening(scene, a, b);
    EXPECT_EQ(ab, segment_through_opening(scene, b, a)) << a.transpose() << " | " << b.transpose();
    return ab;
  };
  EXPECT_TRUE(through(c, {2.65, -3.0, 1.5}));  // straight out of the window
  EXPECT_TRUE(through(c, {1.0, -3.0, 1.0}));   // slanting: x 1.99 at y = 0, 1.92 at y = -0.2
  EXPECT_TRUE(through({5.0, 1.35, 1.0}, {8.0, 1.35, 1.0}));  // out of the door
  EXPECT_TRUE(through({5.0, 1.0, 1.8}, {9.0, 1.7, 2.0}));
  // Through the wall beside, above or below the hole: not through the opening.
  EXPECT_FALSE(through(c, {2.65, -3.0, 4.0}));                // y = 0 at z 2.5
  EXPECT_FALSE(through(c, {-1.0, -3.0, 1.5}));                // y = 0 at x 1.19
  EXPECT_FALSE(through(c, {2.65, -3.0, -0.5}));               // y = 0 at z 0.7
  EXPECT_FALSE(through({5.0, 1.35, 1.0}, {8.0, 1.35, 4.0}));  // in at z 2.0, out at 2.2: lintel
  // Where an end lies inside the wall's slab or on a face plane the rule is not
  // symmetric: a is the position, b the sample.
  auto out_of = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return segment_through_opening(scene, a, b);
  };
  // Samples inside the hole: on the west jamb (x 1.9, normal +x), the sill, the lintel;
  // or short of the wall.
  EXPECT_FALSE(out_of(c, {1.905, -0.1, 1.5}));
  EXPECT_FALSE(out_of(c, {1.905, -0.195, 1.0}));
  EXPECT_FALSE(out_of(c, {2.65, -0.15, 0.905}));
  EXPECT_FALSE(out_of(c, {2.65, -0.199, 2.095}));
  EXPECT_FALSE(out_of({5.0, 1.35, 1.0}, {6.1, 0.905, 1.0}));  // door jamb
  EXPECT_FALSE(through(c, {2.65, 0.5, 1.5}));
  // A sample on a face plane of the wall is not beyond it.
  EXPECT_FALSE(out_of(c, {2.65, -0.2, 1.5}));
  // From a position standing in the hole (inside the wall's slab, or on a face plane: a
  // scan in a doorway), what lies beyond a face is seen through the opening; from beyond
  // the wall, a sample in the hole or on its face plane is not.
  EXPECT_TRUE(out_of({2.65, 0.0, 1.5}, {2.65, -3.0, 1.5}));  // window's inner face plane
  EXPECT_FALSE(out_of({2.65, -3.0, 1.5}, {2.65, 0.0, 1.5}));
  EXPECT_TRUE(out_of({6.1, 1.35, 1.0}, {9.0, 1.35, 1.0}));     // in the doorway, out
  EXPECT_TRUE(out_of({6.1, 1.35, 1.0}, {3.0, 1.35, 1.0}));     // and back in
  EXPECT_TRUE(out_of({6.0, 1.35, 1.0}, {9.0, 1.0, 2.0}));      // on the door's inner face plane
  EXPECT_FALSE(out_of({6.0, 1.35, 1.0}, {7.0, 1.35, 7.0}));    // out at z 2.2: the lintel
  EXPECT_FALSE(out_of({6.1, 1.35, 1.0}, {6.15, 0.905, 1.0}));  // the jamb beside
  // Both ends on the same side, the segment parallel to the wall inside the hole.
  EXPECT_FALSE(through({2.0, -0.1, 1.5}, {3.0, -0.1, 1.5}));
  EXPECT_FALSE(through(c, {5.0, 3.0, 1.0}));
}

TEST(CoverageReference, RuleHonoursRangeElevationAndFacing) {
  Scene scene = load("box-room");
  const GroundTruth truth(scene);
  // A sample on the south wall's inner face (normal +y) at (3, 0, z).
  SurfaceSample s;
  s.normal = Eigen::Vector3d::UnitY();
  s.position = {3.0, 0.0, 1.0};
  EXPECT_TRUE(sample_visible_from(truth, s, {3.0, 2.0, 1.5}));
  // Behind the face: not facing.
  SurfaceSample back = s;
  back.normal = -back.normal;
  EXPECT_FALSE(sample_visible_from(truth, back, {3.0, 2.0, 1.5}));
  // Closer than min_range (0.6 m).
  EXPECT_FALSE(sample_visible_from(truth, s, {3.0, 0.5, 1.2}));
  // Below elevation_min_deg (-60°): the wall foot 0.5 m away, 1.5 m down (-71.6°).
  s.position.z() = 0.01;
  EXPECT_FALSE(sample_visible_from(truth, s, {3.0, 0.5, 1.5}));
  EXPECT_TRUE(sample_visible_from(truth, s, {3.0, 1.0, 1.5}));  // -56°
  // Beyond max_range.
  scene.scanner.max_range = 1.5;
  const GroundTruth short_range(scene);
  EXPECT_FALSE(sample_visible_from(short_range, s, {3.0, 2.0, 1.5}));
}

}  // namespace
