// Stage 8: a map refined scan by scan against one built from scratch.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "semioctree/update.h"

namespace semioctree {
namespace {

void add(Cloud& c, double x, double y, double z) {
  c.push_back(pcl::PointXYZ{float(x), float(y), float(z)});
}

// A 4 × 4 m room (walls of points) with a pillar, and — only in the second
// scan — the walls of a 2 m deep alcove beyond a gap in the wall at x = 4
// (out of the first scan's range).
Cloud room_scan(bool with_alcove) {
  Cloud c;
  const double step = 0.02;
  for (double z = step; z < 2.4; z += step) {
    for (double t = 0; t <= 4.0; t += step) {
      add(c, t, 0.01, z);
      add(c, t, 3.99, z);
      add(c, 0.01, t, z);
      if (!(t > 1.5 && t < 2.5)) add(c, 3.99, t, z);  // a gap to the alcove
    }
    if (z < 1.6)
      for (double t = 0; t < 0.6; t += step) {
        add(c, 2.0 + t, 1.0, z);
        add(c, 2.0 + t, 1.59, z);
        add(c, 2.0, 1.0 + t, z);
        add(c, 2.59, 1.0 + t, z);
      }
    if (with_alcove)
      for (double t = 0; t <= 2.0; t += step) {
        add(c, 4.0 + t, 1.51, z);
        add(c, 4.0 + t, 2.49, z);
        if (t <= 1.0) add(c, 5.99, 1.5 + t, z);
      }
  }
  return c;
}

SurveyMapParams params() {
  SurveyMapParams p;
  p.limits.min_range = 0.3;
  p.merged_spacing = 0;  // keep every point: compare like with like
  return p;
}

std::map<Label, double> volumes(const SemiOcTree& t) {
  std::map<Label, double> v;
  t.for_each_octant([&](const Octant& o) { v[o.label()] += o.size * o.size * o.size; });
  return v;
}

TEST(Update, SecondScanRefinesTheMapLikeARebuild) {
  const Point3 a(1.0, 3.0, 1.2), b(3.0, 2.0, 1.2);
  SurveyMap map(params());
  const ScanUpdateReport first = map.add_scan(room_scan(false), a, 2.4);
  EXPECT_EQ(first.scan_index, 0u);
  const Point3 behind_pillar(2.6, 0.4, 1.0);  // hidden from a, seen from b
  ASSERT_EQ(map.tree().find_octant(behind_pillar)->label(), Label::kOccluded);
  const std::size_t coarse_before = map.tree().coarse_count();

  const ScanUpdateReport second = map.add_scan(room_scan(true), b, 2.4);
  EXPECT_EQ(second.scan_index, 1u);
  EXPECT_GT(second.new_coarse_voxels, 0u);  // the alcove is new ground
  EXPECT_EQ(map.tree().coarse_count(), coarse_before + second.new_coarse_voxels);
  EXPECT_GT(second.new_space.octants_tested, 0u);
  EXPECT_GT(second.retest.octants_tested, 0u);
  EXPECT_EQ(map.tree().find_octant(behind_pillar)->label(), Label::kEmpty);
  EXPECT_EQ(map.tree().find_octant(Point3(5.0, 2.0, 1.2))->label(), Label::kEmpty);  // alcove
  // Nothing is left unknown, and occupied space is at the leaf only.
  map.tree().for_each_octant([&](const Octant& o) {
    EXPECT_NE(o.label(), Label::kUnknown);
    if (o.label() == Label::kOccupied) {
      EXPECT_EQ(o.level, map.tree().leaf_level());
    }
  });
  EXPECT_EQ(map.scanners().size(), 2u);
  // The map is kept pruned: no eight siblings share one label.
  const std::size_t nodes = map.tree().calcNumNodes();
  map.tree().prune();
  EXPECT_EQ(map.tree().calcNumNodes(), nodes);

  // The same two scans classified from scratch from both positions.
  Cloud both = room_scan(false);
  both += room_scan(true);
  auto rebuilt = discretize(both, 2.4, params().grid);
  label_openings(*rebuilt, detect_openings(both, 2.4, *rebuilt, {a, b}));
  study_occlusion(*rebuilt, map.views());
  const auto got = volumes(map.tree()), want = volumes(*rebuilt);
  double total = 0;
  for (const auto& [l, v] : want) total += v;
  for (Label l : {Label::kEmpty, Label::kOccupied, Label::kOccluded, Label::kOut}) {
    const double g = got.count(l) ? got.at(l) : 0.0, w = want.count(l) ? want.at(l) : 0.0;
    // Sample-based splitting decides slightly differently in the two orders.
    EXPECT_NEAR(g, w, 0.01 * total) << label_name(l);
  }
}

// A 4 × 4 × 2.4 m room whose wall at x = 4 has a door 1 m wide and 2 m high
// (y from 1.5 to 2.5) into a 2 m deep alcove behind it. Without `lintel` the
// wall above the door returned no points (a dark lintel): the gap reaches the
// ceiling and is no door. With `door_panel` the door is shut by a sparse grid
// of points (one every 0.1 m, as a mesh or a dim panel gives): no hole is left.
Cloud door_room_scan(bool lintel, bool door_panel) {
  Cloud c;
  const double step = 0.02;
  for (double z = step; z < 2.4; z += step) {
    for (double t = 0; t <= 4.0; t += step) {
      add(c, t, 0.01, z);
      add(c, t, 3.99, z);
      add(c, 0.01, t, z);
      const bool in_door = t > 1.5 && t < 2.5;
      if (!in_door || (lintel && z >= 2.0)) add(c, 3.99, t, z);
    }
    for (double t = 0; t <= 2.0; t += step) {
      add(c, 4.0 + t, 1.51, z);
      add(c, 4.0 + t, 2.49, z);
      if (t <= 1.0) add(c, 5.99, 1.5 + t, z);
    }
  }
  if (door_panel)
    for (double y = 1.55; y < 2.5; y += 0.1)
      for (double z = 0.05; z < 2.0; z += 0.1) add(c, 3.99, y, z);
  return c;
}

// Door and window octants of the map (m³).
double opening_volume(const SemiOcTree& t) {
  const auto v = volumes(t);
  return (v.count(Label::kDoor) ? v.at(Label::kDoor) : 0.0) +
         (v.count(Label::kWindow) ? v.at(Label::kWindow) : 0.0);
}

const Point3 kInAlcove(5.0, 2.0, 1.0);  // seen only through the door

// A gap taken for a door at the first scan and shut at the second: its labels
// go, and what was seen through it is no longer out.
TEST(Update, AnOpeningNoLongerFoundLosesItsLabels) {
  SurveyMap map(params());
  map.add_scan(door_room_scan(true, false), Point3(1.0, 2.0, 1.2), 2.4);
  ASSERT_EQ(map.openings().size(), 1u);
  ASSERT_EQ(map.openings()[0].kind, OpeningKind::kDoor);
  EXPECT_GT(opening_volume(map.tree()), 0.0);
  ASSERT_EQ(map.tree().find_octant(kInAlcove)->label(), Label::kOut);

  const ScanUpdateReport second =
      map.add_scan(door_room_scan(true, true), Point3(2.0, 3.0, 1.2), 2.4);
  ASSERT_TRUE(map.openings().empty());
  EXPECT_GT(second.opening_octants_dropped, 0u);
  EXPECT_FALSE(second.opening_leaves_added);
  // The map's doors and windows are the openings' (survey.json lists none).
  EXPECT_EQ(opening_volume(map.tree()), 0.0);
  // Seen through the panel's gaps, or hidden by its points: not out.
  EXPECT_NE(map.tree().find_octant(kInAlcove)->label(), Label::kOut);
  map.tree().for_each_octant([&](const Octant& o) { EXPECT_NE(o.label(), Label::kUnknown); });
}

// A door found only at the second scan (the first saw no wall above it): what
// the first scan saw through it is out, as seen from scratch with both scans.
TEST(Update, AnOpeningFoundLaterMakesWhatWasSeenThroughItOut) {
  const Point3 a(1.0, 2.0, 1.2), b(2.0, 3.0, 1.2);
  SurveyMap map(params());
  map.add_scan(door_room_scan(false, false), a, 2.4);
  ASSERT_TRUE(map.openings().empty());
  ASSERT_EQ(map.tree().find_octant(kInAlcove)->label(), Label::kEmpty);

  const ScanUpdateReport second = map.add_scan(door_room_scan(true, false), b, 2.4);
  ASSERT_EQ(map.openings().size(), 1u);
  EXPECT_TRUE(second.opening_leaves_added);
  EXPECT_GT(second.through_openings.out, 0u);
  EXPECT_GT(opening_volume(map.tree()), 0.0);
  EXPECT_EQ(map.tree().find_octant(kInAlcove)->label(), Label::kOut);

  // Classified from scratch with both scans, as much is out.
  Cloud both = door_room_scan(false, false);
  both += door_room_scan(true, false);
  auto rebuilt = discretize(both, 2.4, params().grid);
  label_openings(*rebuilt, detect_openings(both, 2.4, *rebuilt, {a, b}));
  study_occlusion(*rebuilt, map.views());
  const auto got = volumes(map.tree()), want = volumes(*rebuilt);
  ASSERT_GT(want.count(Label::kOut), 0u);
  ASSERT_GT(got.count(Label::kOut), 0u);
  EXPECT_NEAR(got.at(Label::kOut), want.at(Label::kOut), 0.01 * want.at(Label::kOut));
}

TEST(Update, PointsAboveTheFirstCeilingAreLeftOut) {
  SurveyMap map(params());
  // Before the first scan there is no map to look at.
  EXPECT_TRUE(map.empty());
  EXPECT_THROW(map.tree(), std::logic_error);
  EXPECT_THROW(map.merged_cloud(), std::logic_error);
  map.add_scan(room_scan(false), Point3(1.0, 3.0, 1.2), 2.4);
  Cloud high = room_scan(false);
  add(high, 1.0, 1.0, 2.9);  // above the first scan's ceiling
  const ScanUpdateReport rep = map.add_scan(high, Point3(1.0, 1.0, 1.2), 3.0);
  EXPECT_DOUBLE_EQ(map.ceiling_height(), 2.4);
  EXPECT_EQ(rep.new_coarse_voxels, 0u);
  octomap::OcTreeKey k;
  ASSERT_TRUE(map.tree().key_of({1.0, 1.0, 2.9}, k));
  EXPECT_EQ(map.tree().find_coarse(map.tree().coarse_index(k)), nullptr);
}

// Each scan keeps the directions it got returns in, and the study keeps to them: a scan
// that got none (everything nearer than its minimum range, say) sees nothing.
TEST(Update, EachScanKeepsTheDirectionsItGotReturnsIn) {
  const Point3 at(1.0, 3.0, 1.2);
  SurveyMap blind(params());
  const auto none = std::make_shared<const ReturnDirections>();
  blind.add_scan(room_scan(false), at, 2.4, none);
  ASSERT_EQ(blind.views().size(), 1u);
  EXPECT_EQ(blind.views()[0].returns, none);
  SurveyMap seeing(params());
  seeing.add_scan(room_scan(false), at, 2.4);
  EXPECT_EQ(seeing.views()[0].returns, nullptr);
  const std::map<Label, double> b = volumes(blind.tree()), s = volumes(seeing.tree());
  EXPECT_EQ(b.count(Label::kEmpty), 0u);
  EXPECT_GT(s.at(Label::kEmpty), 20.0);  // most of the 4 × 4 × 2.4 m room
  // A second scan with returns everywhere sees the room.
  Cloud c = room_scan(false);
  Cloud from_second;
  const Point3 second(3.0, 3.0, 1.2);
  for (const auto& p : c)
    from_second.push_back(
        pcl::PointXYZ{p.x - float(second.x), p.y - float(second.y), p.z - float(second.z)});
  blind.add_scan(c, second, 2.4, return_directions(from_second, Eigen::Matrix3d::Identity()));
  EXPECT_GT(volumes(blind.tree()).at(Label::kEmpty), 20.0);
  EXPECT_EQ(blind.views()[0].returns, none);
  EXPECT_NE(blind.views()[1].returns, nullptr);
}

// A surface's side is where the map holds free space both a leaf and a half and three
// and a half leaves out: a wall's inside read free just behind its face (lines that
// slipped through a face seen at a grazing angle) leaves the face its side; free space
// at both depths on both sides (a thin board seen from both) leaves it none.
TEST(Update, ASurfaceKeepsTheSideItWasSeenFromWhenItsInsideReadsFreeJustBehindIt) {
  SurveyMap map(params());
  map.add_scan(room_scan(false), Point3(1.0, 3.0, 1.2), 2.4);
  // The pillar's west face (x = 2.0, the room at x < 2), at mid-height.
  const Eigen::Vector3d face(2.0, 1.3, 0.8), east(1.0, 0.0, 0.0);
  ASSERT_EQ(map.seen_side(face, east), -1);
  ASSERT_EQ(map.seen_side(face, -east), 1);
  const double leaf = map.tree().leaf_size();
  auto read_free = [&](double depth) {
    octomap::OcTreeKey k;
    ASSERT_TRUE(map.tree().key_of(Point3(face.x() + depth * leaf, face.y(), face.z()), k));
    map.tree().set_label(k, map.tree().leaf_level(), Label::kEmpty);
  };
  read_free(1.5);  // the inside, just behind the face
  EXPECT_EQ(map.seen_side(face, east), -1);
  read_free(3.5);  // and deeper: free on both sides
  EXPECT_EQ(map.seen_side(face, east), 0);
}

// A real scan's returns from the scanner's mount and the robot's body lie
// closer than the minimum range or below the lowest elevation: not mapped.
TEST(Update, ReturnsOutsideTheScannerLimitsAreDropped) {
  ScannerView v;  // 0.6 to 60 m, -60° to 90°
  const double s60 = std::sin(60 * M_PI / 180), c60 = std::cos(60 * M_PI / 180);
  Cloud::Ptr all(new Cloud);
  Cloud& scan = *all;
  add(scan, 0.05, 0.0, -0.11);        // the mount, 0.12 m away
  add(scan, 0.3, 0.0, -0.8);          // the robot's body, -69°
  add(scan, 3.0, 0.0, -1.2);          // the floor, -22°
  add(scan, 0.0, 2.0, 0.0);           // a wall
  add(scan, 70.0, 0.0, 0.0);          // beyond the maximum range
  add(scan, 2 * c60, 0.0, -2 * s60);  // on the lowest elevation: kept
  add(scan, 0.0, 0.6, 0.0);           // at the minimum range: kept
  std::size_t dropped = 0;
  const Cloud::Ptr kept = within_limits(all, v, &dropped);
  EXPECT_EQ(dropped, 3u);
  ASSERT_EQ(kept->size(), 4u);
  EXPECT_NE(kept, all);  // a new cloud; the scan is left as it was
  EXPECT_EQ(all->size(), 7u);
  EXPECT_FLOAT_EQ((*kept)[0].x, 3.0f);
  EXPECT_FLOAT_EQ((*kept)[1].y, 2.0f);
  // A scan wholly within the limits is returned as it is, not copied.
  EXPECT_EQ(within_limits(kept, v, &dropped), kept);
  EXPECT_EQ(dropped, 0u);
  v.elevation_min_deg = -41;  // a robot whose body reaches -41.4°
  EXPECT_EQ(within_limits(all, v)->size(), 3u);
  // The upper limit as the lower: on it kept, above it dropped. A return with a coordinate
  // not a number is kept (preprocessing skips it).
  v.elevation_max_deg = 30;
  const double s30 = std::sin(30 * M_PI / 180), c30 = std::cos(30 * M_PI / 180);
  Cloud::Ptr up(new Cloud);
  add(*up, 4 * c30, 0.0, 4 * s30);                              // on it
  add(*up, 1.0, 0.0, 1.0);                                      // 45°: above
  add(*up, std::numeric_limits<float>::quiet_NaN(), 0.0, 0.0);  // not a number
  add(*up, 0.0, -5.0, -5.0 * std::tan(40 * M_PI / 180));        // -40°
  const Cloud::Ptr up_kept = within_limits(up, v, &dropped);
  EXPECT_EQ(dropped, 1u);
  ASSERT_EQ(up_kept->size(), 3u);
  EXPECT_FLOAT_EQ((*up_kept)[0].z, float(4 * s30));
  EXPECT_TRUE(std::isnan((*up_kept)[1].x));
  EXPECT_FLOAT_EQ((*up_kept)[2].y, -5.0f);
}

}  // namespace
}  // namespace semioctree
