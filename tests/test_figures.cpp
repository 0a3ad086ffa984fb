// The paper's figures (figures.h): Table 1's volume shares, Table 2's increment
// factors and openings.json, against values worked out by hand.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "semioctree/figures.h"
#include "support/sample_trees.h"
#include "support/scratch.h"

namespace semioctree {
namespace {

TEST(Figures, VolumeSharesOfTheSampleTreeByHand) {
  // sample_tree: 12 coarse voxels of 0.4 m (0.768 m³). A wall of 16 × 16 occupied
  // leaves; occluded octants of 0.2 and 0.1 m; a door and a window leaf; one coarse
  // voxel out, less the 0.2 m unknown octant inside it; a scan and an NBV leaf.
  const auto tree = testing::sample_tree();
  const OctantStatistics s = tree->statistics();
  const double leaf = 0.05 * 0.05 * 0.05;
  const double occupied = 256 * leaf, occluded = 0.008 + 0.001, out = 0.064 - 0.008;
  const double door = leaf, window = leaf;
  // Table 1 leaves unknown space and the scan/NBV markers out of the whole.
  const double whole = 0.768 - 0.008 - 2 * leaf;
  const double empty = whole - occupied - occluded - out - door - window;
  EXPECT_NEAR(volume_percent(s, Label::kOccupied), 100 * occupied / whole, 1e-9);
  EXPECT_NEAR(volume_percent(s, Label::kOccluded), 100 * occluded / whole, 1e-9);
  EXPECT_NEAR(volume_percent(s, Label::kOut), 100 * out / whole, 1e-9);
  EXPECT_NEAR(volume_percent(s, Label::kDoor), 100 * door / whole, 1e-9);
  EXPECT_NEAR(volume_percent(s, Label::kWindow), 100 * window / whole, 1e-9);
  EXPECT_NEAR(volume_percent(s, Label::kEmpty), 100 * empty / whole, 1e-9);
  EXPECT_EQ(volume_percent(OctantStatistics{}, Label::kEmpty), 0.0);
}

TEST(Figures, IncrementFactorIsTheRatioOfSuccessiveCounts) {
  // Three runs at 0.4, 0.2, 0.1 m with 10, 45 and 300 octants.
  std::vector<DiscretizationRun> runs(3);
  const std::uint64_t counts[3] = {10, 45, 300};
  for (int i = 0; i < 3; ++i) {
    runs[i].leaf = 0.4 / (1 << i);
    runs[i].stats.count.assign(2, {});  // two levels
    runs[i].stats.count[0][std::size_t(Label::kEmpty)] = counts[i] - 1;
    runs[i].stats.count[1][std::size_t(Label::kOccupied)] = 1;
  }
  ASSERT_EQ(runs[2].stats.total(), 300u);
  const std::vector<double> f = increment_factors(runs);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_DOUBLE_EQ(f[0], 4.5);
  EXPECT_DOUBLE_EQ(f[1], 300.0 / 45.0);
  EXPECT_TRUE(increment_factors({runs[0]}).empty());
}

TEST(Figures, OpeningsJsonHoldsEveryOpeningAsDetected) {
  DetectedOpening door;
  door.kind = OpeningKind::kDoor;
  door.corners = {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(2, 0, 2.1),
                  Eigen::Vector3d(1, 0, 2.1)};
  door.width = 1.0;
  door.height = 2.1;
  door.los_fraction = 0.9;
  DetectedOpening window = door;
  window.kind = OpeningKind::kWindow;
  window.corners = {Eigen::Vector3d(4, 0.5, 0.9), Eigen::Vector3d(4, 2, 0.9),
                    Eigen::Vector3d(4, 2, 2.3), Eigen::Vector3d(4, 0.5, 2.3)};
  window.width = 1.5;
  window.height = 1.4;
  window.sill = 0.9;
  window.los_fraction = 0.5;
  const auto dir = testing::temp_dir("figures-openings");
  const std::string path = (dir / "openings.json").string();
  write_openings_json({door, window}, path);
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "semioctree-openings");
  EXPECT_EQ(j["version"], 1);
  ASSERT_EQ(j["openings"].size(), 2u);
  const DetectedOpening* expected[2] = {&door, &window};
  for (int i = 0; i < 2; ++i) {
    const nlohmann::json& o = j["openings"][i];
    const DetectedOpening& e = *expected[i];
    EXPECT_EQ(o["kind"], i == 0 ? "door" : "window");
    EXPECT_DOUBLE_EQ(o["width"].get<double>(), e.width);
    EXPECT_DOUBLE_EQ(o["height"].get<double>(), e.height);
    EXPECT_DOUBLE_EQ(o["sill"].get<double>(), e.sill);
    EXPECT_DOUBLE_EQ(o["los_fraction"].get<double>(), e.los_fraction);
    ASSERT_EQ(o["corners"].size(), 4u);
    for (int c = 0; c < 4; ++c)
      for (int a = 0; a < 3; ++a)
        EXPECT_DOUBLE_EQ(o["corners"][c][a].get<double>(), e.corners[c][a]);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace semioctree
