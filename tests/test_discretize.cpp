// Discretization (paper 2.2.1): occupancy analysis into the SemiOcTree, the
// homogeneous grid through the same code, and the slice image.
#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <tuple>

#include "semioctree/discretize.h"
#include "semioctree/preprocess.h"
#include "semioctree/slice_image.h"
#include "support/sample_trees.h"
#include "support/scratch.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

Cloud cube_of_points(double x0, double y0, double z0, double side, double step) {
  Cloud c;
  for (double x = x0 + step / 2; x < x0 + side; x += step)
    for (double y = y0 + step / 2; y < y0 + side; y += step)
      for (double z = z0 + step / 2; z < z0 + side; z += step)
        c.push_back(pcl::PointXYZ{float(x), float(y), float(z)});
  return c;
}

TEST(Discretize, BoxOfPointsGivesTheExpectedOctantsAtEveryLevel) {
  // A solid 0.4 m cube of points filling octant [0, 0.4)³ of coarse voxel
  // (0,0,0) (L = 0.8, r = 0.1, k = 3), plus one point far away to set the bounds.
  Cloud c = cube_of_points(0.0, 0.0, 0.0, 0.4, 0.05);
  c.push_back(pcl::PointXYZ{2.35f, 1.55f, 0.05f});
  DiscretizeReport rep;
  const auto t = discretize(c, 0.8, {0.1, 0.8}, &rep);
  t->prune();  // must not merge occupied leaves
  const auto st = t->statistics();
  // Coarse grid: x 0..2, y 0..1, z 0 → 6 voxels; two of them split.
  EXPECT_EQ(t->coarse_count(), 6u);
  EXPECT_EQ(st.at_level(0), 4u);  // 4 unsplit empty coarse voxels
  EXPECT_EQ(st.count[1][int(Label::kEmpty)],
            7u + 7u);                              // siblings of the cube, and of the far point
  EXPECT_EQ(st.count[2][int(Label::kEmpty)], 7u);  // the far point's level-2 siblings
  EXPECT_EQ(st.count[2][int(Label::kOccupied)], 0u);
  EXPECT_EQ(st.count[3][int(Label::kOccupied)], 64u + 1u);  // 4³ leaves of the cube, 1 far
  EXPECT_EQ(st.count[3][int(Label::kEmpty)], 7u);
  EXPECT_EQ(st.with_label(Label::kOccupied), st.count[3][int(Label::kOccupied)]);
  EXPECT_EQ(rep.occupied_leaves, 65u);
  EXPECT_NEAR(st.total_volume(), 6 * 0.512, 1e-9);
}

TEST(Discretize, PointsOutsideFloorAndCeilingAreIgnored) {
  Cloud c = cube_of_points(0.0, 0.0, 0.0, 0.4, 0.1);
  c.push_back(pcl::PointXYZ{0.1f, 0.1f, -0.5f});
  c.push_back(pcl::PointXYZ{0.1f, 0.1f, 5.0f});
  DiscretizeReport rep;
  discretize(c, 3.0, {0.1, 0.8}, &rep);
  EXPECT_EQ(rep.points_outside, 2u);
  EXPECT_EQ(rep.points_used, 64u);
  EXPECT_EQ(rep.max_coarse.z, 3);  // 3.0 m ceiling: layers [0, 0.8) … [2.4, 3.2)
}

TEST(Discretize, HomogeneousAndSemioctreeAgreeOnOccupiedLeaves) {
  const auto room = testing::synthetic_room(4, 3, 2.5, 0.04, 0.003, 3, 2, 1.5, 1.5);
  Cloud lifted;
  for (const auto& p : *room) lifted.push_back(pcl::PointXYZ{p.x + 2.f, p.y + 1.5f, p.z + 1.5f});
  const auto semi = discretize(lifted, 2.45, {0.1, 0.8});
  const auto homo = discretize(lifted, 2.45, {0.1, 0.1});
  EXPECT_EQ(homo->leaf_level(), 0u);
  auto occupied = [](const SemiOcTree& t) {
    std::set<std::tuple<unsigned, unsigned, unsigned>> s;
    t.for_each_octant([&](const Octant& o) {
      if (o.label() == Label::kOccupied) {
        EXPECT_EQ(o.level, t.leaf_level()) << "occupied above the leaf level";
        s.emplace(o.key.k[0], o.key.k[1], o.key.k[2]);
      }
    });
    return s;
  };
  const auto a = occupied(*semi), b = occupied(*homo);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
  // The semioctree uses far fewer octants for the same occupied space.
  EXPECT_LT(semi->statistics().total() * 2, homo->statistics().total());
  // Coarse voxels snap to the 0.8 m grid, so they cover at least the same volume.
  EXPECT_GE(semi->statistics().total_volume(), homo->statistics().total_volume() - 1e-6);
}

TEST(Discretize, BadParameters) {
  Cloud c = cube_of_points(0, 0, 0, 0.4, 0.1);
  EXPECT_THROW(discretize(c, 3.0, {0.1, 0.7}), std::invalid_argument);
  EXPECT_THROW(discretize(c, 0.0, {0.1, 0.8}), std::invalid_argument);
  Cloud below;
  below.push_back(pcl::PointXYZ{0.f, 0.f, -1.f});
  EXPECT_THROW(discretize(below, 3.0, {0.1, 0.8}), std::invalid_argument);
}

// Reads a PNG into RGB rows.
std::vector<std::vector<Rgb>> read_png(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "rb");
  EXPECT_NE(f, nullptr);
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  const auto w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  EXPECT_EQ(png_get_color_type(png, info), PNG_COLOR_TYPE_RGB);
  png_bytepp rows = png_get_rows(png, info);
  std::vector<std::vector<Rgb>> img(h, std::vector<Rgb>(w));
  for (png_uint_32 y = 0; y < h; ++y)
    for (png_uint_32 x = 0; x < w; ++x)
      img[y][x] = {rows[y][3 * x], rows[y][3 * x + 1], rows[y][3 * x + 2]};
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(f);
  return img;
}

TEST(SliceImage, ShowsEachLabelInItsColourAndTheScanner) {
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  const auto dir = testing::temp_dir("slice");
  SliceOptions o;
  o.height = 0.125;  // through the door leaf, the occluded octants and the wall
  o.pixels_per_leaf = 10;
  o.scans = {Point3(0.6, 0.6, 0.125)};
  o.nbv = Point3(1.0, 0.6, 0.125);
  // A window above the cut is marked all the same: a bar across its wall.
  o.openings = {{false, Point3(0.2, 0.75, 1.0), Point3(0.6, 0.75, 1.0)}};
  write_slice_png(t, (dir / "s.png").string(), o);
  const auto img = read_png((dir / "s.png").string());
  ASSERT_FALSE(img.empty());
  // Points are octant centres, away from the outlines.
  // Map: 3 × 2 coarse voxels of 8 leaves, 10 px per leaf → 240 × 160 px at (56, 36)
  // (left of it the y axis's labels).
  auto at = [&](double x, double y) {
    return img[std::size_t(36 + 160 - int(y / 0.05 * 10))][std::size_t(56 + int(x / 0.05 * 10))];
  };
  auto same = [](Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; };
  EXPECT_TRUE(same(at(0.025, 0.325), label_color(Label::kOccupied)));  // inside a wall leaf
  EXPECT_TRUE(same(at(0.5, 0.1), label_color(Label::kOccluded)));
  const Rgb door = at(1.125, 0.125);
  EXPECT_TRUE(same(door, label_color(Label::kDoor)))
      << int(door.r) << "," << int(door.g) << "," << int(door.b);
  EXPECT_TRUE(same(at(0.9, 0.5), label_color(Label::kEmpty)));
  EXPECT_TRUE(same(at(0.6, 0.6), label_color(Label::kScan)));      // scanner disc
  EXPECT_TRUE(same(at(1.0, 0.6), label_color(Label::kNbv)));       // NBV disc
  EXPECT_TRUE(same(at(0.4, 0.75), label_color(Label::kWindow)));   // the window's bar
  EXPECT_FALSE(same(at(0.4, 0.65), label_color(Label::kWindow)));  // and only there
  EXPECT_THROW(write_slice_png(SemiOcTree(0.05, 0.4), (dir / "e.png").string(), o),
               std::invalid_argument);

  // A route drawn instead of the straight line between scans, and a room's outline.
  o.scans = {Point3(0.3, 0.3, 0.125), Point3(0.9, 0.6, 0.125)};
  o.nbv.reset();
  o.routes = {{Point3(0.3, 0.3, 0), Point3(0.3, 0.6, 0), Point3(0.9, 0.6, 0)}};
  o.rooms = {{{{0.2f, 0.2f, 1.0f, 0.2f}}, Point3(1.0, 0.75, 0), "R0"}};
  write_slice_png(t, (dir / "r.png").string(), o);
  const auto routed = read_png((dir / "r.png").string());
  ASSERT_FALSE(routed.empty());
  auto at_r = [&](double x, double y) {
    return routed[std::size_t(36 + 160 - int(y / 0.05 * 10))][std::size_t(56 + int(x / 0.05 * 10))];
  };
  // Drawn over the map (lines 1.5 px wide, antialiased: not pure black) where the route
  // runs, and nothing drawn on the straight line between the scans. (Points a hair off
  // a pixel boundary: 0.6 / 0.05 * 10 rounds down to the pixel row past the line.)
  EXPECT_FALSE(same(at_r(0.3, 0.45), at(0.3, 0.45)));          // on the route's first leg
  EXPECT_FALSE(same(at_r(0.775, 0.6025), at(0.775, 0.6025)));  // on its second
  EXPECT_TRUE(same(at_r(0.6, 0.45), at(0.6, 0.45)));           // the straight line's middle
  EXPECT_TRUE(same(at_r(0.8, 0.2), slice_room_color()));
}

}  // namespace
}  // namespace semioctree

namespace semioctree {
namespace {

TEST(Discretize, RealScanGivesAPlausibleMapAndSlice) {
  const auto scans = read_scans(std::string(SEMIOCTREE_SOURCE_DIR) + "/tests/data/room_scan1.pcd");
  const PreprocessResult pre = preprocess(*scans[0].points);
  const auto t = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.8});
  const auto st = t->statistics();
  // One occupied leaf per 5 cm cell holding a point between floor and ceiling, counted
  // here without the tree; occupied octants are leaves.
  std::set<std::tuple<long, long, long>> cells;
  for (const auto& p : *pre.cloud)
    if (p.z >= 0 && p.z < pre.ceiling_height)
      cells.emplace(long(std::floor(p.x / 0.05)), long(std::floor(p.y / 0.05)),
                    long(std::floor(p.z / 0.05)));
  EXPECT_EQ(st.with_label(Label::kOccupied), cells.size());
  EXPECT_EQ(st.with_label(Label::kOccupied), st.count[4][int(Label::kOccupied)]);
  EXPECT_GT(st.with_label(Label::kEmpty), 1000u);
  const auto dir = testing::temp_dir("real-slice");
  SliceOptions o;
  o.height = (pre.transform * Eigen::Vector3d::Zero()).z();  // scanner height
  o.scans = {Point3(0, 0, o.height)};
  write_slice_png(*t, (dir / "slice.png").string(), o);
  const auto img = read_png((dir / "slice.png").string());
  std::size_t occupied_px = 0;
  for (const auto& row : img)
    for (const Rgb& c : row) {
      const Rgb occ = label_color(Label::kOccupied);
      occupied_px += c.r == occ.r && c.g == occ.g && c.b == occ.b;
    }
  EXPECT_GT(occupied_px, 500u) << "walls visible in the slice";
}

}  // namespace
}  // namespace semioctree
