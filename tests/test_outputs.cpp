// The map files every command writes (outputs.h): the scan and NBV markers go into the
// OctoMap exports, drawn in as they are built; the map and semioctree.ot are the map alone.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "octomap/ColorOcTree.h"
#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/outputs.h"
#include "support/sample_trees.h"
#include "support/scratch.h"

namespace semioctree {
namespace {

Label label_at(const SemiOcTree& t, const Point3& p) {
  const auto o = t.find_octant(p);
  return o ? o->label() : Label::kUnknown;
}

std::string bytes_of(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Outputs, ExportsCarryScanAndNbvMarkersAndTheMapIsUnchanged) {
  const auto tree = testing::sample_tree();
  const auto before = tree->statistics();
  const Point3 scan(0.5, 0.55, 0.55), nbv(1.0, 0.25, 0.55), away(0.7, 0.2, 0.7);
  ASSERT_EQ(label_at(*tree, scan), Label::kEmpty);
  ASSERT_EQ(label_at(*tree, nbv), Label::kEmpty);

  SliceOptions slice;
  slice.height = 0.55;
  slice.scans = {scan};
  slice.nbv = nbv;
  const auto dir = testing::temp_dir("outputs");
  write_map_files(*tree, dir.string(), slice);

  // The map written from is untouched, and semioctree.ot is that map.
  const auto after = tree->statistics();
  EXPECT_EQ(after.count, before.count);
  EXPECT_EQ(label_at(*tree, scan), Label::kEmpty);
  const auto read = read_semioctree_file((dir / "semioctree.ot").string());
  const auto st = read->statistics();
  EXPECT_EQ(st.count, before.count);
  for (int l = 0; l < kLabelCount; ++l) EXPECT_EQ(st.volume[l], before.volume[l]) << l;

  // The exports are those of the map with the markers set as labels: the 3×3×3 cube of
  // leaves around each position, the octants around them split.
  const auto marked = read_semioctree_file((dir / "semioctree.ot").string());
  const double r = marked->leaf_size();
  auto set_cube = [&](const Point3& c, Label label) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          octomap::OcTreeKey key;
          ASSERT_TRUE(marked->key_of(Point3(c.x + dx * r, c.y + dy * r, c.z + dz * r), key));
          marked->set_label(key, marked->leaf_level(), label);
        }
  };
  set_cube(scan, Label::kScan);
  set_cube(nbv, Label::kNbv);
  ASSERT_EQ(marked->statistics().with_label(Label::kScan), 27u + 1u);  // and the sample's own
  const auto want = testing::temp_dir("outputs-want");
  write_tree_file(*to_color_octree(*marked), (want / "labels_color.ot").string());
  write_binary_file(*to_occupancy_octree(*marked), (want / "occupancy.bt").string());
  EXPECT_EQ(bytes_of(dir / "labels_color.ot"), bytes_of(want / "labels_color.ot"));
  EXPECT_EQ(bytes_of(dir / "occupancy.bt"), bytes_of(want / "occupancy.bt"));

  // octovis sees them in the label colours, and the rest as it was; the .bt has them free.
  const TreeFile color = read_tree_file((dir / "labels_color.ot").string());
  auto* ct = dynamic_cast<octomap::ColorOcTree*>(color.tree.get());
  ASSERT_NE(ct, nullptr);
  auto colour_at = [&](const Point3& p) {
    const octomap::ColorOcTreeNode* n = ct->search(p.x, p.y, p.z);
    return n ? n->getColor() : octomap::ColorOcTreeNode::Color();
  };
  auto colour_of = [](Label l) {
    const Rgb c = label_color(l);
    return octomap::ColorOcTreeNode::Color(c.r, c.g, c.b);
  };
  for (int d = -1; d <= 1; ++d) {
    EXPECT_EQ(colour_at(Point3(scan.x + d * r, scan.y - d * r, scan.z + d * r)),
              colour_of(Label::kScan));
    EXPECT_EQ(colour_at(Point3(nbv.x + d * r, nbv.y + d * r, nbv.z - d * r)),
              colour_of(Label::kNbv));
  }
  EXPECT_EQ(colour_at(Point3(scan.x + 2 * r, scan.y, scan.z)), colour_of(Label::kEmpty));
  EXPECT_EQ(colour_at(away), colour_of(label_at(*tree, away)));
  const TreeFile bt = read_tree_file((dir / "occupancy.bt").string());
  auto* ot = dynamic_cast<octomap::OcTree*>(bt.tree.get());
  ASSERT_NE(ot, nullptr);
  const octomap::OcTreeNode* b = ot->search(nbv.x, nbv.y, nbv.z);
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(ot->isNodeOccupied(b));
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(want);
}

TEST(Outputs, NoMarkersWithoutPositions) {
  const auto tree = testing::sample_tree();
  const auto dir = testing::temp_dir("outputs-plain");
  write_map_files(*tree, dir.string(), SliceOptions{});
  const TreeFile color = read_tree_file((dir / "labels_color.ot").string());
  EXPECT_EQ(color.tree->size(), to_color_octree(*tree)->size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace semioctree
