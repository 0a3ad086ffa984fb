// An OctoMap occupancy map as a SemiOcTree (import.h): labels cell by cell against the
// map, pruned free and occupied nodes, the coarse grid over the map's extent, bad sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/octomap_ext/import.h"
#include "support/sample_trees.h"

namespace semioctree {
namespace {

// What the occupancy export keeps of a label, and what the import makes of it.
Label through_occupancy(Label l, Label unobserved) {
  switch (l) {
    case Label::kOccupied:
      return Label::kOccupied;
    case Label::kOccluded:
    case Label::kUnknown:
      return unobserved;
    default:
      return Label::kEmpty;  // empty, door, window, out, scan, nbv: free in the .bt
  }
}

TEST(Import, SampleTreeThroughItsOccupancyMapKeepsEveryCell) {
  const auto original = testing::sample_tree();  // 3 × 2 × 2 coarse voxels of 0.4 m
  const auto map = to_occupancy_octree(*original);
  for (Label unobserved : {Label::kUnknown, Label::kOccluded}) {
    OccupancyImportReport rep;
    const auto tree = from_occupancy_octree(*map, 0.4, unobserved, &rep);
    EXPECT_EQ(tree->leaf_size(), 0.05);
    EXPECT_EQ(tree->leaf_level(), 3u);
    EXPECT_EQ(tree->coarse_count(), 12u);
    EXPECT_EQ(rep.coarse_voxels, 12u);
    EXPECT_EQ(rep.map_leaves, map->getNumLeafNodes());
    std::size_t cells = 0, occupied = 0;
    for (double x = 0.025; x < 1.2; x += 0.05)
      for (double y = 0.025; y < 0.8; y += 0.05)
        for (double z = 0.025; z < 0.8; z += 0.05, ++cells) {
          const auto was = original->find_octant(Point3(x, y, z));
          const auto now = tree->find_octant(Point3(x, y, z));
          ASSERT_TRUE(was && now) << x << " " << y << " " << z;
          EXPECT_EQ(now->label(), through_occupancy(was->label(), unobserved))
              << x << " " << y << " " << z << " was " << label_name(was->label());
          occupied += now->label() == Label::kOccupied;
        }
    EXPECT_EQ(cells, 24u * 16u * 16u);
    EXPECT_EQ(occupied, 256u);  // the sample tree's wall
    EXPECT_EQ(rep.occupied_leaves, 256u);
    EXPECT_EQ(tree->statistics().with_label(Label::kOccupied), 256u);
  }
}

TEST(Import, PrunedNodesBecomeOctantsOfTheirSizeOrOccupiedLeaves) {
  // A free 1.6 m cube and an occupied 0.4 m cube, both aligned with the 0.4 m grid:
  // OctoMap prunes them into a few big nodes.
  octomap::OcTree map(0.05);
  for (double x = 0.025; x < 1.6; x += 0.05)
    for (double y = 0.025; y < 1.6; y += 0.05)
      for (double z = 0.025; z < 1.6; z += 0.05) map.updateNode(x, y, z, false);
  for (double x = 2.025; x < 2.4; x += 0.05)
    for (double y = 0.025; y < 0.4; y += 0.05)
      for (double z = 0.025; z < 0.4; z += 0.05) map.updateNode(x, y, z, true);
  map.prune();
  ASSERT_LT(map.getNumLeafNodes(), 20u);  // pruned: 1 node for the free cube, 1 occupied
  OccupancyImportReport rep;
  const auto tree = from_occupancy_octree(map, 0.4, Label::kUnknown, &rep);
  // The bounding box, 2.4 × 1.6 × 1.6 m, is 6 × 4 × 4 coarse voxels: 4³ of free space,
  // each one empty octant; 1 of occupied space, 512 leaves; the other 31 unobserved.
  EXPECT_EQ(tree->coarse_count(), 96u);
  EXPECT_EQ(rep.coarse_voxels, 96u);
  const OctantStatistics s = tree->statistics();
  EXPECT_EQ(s.count[0][std::size_t(Label::kEmpty)], 64u);
  EXPECT_EQ(s.with_label(Label::kEmpty), 64u);
  EXPECT_EQ(s.with_label(Label::kOccupied), 512u);
  EXPECT_EQ(s.count[0][std::size_t(Label::kUnknown)], 31u);
  EXPECT_EQ(s.with_label(Label::kUnknown), 31u);
  EXPECT_EQ(tree->find_octant(Point3(2.2, 1.0, 1.0))->label(), Label::kUnknown);
  EXPECT_NEAR(s.volume[std::size_t(Label::kEmpty)], 1.6 * 1.6 * 1.6, 1e-9);
  EXPECT_NEAR(s.volume[std::size_t(Label::kOccupied)], 0.4 * 0.4 * 0.4, 1e-9);
  EXPECT_EQ(rep.occupied_leaves, 512u);
  // A node of the map larger than a coarse voxel labels every voxel it covers.
  EXPECT_EQ(tree->find_octant(Point3(1.5, 1.5, 1.5))->label(), Label::kEmpty);
  EXPECT_EQ(tree->find_octant(Point3(1.5, 1.5, 1.5))->level, 0u);
  EXPECT_EQ(tree->find_octant(Point3(2.3, 0.3, 0.3))->label(), Label::kOccupied);
  EXPECT_FALSE(tree->find_octant(Point3(3.0, 3.0, 3.0)).has_value());  // beyond its extent
}

TEST(Import, CoarseSizeMustBeTheResolutionTimesAPowerOfTwo) {
  octomap::OcTree map(0.05);
  map.updateNode(0.1, 0.1, 0.1, true);
  EXPECT_THROW(from_occupancy_octree(map, 0.7), std::invalid_argument);
  EXPECT_THROW(from_occupancy_octree(map, 0.025), std::invalid_argument);
  // An empty map gives an empty tree.
  EXPECT_EQ(from_occupancy_octree(octomap::OcTree(0.05), 0.8)->coarse_count(), 0u);
}

// A few bytes of map can claim a huge solid or a huge extent: the import counts the
// octants it would make and refuses too many before creating any (found by fuzzing:
// these made map-nbv run for hours).
TEST(Import, RefusesMapsThatWouldMakeMoreOctantsThanAllowed) {
  octomap::OcTree map(0.05);
  map.updateNode(0.1, 0.1, 0.1, true);  // one occupied leaf in one coarse voxel: 2 octants
  EXPECT_EQ(from_occupancy_octree(map, 0.4, Label::kUnknown, nullptr, 2)->coarse_count(), 1u);
  EXPECT_THROW(from_occupancy_octree(map, 0.4, Label::kUnknown, nullptr, 1), std::length_error);

  // A 61-byte .bt: the root and one occupied child, a pruned solid of half the key
  // space per axis (32768³ leaves), more than any machine's memory holds.
  const std::string solid = std::string(
                                "# Octomap OcTree binary file\nid OcTree\nsize 2\nres 0.1\n"
                                "data\n") +
                            std::string("\x02\x00", 2);
  std::istringstream in(solid);
  const TreeFile file = read_tree_stream(in, "solid.bt");
  const auto& occupancy = dynamic_cast<const octomap::OcTree&>(*file.tree);
  try {
    from_occupancy_octree(occupancy, 0.8);
    FAIL() << "imported a 32768³-leaf solid";
  } catch (const std::length_error& e) {
    EXPECT_NE(std::string(e.what()).find("more than the"), std::string::npos) << e.what();
  }

  // Two free nodes 6 km apart on each axis: 7500³ coarse voxels of 0.8 m.
  octomap::OcTree far(0.1);
  far.updateNode(-3000.0, -3000.0, -3000.0, false);
  far.updateNode(3000.0, 3000.0, 3000.0, false);
  EXPECT_THROW(from_occupancy_octree(far, 0.8), std::length_error);
}

// The coarse size nearest 0.8 m: 0.64 for 0.08 m leaves (0.64 and 1.28 are 0.32 and 0.68
// octaves away), 0.8 for 0.1 and 0.05; a tie (0.2·2·√2 m is half an octave from both 0.4
// and 0.8) goes to the larger.
TEST(Import, NearestCoarseSize) {
  EXPECT_DOUBLE_EQ(nearest_coarse_size(0.08, 0.8), 0.64);
  EXPECT_DOUBLE_EQ(nearest_coarse_size(0.1, 0.8), 0.8);
  EXPECT_DOUBLE_EQ(nearest_coarse_size(0.05, 0.8), 0.8);
  EXPECT_DOUBLE_EQ(nearest_coarse_size(0.2, 0.2 * 2 * std::sqrt(2.0)), 0.8);
}

// A floor at z = −0.15 m under a ceiling, with a few specks below it: the floor's layer is
// found (not the specks'), the map moved up by whole leaves keeps every node's value.
TEST(Import, FloorFoundAndMapShiftedByWholeLeaves) {
  octomap::OcTree map(0.08);
  for (double x = 0.04; x < 4; x += 0.08)
    for (double y = 0.04; y < 3; y += 0.08) {
      map.updateNode(x, y, -0.15, true);  // the floor, in the layer [−0.16, −0.08)
      map.updateNode(x, y, 2.6, true);    // the ceiling
      map.updateNode(x, y, 1.0, false);   // free space
    }
  for (double x = 0.04; x < 4; x += 0.8) map.updateNode(x, 1.0, -0.5, true);  // specks below
  const std::optional<OccupancyFloor> f = find_occupancy_floor(map);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->shift_layers, 2);
  EXPECT_NEAR(f->z, -0.16, 1e-12);
  const std::unique_ptr<octomap::OcTree> up = shifted_by_layers(map, f->shift_layers);
  const octomap::OcTreeNode* floor = up->search(2.0, 1.5, -0.15 + 0.16);
  ASSERT_NE(floor, nullptr);
  EXPECT_TRUE(up->isNodeOccupied(floor));
  ASSERT_NE(up->search(2.0, 1.5, 1.16), nullptr);
  EXPECT_FALSE(up->isNodeOccupied(up->search(2.0, 1.5, 1.16)));
  EXPECT_EQ(up->search(2.0, 1.5, -0.15), nullptr);  // nothing left where the floor was
  EXPECT_FALSE(find_occupancy_floor(octomap::OcTree(0.1)));
  // A floor on a layer boundary (z = 0, noise on both sides) is not moved.
  octomap::OcTree level(0.1);
  for (double x = 0.05; x < 3; x += 0.1)
    for (double y = 0.05; y < 3; y += 0.1)
      level.updateNode(x, y, (int(x * 20) % 2) ? 0.01 : -0.01, true);
  ASSERT_TRUE(find_occupancy_floor(level));
  EXPECT_EQ(find_occupancy_floor(level)->shift_layers, 0);
}

}  // namespace
}  // namespace semioctree
