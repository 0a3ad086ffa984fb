// The map files every command writes (outputs.h): the scan and NBV markers go
// into the files, not into the map they are written from.
#include <gtest/gtest.h>

#include <filesystem>

#include "octomap/ColorOcTree.h"
#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/outputs.h"
#include "support/sample_trees.h"

namespace semioctree {
namespace {

Label label_at(const SemiOcTree& t, const Point3& p) {
  const auto o = t.find_octant(p);
  return o ? o->label() : Label::kUnknown;
}

TEST(Outputs, FilesCarryScanAndNbvMarkersAndTheMapIsUnchanged) {
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

  // The map written from is untouched.
  const auto after = tree->statistics();
  EXPECT_EQ(after.count, before.count);
  EXPECT_EQ(label_at(*tree, scan), Label::kEmpty);

  const auto read = read_semioctree_file((dir / "semioctree.ot").string());
  const double r = read->leaf_size();
  for (int d = -1; d <= 1; ++d) {  // the 3×3×3 cube of leaves around each position
    EXPECT_EQ(label_at(*read, Point3(scan.x + d * r, scan.y - d * r, scan.z + d * r)),
              Label::kScan);
    EXPECT_EQ(label_at(*read, Point3(nbv.x + d * r, nbv.y + d * r, nbv.z - d * r)), Label::kNbv);
  }
  EXPECT_EQ(label_at(*read, Point3(scan.x + 2 * r, scan.y, scan.z)), Label::kEmpty);
  EXPECT_EQ(label_at(*read, away), label_at(*tree, away));
  const auto st = read->statistics();
  // The sample tree has one scan and one NBV leaf of its own.
  EXPECT_EQ(st.with_label(Label::kScan), 27u + 1u);
  EXPECT_EQ(st.with_label(Label::kNbv), 27u + 1u);
  // Everything else keeps its label: same volume per label, less the markers'.
  const double cube = 27 * r * r * r;
  EXPECT_NEAR(st.volume[int(Label::kEmpty)], before.volume[int(Label::kEmpty)] - 2 * cube, 1e-9);
  EXPECT_NEAR(st.volume[int(Label::kOccupied)], before.volume[int(Label::kOccupied)], 1e-9);

  // octovis sees them in the label colours; the .bt has them free.
  const TreeFile color = read_tree_file((dir / "labels_color.ot").string());
  auto* ct = dynamic_cast<octomap::ColorOcTree*>(color.tree.get());
  ASSERT_NE(ct, nullptr);
  const octomap::ColorOcTreeNode* n = ct->search(scan.x, scan.y, scan.z);
  ASSERT_NE(n, nullptr);
  const auto c = label_color(Label::kScan);
  EXPECT_EQ(n->getColor(), octomap::ColorOcTreeNode::Color(c.r, c.g, c.b));
  const TreeFile bt = read_tree_file((dir / "occupancy.bt").string());
  auto* ot = dynamic_cast<octomap::OcTree*>(bt.tree.get());
  ASSERT_NE(ot, nullptr);
  const octomap::OcTreeNode* b = ot->search(nbv.x, nbv.y, nbv.z);
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(ot->isNodeOccupied(b));
  std::filesystem::remove_all(dir);
}

TEST(Outputs, NoMarkersWithoutPositions) {
  const auto tree = testing::sample_tree();
  const auto dir = testing::temp_dir("outputs-plain");
  write_map_files(*tree, dir.string(), SliceOptions{});
  const auto read = read_semioctree_file((dir / "semioctree.ot").string());
  EXPECT_EQ(read->statistics().count, tree->statistics().count);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace semioctree
