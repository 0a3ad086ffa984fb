// Ground truth: openings in world coordinates, surface samples, visibility, floor plan.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"

namespace {

using namespace semioctree::sim;

const std::string kScenes = SEMIOCTREE_SOURCE_DIR "/sim/scenes";

Scene load(const std::string& name) {
  return load_scene_json(kScenes + "/" + name + ".scene.json");
}

TEST(Openings, AreRectanglesInWorldCoordinates) {
  const auto openings = opening_rects(load("one-door-window"));
  ASSERT_EQ(openings.size(), 2u);
  const OpeningRect& w = openings[0];
  EXPECT_EQ(w.kind, OpeningKind::window);
  EXPECT_EQ(w.wall, 0);
  EXPECT_DOUBLE_EQ(w.width, 1.5);
  EXPECT_DOUBLE_EQ(w.height, 1.2);
  // South wall from (-0.1, -0.1): start 2.0 → x 1.9 .. 3.4; sill 0.9 → z 0.9 .. 2.1.
  EXPECT_TRUE(w.corners[0].isApprox(Eigen::Vector3d(1.9, -0.1, 0.9)));
  EXPECT_TRUE(w.corners[1].isApprox(Eigen::Vector3d(3.4, -0.1, 0.9)));
  EXPECT_TRUE(w.corners[2].isApprox(Eigen::Vector3d(3.4, -0.1, 2.1)));
  EXPECT_TRUE(w.corners[3].isApprox(Eigen::Vector3d(1.9, -0.1, 2.1)));
  EXPECT_TRUE(w.normal.isApprox(Eigen::Vector3d(0, 1, 0)));
  const OpeningRect& d = openings[1];
  EXPECT_EQ(d.kind, OpeningKind::door);
  EXPECT_EQ(d.wall, 1);
  // East wall from (6.1, -0.1) towards +y: start 1.0 → y 0.9 .. 1.8, z 0 .. 2.05.
  EXPECT_TRUE(d.corners[0].isApprox(Eigen::Vector3d(6.1, 0.9, 0.0)));
  EXPECT_TRUE(d.corners[2].isApprox(Eigen::Vector3d(6.1, 1.8, 2.05)));
}

TEST(SurfaceSamples, CoverTheInnerWallsAtTheRequestedDensity) {
  const Scene s = load("box-room");
  const auto samples = surface_samples(s, 0.02);
  // Inner wall faces: 2 x (6 x 2.8) + 2 x (4 x 2.8) = 56 m², one sample per 4 cm².
  std::size_t inner = 0;
  for (const auto& p : samples) {
    EXPECT_NEAR(p.normal.norm(), 1.0, 1e-12);
    EXPECT_NE(p.part.kind, PartKind::slab);  // floors and ceilings are left out
    const bool inside = p.position.x() > -1e-9 && p.position.x() < 6 + 1e-9 &&
                        p.position.y() > -1e-9 && p.position.y() < 4 + 1e-9;
    if (inside) {
      ++inner;
      // Inner faces look into the room.
      const Eigen::Vector3d to_centre = Eigen::Vector3d(3, 2, p.position.z()) - p.position;
      EXPECT_GT(p.normal.dot(to_centre), 0) << p.position.transpose();
      EXPECT_GE(p.position.z(), 0.0);
      EXPECT_LE(p.position.z(), 2.8);
    }
  }
  EXPECT_NEAR(static_cast<double>(inner), 56.0 / (0.02 * 0.02), 0.02 * 56.0 / (0.02 * 0.02));
  // Wall tops under the ceiling and wall bottoms on the floor are buried: no horizontal samples.
  for (const auto& p : samples) EXPECT_LT(std::abs(p.normal.z()), 0.5) << p.position.transpose();
}

TEST(SurfaceSamples, LieOnTheirElementsAndSkipBuriedFaces) {
  const Scene s = load("lab");
  const double spacing = 0.05;  // coarser than the default: the lab has ~800 m² of surface
  const auto samples = surface_samples(s, spacing);
  std::size_t on_column = 0, on_boxes = 0, on_meshes = 0;
  for (const auto& p : samples) {
    if (p.part.kind == PartKind::cylinder &&
        p.part.index == 0) {  // the column, r = 0.25 around (6.8, 5)
      ++on_column;
      const double r = std::hypot(p.position.x() - 6.8, p.position.y() - 5.0);
      EXPECT_TRUE(std::abs(r - 0.25) < 1e-9 || std::abs(p.normal.z()) == 1.0);
    }
    if (p.part.kind == PartKind::box) {
      ++on_boxes;
      // Boxes standing on the floor have no samples on their bottom face.
      if (s.boxes[p.part.index].center.z() - s.boxes[p.part.index].size.z() / 2 == 0.0) {
        EXPECT_FALSE(p.normal.z() < -0.5 && std::abs(p.position.z()) < 1e-9)
            << s.boxes[p.part.index].name;
      }
    }
    if (p.part.kind == PartKind::mesh) ++on_meshes;
  }
  // Column side 2π·0.25 x 3.2 m ≈ 5.03 m² (its caps touch floor and ceiling).
  const double per_m2 = 1 / (spacing * spacing);
  EXPECT_NEAR(static_cast<double>(on_column), 5.03 * per_m2, 0.03 * 5.03 * per_m2);
  EXPECT_GT(on_boxes, 10000u);
  EXPECT_GT(on_meshes, 500u);
  // The instrument stands on bench-1: its bottom face is buried in the bench.
  for (const auto& p : samples) {
    if (p.part.kind == PartKind::box && s.boxes[p.part.index].name == "instrument") {
      EXPECT_GT(p.normal.z(), -0.5);
    }
  }
}

// The streamed samples and those picked by index are the listed ones, in their order
// (the coverage cache's key and the survey's missed samples read them so).
TEST(SurfaceSamples, StreamedAndPickedAsTheyAreListed) {
  const Scene s = load("lab");
  const double spacing = 0.05;
  const auto samples = surface_samples(s, spacing);
  ASSERT_GT(samples.size(), 100000u);
  auto same = [](const SurfaceSample& a, const SurfaceSample& b) {
    return a.position == b.position && a.normal == b.normal && a.part.kind == b.part.kind &&
           a.part.index == b.part.index;
  };
  std::size_t streamed = 0, differ = 0;
  for_each_surface_sample(s, spacing, [&](const SurfaceSample& q) {
    differ += streamed >= samples.size() || !same(q, samples[streamed]);
    ++streamed;
  });
  EXPECT_EQ(streamed, samples.size());
  EXPECT_EQ(differ, 0u);

  // Every 997th, the first and the last; an index past the end is left out.
  std::vector<std::uint32_t> picked{0};
  for (std::size_t i = 997; i + 1 < samples.size(); i += 997) picked.push_back(std::uint32_t(i));
  picked.push_back(std::uint32_t(samples.size() - 1));
  std::size_t total = 0;
  const auto at = surface_samples_at(s, spacing, picked, &total);
  EXPECT_EQ(total, samples.size());
  ASSERT_EQ(at.size(), picked.size());
  for (std::size_t k = 0; k < picked.size(); ++k)
    EXPECT_TRUE(same(at[k], samples[picked[k]])) << "index " << picked[k];
  picked.push_back(std::uint32_t(samples.size()));
  EXPECT_EQ(surface_samples_at(s, spacing, picked).size(), picked.size() - 1);
  EXPECT_THROW(surface_samples_at(s, spacing, {5, 3}), std::invalid_argument);
}

TEST(SurfaceSamples, OpeningsHaveNoSamplesButTheirJambsDo) {
  const Scene s = load("one-door-window");
  const auto samples = surface_samples(s, 0.02);
  std::size_t jambs = 0;
  for (const auto& p : samples) {
    if (p.part.kind != PartKind::wall || p.part.index != 0) continue;
    const bool in_window_span = p.position.x() > 1.9 + 1e-9 && p.position.x() < 3.4 - 1e-9 &&
                                p.position.z() > 0.9 + 1e-9 && p.position.z() < 2.1 - 1e-9;
    EXPECT_FALSE(in_window_span && std::abs(std::abs(p.position.y() + 0.1) - 0.1) < 1e-9)
        << "sample on a wall face inside the window: " << p.position.transpose();
    if (std::abs(p.normal.y()) < 1e-9) ++jambs;  // faces across the thickness
  }
  // Jambs, sill and lintel of the window: (2 x 1.2 + 2 x 1.5) x 0.2 m = 1.08 m², plus the
  // wall's two ends (2 x 2.8 x 0.2 = 1.12 m²) where not buried in the next wall.
  EXPECT_GT(jambs, static_cast<std::size_t>(1.08 / 0.0004 * 0.95));
}

TEST(SurfaceSamples, SpacingIsHonoured) {
  const Scene s = load("box-room");
  const double coarse = static_cast<double>(surface_samples(s, 0.04).size());
  const double fine = static_cast<double>(surface_samples(s, 0.02).size());
  EXPECT_NEAR(fine / coarse, 4.0, 0.1);
}

TEST(Visibility, SegmentFreeQuery) {
  const Scene s = load("one-door-window");
  const GroundTruth truth(s);
  EXPECT_TRUE(truth.segment_free({1, 1, 1.5}, {5, 3.5, 1.5}));
  EXPECT_FALSE(truth.segment_free({1, 2, 0.4}, {5, 2, 0.4}));       // through the table
  EXPECT_FALSE(truth.segment_free({1, 2, 1.5}, {-1, 2, 1.5}));      // through a wall
  EXPECT_TRUE(truth.segment_free({2.6, 2, 1.5}, {2.6, -3, 1.5}));   // out of the window
  EXPECT_TRUE(truth.segment_free({5, 1.35, 1.0}, {8, 1.35, 1.0}));  // out of the door
  // End points on surfaces count as free: a wall sample seen from inside the room.
  EXPECT_TRUE(truth.segment_free({1, 2, 1.5}, {-0.0, 2, 1.5}));
}

TEST(Visibility, EveryInnerWallSampleOfAnEmptyRoomIsSeen) {
  const Scene s = load("box-room");
  const GroundTruth truth(s);
  const Eigen::Vector3d scanner(2.0, 1.5, 1.5);
  std::size_t inner = 0, seen = 0;
  for (const auto& p : truth.surface_samples(0.05)) {
    if (p.normal.dot(scanner - p.position) <= 0) continue;  // faces away
    ++inner;
    seen += truth.segment_free(scanner, p.position);
  }
  EXPECT_GT(inner, 10000u);
  EXPECT_EQ(seen, inner);
}

TEST(Robot, StandingFree) {
  const Scene s = load("one-door-window");
  const GroundTruth truth(s);
  EXPECT_TRUE(truth.standing_free(s.robot.start));
  EXPECT_FALSE(truth.standing_free({3.0, 2.0}));  // on the table
  EXPECT_FALSE(truth.standing_free({3.0, 2.6}));  // next to it, closer than the robot's radius
  EXPECT_FALSE(truth.standing_free({0.3, 2.0}));  // too close to the west wall
  EXPECT_TRUE(truth.standing_free({5.0, 3.0}));
}

TEST(FloorPlan, RoomsOfTheLab) {
  const GroundTruth truth(load("lab"));
  const FloorPlan plan = truth.floor_plan(0.05);
  ASSERT_EQ(plan.room_area.size(), 4u);
  EXPECT_NEAR(plan.room_area[0], 10.4 * 8.5, 0.3);  // main room
  EXPECT_NEAR(plan.room_area[1], 13.6 * 1.8, 0.3);  // corridor
  EXPECT_NEAR(plan.room_area[2], 3.0 * 4.2, 0.2);   // small rooms
  EXPECT_NEAR(plan.room_area[3], 3.0 * 4.1, 0.2);
  EXPECT_EQ(plan.start_room, 0);
  EXPECT_EQ(plan.room_at({12.0, 9.5}), 1);
  EXPECT_EQ(plan.room_at({-5.0, -5.0}), -1);  // outside the building
  // The scene gives survey_area: the main room's floor.
  EXPECT_NEAR(plan.survey_area_m2, 10.4 * 8.5, 0.3);
  EXPECT_TRUE(plan.in_survey_area({5.2, 3.6}));
  EXPECT_FALSE(plan.in_survey_area({12.0, 2.0}));
}

TEST(FloorPlan, DefaultSurveyAreaIsTheReachableFreeFloor) {
  const GroundTruth box(load("box-room"));
  // 6 x 4 m room, robot radius 0.5 m: the centre may stand in 5 x 3 m.
  EXPECT_NEAR(box.floor_plan(0.05).survey_area_m2, 15.0, 0.5);

  const Scene s = load("one-door-window");
  const FloorPlan plan = GroundTruth(s).floor_plan(0.05);
  // The table (1.6 x 0.8, grown by the radius) is not standable; the 0.9 m door is too
  // narrow for a 1 m wide robot, so nothing outside the room is reachable.
  EXPECT_LT(plan.survey_area_m2, 15.0 - 1.6 * 0.8);
  EXPECT_GT(plan.survey_area_m2, 15.0 - (1.6 + 1.0) * (0.8 + 1.0) - 0.5);
  EXPECT_FALSE(plan.in_survey_area({3.0, 2.0}));
  EXPECT_FALSE(plan.in_survey_area({7.0, 1.35}));
  EXPECT_TRUE(plan.in_survey_area(s.robot.start));
}

// The floors of rooms the floor survey is tried on: rooms enclosed by walls, every one
// reachable by the robot from its start through the doors.
TEST(FloorPlan, ShippedFloorsHaveRoomsTheRobotReaches) {
  for (const auto& [file, rooms] : {std::pair<std::string, int>{"office-floor", 10},
                                    std::pair<std::string, int>{"apartment", 6}}) {
    const Scene scene = load_scene_json(kScenes + "/" + file + ".scene.json");
    const GroundTruth truth(scene);
    const FloorPlan plan = truth.floor_plan(0.05);
    ASSERT_EQ(int(plan.room_area.size()), rooms) << file;
    std::vector<bool> reached(plan.room_area.size(), false);
    for (std::size_t i = 0; i < plan.room.size(); ++i)
      if (plan.room[i] >= 0 && plan.reachable[i]) reached[std::size_t(plan.room[i])] = true;
    for (int r = 0; r < rooms; ++r) EXPECT_TRUE(reached[std::size_t(r)]) << file << " room " << r;
    EXPECT_TRUE(scene.survey_area) << file;  // the whole floor
  }
}

}  // namespace
