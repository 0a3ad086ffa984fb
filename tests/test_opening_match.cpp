// Detected openings against a scene's true ones (sim_platform/opening_match.h): the IoU
// in the wall plane, the one-to-one matching, precision and recall, and which true
// openings belong to the surveyed room.
#include <gtest/gtest.h>

#include <string>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/opening_match.h"

namespace semioctree::sim_platform {
namespace {

using Vec3 = Eigen::Vector3d;

// A true door 1 m wide and 2 m high in the wall y = 0, x from 1 to 2.
sim::OpeningRect true_door() {
  sim::OpeningRect g;
  g.kind = sim::OpeningKind::door;
  g.corners = {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(2, 0, 2), Vec3(1, 0, 2)};
  g.width = 1, g.height = 2;
  g.normal = Vec3(0, 1, 0);
  return g;
}

DetectedOpening detected(OpeningKind kind, double x0, double x1, double z0, double z1,
                         double y = 0.0) {
  DetectedOpening d;
  d.kind = kind;
  d.corners = {Vec3(x0, y, z0), Vec3(x1, y, z0), Vec3(x1, y, z1), Vec3(x0, y, z1)};
  d.width = x1 - x0, d.height = z1 - z0;
  d.wall_normal = Vec3(0, -1, 0);  // either side of the wall
  return d;
}

const Eigen::Isometry3d kWorld = Eigen::Isometry3d::Identity();

TEST(OpeningMatch, IouInTheWallPlane) {
  const sim::OpeningRect g = true_door();
  EXPECT_DOUBLE_EQ(opening_iou(detected(OpeningKind::kDoor, 1, 2, 0, 2), g, kWorld), 1.0);
  // Half a width off: overlap 1 m², union 3 m².
  EXPECT_NEAR(opening_iou(detected(OpeningKind::kDoor, 1.5, 2.5, 0, 2), g, kWorld), 1.0 / 3, 1e-12);
  EXPECT_EQ(opening_iou(detected(OpeningKind::kWindow, 1, 2, 0, 2), g, kWorld), 0.0);
  EXPECT_EQ(opening_iou(detected(OpeningKind::kDoor, 1, 2, 0, 2, 0.5), g, kWorld), 0.0);
  // In another frame: the detection moved with the frame matches as before.
  Eigen::Isometry3d to_frame = Eigen::Isometry3d::Identity();
  to_frame.rotate(Eigen::AngleAxisd(0.5, Vec3::UnitZ()));
  to_frame.pretranslate(Vec3(3, -1, 0));
  DetectedOpening moved = detected(OpeningKind::kDoor, 1, 2, 0, 2);
  for (Vec3& c : moved.corners) c = to_frame * c;
  moved.wall_normal = to_frame.linear() * moved.wall_normal;
  EXPECT_NEAR(opening_iou(moved, g, to_frame), 1.0, 1e-9);
  EXPECT_LT(opening_iou(moved, g, kWorld), 0.5);
}

TEST(OpeningMatch, OneToOnePrecisionAndRecall) {
  const std::vector<sim::OpeningRect> truths{true_door()};
  // Two detections of the one door: one matches, the other is a false positive.
  const std::vector<DetectedOpening> twice{detected(OpeningKind::kDoor, 1.05, 2, 0, 2),
                                           detected(OpeningKind::kDoor, 1, 2, 0, 1.9)};
  OpeningsMatch m = match_openings(twice, truths, kWorld);
  EXPECT_EQ(m.matched, 1u);
  EXPECT_DOUBLE_EQ(m.precision, 0.5);
  EXPECT_DOUBLE_EQ(m.recall, 1.0);
  EXPECT_DOUBLE_EQ(m.detection_iou[0], 0.95);  // the better one is taken
  EXPECT_EQ(m.detection_iou[1], 0.0);
  // A detection below the IoU threshold matches nothing.
  m = match_openings({detected(OpeningKind::kDoor, 1.5, 2.5, 0, 2)}, truths, kWorld);
  EXPECT_EQ(m.matched, 0u);
  EXPECT_EQ(m.precision, 0.0);
  EXPECT_EQ(m.recall, 0.0);
  // Nothing to find and nothing found: perfect.
  m = match_openings({}, {}, kWorld);
  EXPECT_EQ(m.precision, 1.0);
  EXPECT_EQ(m.recall, 1.0);
}

TEST(OpeningMatch, OpeningsOfTheSurveyedRoom) {
  // The lab's main room has the window and three doors; the small rooms east share two
  // of the doors, the corridor one.
  const sim::Scene lab =
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
  const sim::GroundTruth truth(lab);
  const sim::FloorPlan plan = truth.floor_plan(0.05);
  EXPECT_EQ(openings_of_room(truth, plan, plan.start_room).size(), 4u);
  const int small_room = plan.room_at(Eigen::Vector2d(12.0, 2.0));
  ASSERT_GE(small_room, 0);
  ASSERT_NE(small_room, plan.start_room);
  const auto small = openings_of_room(truth, plan, small_room);
  ASSERT_EQ(small.size(), 1u);
  EXPECT_EQ(small[0].kind, sim::OpeningKind::door);
}

}  // namespace
}  // namespace semioctree::sim_platform
