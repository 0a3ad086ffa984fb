// Rooms of a map (src/nbv/rooms.cpp) on hand-built maps: two rooms a door apart, the same
// with the doorway open, an L-shaped room (a region, not its box), and the openings linked
// to the rooms on their two sides.
#include <gtest/gtest.h>

#include <cmath>

#include "semioctree/nbv.h"
#include "support/nbv_maps.h"

namespace semioctree {
namespace {

using testing::kLeaf;
using testing::Map;

constexpr double kHeight = 1.2;  // the plane's height (a scanner's)

// Two rooms of 4 × 4.8 m side by side (x ∈ [0, 4) and [4.05, 8)), 2.4 m high, a wall at
// x = 4 with a doorway at y ∈ [1.6, 2.4), 2.0 m high: labelled door, or left empty.
struct TwoRooms : Map {
  explicit TwoRooms(bool door_labelled) : Map(10, 6, 3) {
    leaves({0, 0, 0}, {8.0, kLeaf, 2.4}, Label::kOccupied);
    leaves({0, 4.8 - kLeaf, 0}, {8.0, 4.8, 2.4}, Label::kOccupied);
    leaves({0, 0, 0}, {kLeaf, 4.8, 2.4}, Label::kOccupied);
    leaves({8.0 - kLeaf, 0, 0}, {8.0, 4.8, 2.4}, Label::kOccupied);
    leaves({4.0, 0, 0}, {4.0 + kLeaf, 1.6, 2.4}, Label::kOccupied);
    leaves({4.0, 2.4, 0}, {4.0 + kLeaf, 4.8, 2.4}, Label::kOccupied);
    leaves({4.0, 1.6, 2.0}, {4.0 + kLeaf, 2.4, 2.4}, Label::kOccupied);
    if (door_labelled) leaves({4.0, 1.6, 0}, {4.0 + kLeaf, 2.4, 2.0}, Label::kDoor);
  }
};

DetectedOpening door_at_x4() {
  DetectedOpening d;
  d.kind = OpeningKind::kDoor;
  d.corners = {Eigen::Vector3d(4.025, 1.6, 0), Eigen::Vector3d(4.025, 2.4, 0),
               Eigen::Vector3d(4.025, 2.4, 2.0), Eigen::Vector3d(4.025, 1.6, 2.0)};
  d.width = 0.8, d.height = 2.0;
  d.wall_normal = Eigen::Vector3d::UnitX();
  return d;
}

TEST(NbvRooms, ADoorSeparatesTwoRoomsAndLinksThem) {
  TwoRooms m(true);
  const RoomMap rooms = segment_rooms(m.t, kHeight, 0.0, 2.4, {door_at_x4()});
  ASSERT_EQ(rooms.rooms().size(), 2u);
  const std::optional<std::size_t> west = rooms.room_at(Point3(2, 2, 0));
  const std::optional<std::size_t> east = rooms.room_at(Point3(6, 2, 0));
  ASSERT_TRUE(west && east);
  EXPECT_NE(*west, *east);
  EXPECT_EQ(*west, 0u);  // numbered in grid order: the west room's first cell comes first
  // Free inside the walls: x ∈ [1 leaf, 4), y ∈ [1 leaf, 4.8 − 1 leaf) for the west room.
  const Room& w = rooms.rooms()[*west];
  EXPECT_EQ(w.cells, std::size_t(std::lround((4.0 - kLeaf) / kLeaf) *
                                 std::lround((4.8 - 2 * kLeaf) / kLeaf)));
  EXPECT_NEAR(w.area_m2, (4.0 - kLeaf) * (4.8 - 2 * kLeaf), 1e-9);
  EXPECT_NEAR(w.min.x, kLeaf, 1e-9);
  EXPECT_NEAR(w.max.x, 4.0, 1e-9);
  EXPECT_NEAR(w.min.y, kLeaf, 1e-9);
  EXPECT_NEAR(w.max.y, 4.8 - kLeaf, 1e-9);
  EXPECT_EQ(w.min.z, 0.0);
  EXPECT_EQ(w.max.z, 2.4);
  // Walls, doors and points outside the map are in no room.
  EXPECT_FALSE(rooms.room_at(Point3(4.02, 3.0, 0)));
  EXPECT_FALSE(rooms.room_at(Point3(4.02, 2.0, 0)));
  EXPECT_FALSE(rooms.room_at(Point3(-5, 2, 0)));
  // The door joins them: in front (along +x) the east room, behind it the west one.
  ASSERT_EQ(rooms.links().size(), 1u);
  EXPECT_EQ(rooms.links()[0].front, east);
  EXPECT_EQ(rooms.links()[0].back, west);
  EXPECT_EQ(rooms.rooms()[*west].openings, std::vector<std::size_t>{0});
  EXPECT_EQ(rooms.rooms()[*east].openings, std::vector<std::size_t>{0});
}

// A door detected a leaf short of each jamb (its label too): the rays that passed the gaps
// saw the space behind directly. The opening's sill line, drawn past its edges, still
// keeps the rooms apart.
TEST(NbvRooms, ADoorDetectedShortOfItsJambsStillSeparatesTheRooms) {
  TwoRooms m(false);
  m.leaves({4.0, 1.6 + kLeaf, 0}, {4.0 + kLeaf, 2.4 - kLeaf, 2.0}, Label::kDoor);
  DetectedOpening d = door_at_x4();
  d.corners[0].y() = d.corners[3].y() = 1.6 + kLeaf;
  d.corners[1].y() = d.corners[2].y() = 2.4 - kLeaf;
  d.width = 0.8 - 2 * kLeaf;
  // Without the opening, the gaps beside the door label join the rooms.
  EXPECT_EQ(segment_rooms(m.t, kHeight, 0.0, 2.4).rooms().size(), 1u);
  const RoomMap rooms = segment_rooms(m.t, kHeight, 0.0, 2.4, {d});
  ASSERT_EQ(rooms.rooms().size(), 2u);
  EXPECT_NE(rooms.room_at(Point3(2, 2, 0)), rooms.room_at(Point3(6, 2, 0)));
  ASSERT_EQ(rooms.links().size(), 1u);
  EXPECT_TRUE(rooms.links()[0].front && rooms.links()[0].back);
  // A scanner's own cell may be in no room (its blind zone): room_near finds the room
  // around it, and nothing farther than the radius.
  EXPECT_FALSE(rooms.room_at(Point3(4.03, 2.0, 0)));  // the door
  EXPECT_EQ(rooms.room_near(Point3(4.03, 2.0, 0), 1.0),
            rooms.room_at(Point3(2, 2, 0)));  // ties: grid order
  EXPECT_EQ(rooms.room_near(Point3(4.03, 2.0, 0), 0.01), std::nullopt);
  EXPECT_EQ(rooms.room_near(Point3(8.6, 2.0, 0), 1.0), rooms.room_at(Point3(6, 2, 0)));
  EXPECT_FALSE(rooms.room_near(Point3(-3.0, 2.0, 0), 1.0));
}

// Without the door label the doorway is free space: one room through it. Above the
// door's top the wall separates them again.
TEST(NbvRooms, AnUnlabelledDoorwayJoinsTheRoomsBelowItsTop) {
  TwoRooms m(false);
  const RoomMap low = segment_rooms(m.t, kHeight, 0.0, 2.4);
  EXPECT_EQ(low.rooms().size(), 1u);
  EXPECT_EQ(low.room_at(Point3(2, 2, 0)), low.room_at(Point3(6, 2, 0)));
  const RoomMap high = segment_rooms(m.t, 2.2, 0.0, 2.4);
  EXPECT_EQ(high.rooms().size(), 2u);
}

// An L: its room is the L's cells, not the box around it (which holds the space outside
// the corner).
TEST(NbvRooms, AnLShapedRoomIsItsCellsNotItsBox) {
  Map m(6, 6, 3);
  // Free L: [0, 4.8) × [0, 2.4) and [0, 2.4) × [2.4, 4.8); the outer quadrant is occupied.
  m.leaves({2.4, 2.4, 0}, {4.8, 4.8, 2.4}, Label::kOccupied);
  const RoomMap rooms = segment_rooms(m.t, kHeight, 0.0, 2.4);
  ASSERT_EQ(rooms.rooms().size(), 1u);
  const Room& l = rooms.rooms()[0];
  EXPECT_NEAR(l.area_m2, 4.8 * 4.8 - 2.4 * 2.4, 1e-9);
  EXPECT_NEAR((l.max.x - l.min.x) * (l.max.y - l.min.y), 4.8 * 4.8, 1e-9);  // its box
  EXPECT_FALSE(rooms.room_at(Point3(3.6, 3.6, 0)));
  EXPECT_EQ(rooms.room_at(Point3(1.2, 3.6, 0)), std::optional<std::size_t>(0));
  // Its outline: six sides, 4 × 4.8 m long in all (as its box's), joined into 8 segments
  // (the two long sides split where the other arm starts: rows and columns are joined only
  // where the same cells face the same way); the point for its label lies inside it.
  double length = 0;
  for (const auto& e : l.outline) {
    EXPECT_TRUE(e[0] == e[2] || e[1] == e[3]);  // along a row or a column
    length += std::hypot(double(e[2] - e[0]), double(e[3] - e[1]));
  }
  EXPECT_NEAR(length, 4 * 4.8, 1e-4);
  EXPECT_LE(l.outline.size(), 8u);
  EXPECT_EQ(rooms.room_at(l.inner), std::optional<std::size_t>(0));
}

// Each of two rooms a door apart is outlined on its own: the door's line closes it.
TEST(NbvRooms, RoomsAreOutlinedAlongTheirCells) {
  TwoRooms m(true);
  const RoomMap rooms = segment_rooms(m.t, kHeight, 0.0, 2.4, {door_at_x4()});
  ASSERT_EQ(rooms.rooms().size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const Room& room = rooms.rooms()[i];
    double length = 0;
    for (const auto& e : room.outline)
      length += std::hypot(double(e[2] - e[0]), double(e[3] - e[1]));
    EXPECT_NEAR(length, 2 * ((room.max.x - room.min.x) + (room.max.y - room.min.y)), 1e-4) << i;
    EXPECT_EQ(rooms.room_at(room.inner), std::optional<std::size_t>(i));
  }
}

// Space seen through a window (out) is a room of its own beyond it; an opening whose one
// side holds no free cell within reach has no room there.
TEST(NbvRooms, SpaceSeenThroughAWindowIsBeyondIt) {
  Map m(6, 6, 3);
  m.leaves({2.4, 0, 0}, {2.4 + kLeaf, 4.8, 2.4}, Label::kOccupied);
  m.leaves({2.4, 1.6, 0.9}, {2.4 + kLeaf, 3.2, 2.0}, Label::kWindow);
  m.leaves({2.4 + kLeaf, 0, 0}, {4.8, 4.8, 2.4}, Label::kOut);
  DetectedOpening w;
  w.kind = OpeningKind::kWindow;
  w.corners = {Eigen::Vector3d(2.425, 1.6, 0.9), Eigen::Vector3d(2.425, 3.2, 0.9),
               Eigen::Vector3d(2.425, 3.2, 2.0), Eigen::Vector3d(2.425, 1.6, 2.0)};
  w.wall_normal = -Eigen::Vector3d::UnitX();  // facing the room
  DetectedOpening far = w;  // in the middle of the room: no wall, rooms beyond reach
  for (Eigen::Vector3d& c : far.corners) c.x() = 1.2;
  const RoomMap rooms = segment_rooms(m.t, kHeight, 0.0, 2.4, {w, far});
  ASSERT_EQ(rooms.rooms().size(), 2u);
  const std::optional<std::size_t> inside = rooms.room_at(Point3(1, 1, 0));
  const std::optional<std::size_t> outside = rooms.room_at(Point3(4, 1, 0));
  ASSERT_TRUE(inside && outside);
  EXPECT_EQ(rooms.links()[0].front, inside);
  EXPECT_EQ(rooms.links()[0].back, outside);
  EXPECT_EQ(rooms.links()[1].front, inside);  // free cells on both sides: the same room
  EXPECT_EQ(rooms.links()[1].back, inside);
  EXPECT_EQ(rooms.rooms()[*inside].openings, (std::vector<std::size_t>{0, 1}));
}

TEST(NbvRooms, AnEmptyMapHasNoRooms) {
  SemiOcTree t(kLeaf, 0.8);
  const RoomMap rooms = segment_rooms(t, kHeight, 0.0, 2.4);
  EXPECT_TRUE(rooms.rooms().empty());
  EXPECT_FALSE(rooms.room_at(Point3(0, 0, 0)));
}

}  // namespace
}  // namespace semioctree
