// The `semioctree` command line: --help, --version, info and export, and clear
// errors with a non-zero exit on bad input.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <pcl/io/pcd_io.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"
#include "support/cli_run.h"
#include "support/sample_trees.h"
#include "support/sanitized.h"
#include "support/scratch.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

using testing::CliRun;
using testing::run_cli;

namespace fs = std::filesystem;

TEST(Cli, VersionAndHelp) {
  const CliRun v = run_cli("--version");
  EXPECT_EQ(v.exit_code, 0);
  EXPECT_NE(v.all().find(SEMIOCTREE_VERSION), std::string::npos) << v.all();
  const CliRun h = run_cli("--help");
  EXPECT_EQ(h.exit_code, 0);
  for (const char* sub : {"info", "export"})
    EXPECT_NE(h.all().find(sub), std::string::npos) << h.all();
  const CliRun eh = run_cli("export --help");
  EXPECT_EQ(eh.exit_code, 0);
  for (const char* opt : {"--color", "--bt", "--ply"})
    EXPECT_NE(eh.all().find(opt), std::string::npos) << eh.all();
  const CliRun none = run_cli("");
  EXPECT_NE(none.exit_code, 0);
  const CliRun unknown = run_cli("frobnicate");
  EXPECT_NE(unknown.exit_code, 0);
}

TEST(Cli, InfoDescribesASemiOcTree) {
  const auto dir = testing::temp_dir("cli-info");
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  const fs::path ot = dir / "map.ot";
  write_tree_file(t, ot.string());
  const CliRun r = run_cli("info " + ot.string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  EXPECT_NE(r.all().find("SemiOcTree"), std::string::npos) << r.all();
  EXPECT_NE(r.all().find("leaf size:      0.05"), std::string::npos) << r.all();
  EXPECT_NE(r.all().find("coarse size:    0.4"), std::string::npos) << r.all();
  EXPECT_NE(r.all().find("octants:        " + std::to_string(t.statistics().total())),
            std::string::npos)
      << r.all();
  for (const char* label : {"occupied", "occluded", "door", "window", "out"})
    EXPECT_NE(r.all().find(label), std::string::npos) << label;
  EXPECT_NE(r.all().find("memory:"), std::string::npos);
}

TEST(Cli, ExportWritesFilesThatReadBack) {
  const auto dir = testing::temp_dir("cli-export");
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  const fs::path ot = dir / "map.ot";
  write_tree_file(t, ot.string());
  const CliRun r =
      run_cli("export " + ot.string() + " --color " + (dir / "c.ot").string() + " --bt " +
              (dir / "o.bt").string() + " --ply " + (dir / "p.ply").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  // The files hold what the library's exports of the same tree hold.
  const TreeFile color = read_tree_file((dir / "c.ot").string());
  EXPECT_EQ(color.type, "ColorOcTree");
  EXPECT_EQ(color.tree->size(), to_color_octree(t)->size());
  const TreeFile bt = read_tree_file((dir / "o.bt").string());
  EXPECT_TRUE(bt.binary);
  EXPECT_EQ(bt.tree->size(), to_occupancy_octree(t)->size());
  std::size_t labelled = 0;  // the PLY: one vertex per octant that is not unknown
  t.for_each_octant([&](const Octant& o) { labelled += o.label() != Label::kUnknown; });
  std::ifstream ply(dir / "p.ply", std::ios::binary);
  std::string line, header;
  while (std::getline(ply, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex " + std::to_string(labelled) + "\n"), std::string::npos)
      << header;
  const CliRun info = run_cli("info " + (dir / "o.bt").string());
  EXPECT_EQ(info.exit_code, 0) << info.all();
  EXPECT_NE(info.all().find("binary .bt"), std::string::npos) << info.all();
}

TEST(Cli, BadInputGivesAClearErrorAndNonZeroExit) {
  const auto dir = testing::temp_dir("cli-bad");
  const CliRun missing = run_cli("info " + (dir / "nope.ot").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.all().find("semioctree: error:"), std::string::npos) << missing.all();
  EXPECT_NE(missing.all().find("nope.ot"), std::string::npos) << missing.all();

  std::ofstream(dir / "junk.ot")
      << "# Octomap OcTree file\nid SemiOcTree\nsize 99\nres 0.05\ndata\nxx";
  const CliRun junk = run_cli("info " + (dir / "junk.ot").string());
  EXPECT_EQ(junk.exit_code, 1);
  EXPECT_NE(junk.all().find("junk.ot"), std::string::npos) << junk.all();

  // export needs a SemiOcTree and at least one output.
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  write_tree_file(t, (dir / "map.ot").string());
  const CliRun nothing = run_cli("export " + (dir / "map.ot").string());
  EXPECT_NE(nothing.exit_code, 0);
  EXPECT_NE(nothing.all().find("--color"), std::string::npos) << nothing.all();
  write_binary_file(*std::make_unique<octomap::OcTree>(0.1), (dir / "empty.bt").string());
  const CliRun wrong =
      run_cli("export " + (dir / "empty.bt").string() + " --ply " + (dir / "x.ply").string());
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_NE(wrong.all().find("not a SemiOcTree"), std::string::npos) << wrong.all();
}

TEST(Cli, DiscretizeWritesEveryFile) {
  const auto dir = testing::temp_dir("cli-disc");
  pcl::io::savePCDFileBinary((dir / "room.pcd").string(),
                             *testing::synthetic_room(6, 4, 2.8, 0.04));
  const CliRun r =
      run_cli("discretize --cloud " + (dir / "room.pcd").string() +
              " --pose 3,2,1.5,0 --leaf 0.1 --coarse 0.8 --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  for (const char* f :
       {"semioctree.ot", "labels_color.ot", "occupancy.bt", "slice.png", "stats.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  EXPECT_NE(r.all().find("preprocess:"), std::string::npos) << r.all();
  const auto tree = read_semioctree_file((dir / "out" / "semioctree.ot").string());
  EXPECT_EQ(tree->leaf_level(), 3u);
  std::ifstream js(dir / "out" / "stats.json");
  const auto j = nlohmann::json::parse(js);
  // The file is the map of stats.json; the scan marker (3×3×3 leaves around the scanner)
  // is in the octovis export only.
  const auto st = tree->statistics();
  EXPECT_EQ(st.total(), j["octants"].get<std::uint64_t>());
  EXPECT_EQ(st.with_label(Label::kScan), 0u);
  const TreeFile color = read_tree_file((dir / "out" / "labels_color.ot").string());
  const auto* ct = dynamic_cast<const octomap::ColorOcTree*>(color.tree.get());
  ASSERT_NE(ct, nullptr);
  const octomap::ColorOcTreeNode* at_scanner = ct->search(3.0, 2.0, 1.5);
  ASSERT_NE(at_scanner, nullptr);
  const Rgb scan_colour = label_color(Label::kScan);
  EXPECT_EQ(at_scanner->getColor(),
            octomap::ColorOcTreeNode::Color(scan_colour.r, scan_colour.g, scan_colour.b));
  EXPECT_GT(j["volume_percent"]["occupied"].get<double>(), 0.0);
  // A bad coarse size is refused before anything is read.
  const CliRun bad = run_cli("discretize --cloud " + (dir / "room.pcd").string() +
                             " --leaf 0.1 --coarse 0.7 --out " + (dir / "x").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.all().find("power of two"), std::string::npos) << bad.all();
  const CliRun missing = run_cli("discretize --cloud " + (dir / "nope.pcd").string() + " --out x");
  EXPECT_NE(missing.exit_code, 0);
}

// `classify` drops the returns outside the scanner's limits (a real scanner's
// mount and robot) before mapping them, as `survey` and `nbv` do; so do
// `discretize` and `compare`.
TEST(Cli, MappingCommandsDropReturnsOutsideTheScannerLimits) {
  const auto dir = testing::temp_dir("cli-classify");
  Cloud::Ptr room = testing::synthetic_room(6, 4, 2.8, 0.04);
  for (int i = 0; i < 400; ++i) {  // a mount: a disc 0.1 m under the optical centre
    const double a = 0.0157 * i, r = 0.05 + 0.1 * (i % 7) / 7.0;
    room->push_back(pcl::PointXYZ{float(r * std::cos(a)), float(r * std::sin(a)), -0.1f});
  }
  std::size_t outside = 0;  // closer than 0.6 m or below −60° (the default limits)
  for (const auto& p : *room) {
    const double range = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    outside += range < 0.6 || double(p.z) < -std::sin(60 * M_PI / 180) * range;
  }
  ASSERT_GT(outside, 400u);
  pcl::io::savePCDFileBinary((dir / "room.pcd").string(), *room);
  for (const std::string grid :
       {"classify --leaf 0.1 --coarse 0.8", "discretize --leaf 0.1 --coarse 0.8",
        "compare --leaves 0.1 --coarse 0.8"}) {
    const CliRun r = run_cli(grid + " --cloud " + (dir / "room.pcd").string() +
                             " --pose 3,2,1.5,0 --out " + (dir / "out").string());
    ASSERT_EQ(r.exit_code, 0) << grid << "\n" << r.all();
    EXPECT_NE(r.all().find(std::to_string(outside) + " outside the scanner's limits dropped"),
              std::string::npos)
        << grid << ": " << outside << "\n"
        << r.all();
  }
}

// map-nbv: the NBV for a map made with OctoMap's own insertPointCloud (a .bt), or for
// one of our .ot files; clear errors for a map it cannot use.
TEST(Cli, MapNbvTakesAnOctomapMapOrASemioctree) {
  const auto dir = testing::temp_dir("cli-map-nbv");
  // The 8 × 6 × 3 m room with a table, scanned from (3, 2.5, 1.5), floor at z = 0.
  const Cloud::Ptr room = testing::synthetic_room(8, 6, 3, 0.05);
  octomap::Pointcloud scan;
  for (const auto& p : *room) scan.push_back(p.x + 3.0f, p.y + 2.5f, p.z + 1.5f);
  octomap::OcTree map(0.05);
  map.insertPointCloud(scan, octomap::point3d(3.0f, 2.5f, 1.5f));
  const std::string bt = (dir / "room.bt").string();
  ASSERT_TRUE(map.writeBinary(bt));

  const CliRun r =
      run_cli("map-nbv --map " + bt + " --scanner 3,2.5,1.5 --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  // The map was made by casting the scan's rays: it tells where they got returns.
  EXPECT_NE(r.all().find("from the rays the map carved: 1 of 1 scanner"), std::string::npos)
      << r.all();
  std::ifstream in(dir / "out" / "nbv.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "semioctree-map-nbv");
  EXPECT_DOUBLE_EQ(j["leaf"].get<double>(), 0.05);
  EXPECT_GT(j["candidates"].get<int>(), 10);
  ASSERT_FALSE(j["nbv"].is_null()) << r.all();
  // Under the table (x 5–6.6, y 1–1.8 above the floor) is hidden from the scanner.
  EXPECT_GT(j["octants"]["by_label"]["occluded"].get<int>(), 0);
  EXPECT_GT(j["stop_percent"].get<double>(), 0.0);
  EXPECT_EQ(j["openings"], 0) << r.all();  // looked for (a ceiling at 3 m), none in this room
  const double nx = j["nbv"]["x"], ny = j["nbv"]["y"];
  EXPECT_TRUE(nx > 0.5 && nx < 7.5 && ny > 0.5 && ny < 5.5) << nx << ", " << ny;
  EXPECT_DOUBLE_EQ(j["nbv"]["z"].get<double>(), 1.5);
  const auto tree = read_semioctree_file((dir / "out" / "semioctree.ot").string());
  EXPECT_DOUBLE_EQ(tree->leaf_size(), 0.05);
  EXPECT_EQ(tree->find_octant(Point3(3.0, 5.975, 1.5))->label(), Label::kOccupied);  // a wall
  for (const char* f : {"labels_color.ot", "occupancy.bt", "slice.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;

  // Our own .ot is taken as it is: the same NBV. (Sanitized, the reader's tests and its
  // fuzz target stand for this second run of the whole command.)
  if (!testing::sanitized()) {
    const CliRun again = run_cli("map-nbv --map " + (dir / "out" / "semioctree.ot").string() +
                                 " --scanner 3,2.5,1.5 --out " + (dir / "again").string());
    ASSERT_EQ(again.exit_code, 0) << again.all();
    std::ifstream in2(dir / "again" / "nbv.json");
    const auto k = nlohmann::json::parse(in2);
    ASSERT_FALSE(k["nbv"].is_null());
    EXPECT_DOUBLE_EQ(k["nbv"]["x"].get<double>(), nx);
    EXPECT_DOUBLE_EQ(k["nbv"]["y"].get<double>(), ny);
  }

  // A map of the points alone holds no free space: no directions, and it says so.
  octomap::OcTree points_only(0.05);
  for (const auto& p : scan) points_only.updateNode(p, true);
  const std::string pbt = (dir / "points.bt").string();
  ASSERT_TRUE(points_only.writeBinary(pbt));
  const CliRun p =
      run_cli("map-nbv --map " + pbt +
              " --scanner 3,2.5,1.5 --unobserved occluded --candidate-spacing 1 --out " +
              (dir / "points").string());
  EXPECT_EQ(p.exit_code, 0) << p.all();
  EXPECT_NE(p.all().find("does not hold its position as free space"), std::string::npos) << p.all();
  EXPECT_NE(p.all().find("from the rays the map carved: 0 of 1 scanner"), std::string::npos)
      << p.all();

  // Errors name what is wrong.
  const CliRun coarse = run_cli("map-nbv --map " + bt + " --scanner 3,2.5,1.5 --coarse 0.7 --out " +
                                (dir / "x").string());
  EXPECT_EQ(coarse.exit_code, 1);
  EXPECT_NE(coarse.all().find("--coarse"), std::string::npos) << coarse.all();
  const CliRun outside =
      run_cli("map-nbv --map " + bt + " --scanner 30,2.5,1.5 --out " + (dir / "x").string());
  EXPECT_EQ(outside.exit_code, 1);
  EXPECT_NE(outside.all().find("outside the map"), std::string::npos) << outside.all();
  const CliRun floor =
      run_cli("map-nbv --map " + bt + " --scanner 3,2.5,0 --out " + (dir / "x").string());
  EXPECT_EQ(floor.exit_code, 1);
  EXPECT_NE(floor.all().find("--scanner-height"), std::string::npos) << floor.all();
  const CliRun color = run_cli("map-nbv --map " + (dir / "out" / "labels_color.ot").string() +
                               " --scanner 3,2.5,1.5 --out " + (dir / "x").string());
  EXPECT_EQ(color.exit_code, 1);
  EXPECT_NE(color.all().find("holds no occupancy"), std::string::npos) << color.all();
}

// map-nbv finds the doors and the window of the lab in an OctoMap map made from
// the start (the simulated scan, inserted with OctoMap's insertPointCloud), and
// the free space seen through them is out of the room.
TEST(Cli, MapNbvFindsDoorsAndWindowsInAnOctomapMap) {
  // Sanitized, MapNbvOnUserMaps' rooms take map-nbv through the same code.
  if (semioctree::testing::sanitized()) GTEST_SKIP() << "skipped when sanitized (minutes there)";
  const auto dir = testing::temp_dir("cli-map-nbv-lab");
  const std::string pcd = (dir / "scan.pcd").string();
  const CliRun scan = run_cli("scan --scene " + std::string(SEMIOCTREE_SOURCE_DIR) +
                              "/sim/scenes/lab.scene.json --at 5.2,3.6 --azimuth-step 0.2 "
                              "--elevation-step 0.2 --out " +
                              pcd);
  ASSERT_EQ(scan.exit_code, 0) << scan.all();
  pcl::PointCloud<pcl::PointXYZ> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(pcd, cloud), 0);
  const Eigen::Vector3f origin = cloud.sensor_origin_.head<3>();
  ASSERT_NEAR(origin.x(), 5.2f, 1e-5f);
  octomap::Pointcloud points;
  for (const auto& p : cloud) {
    const Eigen::Vector3f w = cloud.sensor_orientation_ * p.getVector3fMap() + origin;
    points.push_back(w.x(), w.y(), w.z());
  }
  octomap::OcTree map(0.05);
  map.insertPointCloud(points, octomap::point3d(origin.x(), origin.y(), origin.z()), -1.0, false,
                       true);
  const std::string bt = (dir / "lab.bt").string();
  ASSERT_TRUE(map.writeBinary(bt));

  const CliRun r =
      run_cli("map-nbv --map " + bt + " --scanner 5.2,3.6,1.5 --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  std::ifstream in(dir / "out" / "nbv.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["openings"], 4) << r.all();  // three doors and the window
  std::ifstream oin(dir / "out" / "openings.json");
  const auto openings = nlohmann::json::parse(oin);
  ASSERT_TRUE(openings.contains("openings")) << openings.dump();
  int doors = 0, windows = 0;
  for (const auto& op : openings["openings"]) (op["kind"] == "door" ? doors : windows)++;
  EXPECT_EQ(doors, 3);
  EXPECT_EQ(windows, 1);
  const auto tree = read_semioctree_file((dir / "out" / "semioctree.ot").string());
  // Room A behind door 2 (y 2.5–3.4 on the wall x = 10.5), in view through it
  // from the start: the OctoMap map holds it as free, and it is out of the room now.
  const Point3 room_a(11.5, 2.85, 1.2);
  EXPECT_EQ(tree->find_octant(room_a)->label(), Label::kOut) << r.all();
  // The room itself stays empty.
  EXPECT_EQ(tree->find_octant(Point3(5.2, 5.0, 1.5))->label(), Label::kEmpty);
  EXPECT_GT(j["volume_percent"]["out"].get<double>(), 0.0);

  // Without the doors and windows (the old behaviour), the corridor counts as the room.
  const CliRun plain = run_cli("map-nbv --map " + bt + " --scanner 5.2,3.6,1.5 --no-openings " +
                               "--out " + (dir / "plain").string());
  ASSERT_EQ(plain.exit_code, 0) << plain.all();
  std::ifstream pin(dir / "plain" / "nbv.json");
  EXPECT_TRUE(nlohmann::json::parse(pin)["openings"].is_null());
  const auto plain_tree = read_semioctree_file((dir / "plain" / "semioctree.ot").string());
  EXPECT_EQ(plain_tree->find_octant(room_a)->label(), Label::kEmpty);
  EXPECT_FALSE(fs::exists(dir / "plain" / "openings.json"));
}

TEST(Cli, CompareWritesTablesAndChart) {
  const auto dir = testing::temp_dir("cli-cmp");
  pcl::io::savePCDFileBinary((dir / "room.pcd").string(),
                             *testing::synthetic_room(6, 4, 2.8, 0.04));
  const CliRun r = run_cli("compare --cloud " + (dir / "room.pcd").string() +
                           " --leaves 0.4,0.2,0.1 --out " + (dir / "cmp").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  for (const char* f :
       {"comparison.json", "comparison.md", "fig15_octants.png", "fig15_octants.svg",
        "slice_semioctree_0.1.png", "slice_homogeneous_0.1.png"})
    EXPECT_TRUE(fs::exists(dir / "cmp" / f)) << f;
  // The images decode: PNG signature and a non-empty IHDR.
  for (const char* f : {"fig15_octants.png", "slice_semioctree_0.1.png"}) {
    std::ifstream png(dir / "cmp" / f, std::ios::binary);
    unsigned char head[24] = {};
    png.read(reinterpret_cast<char*>(head), sizeof head);
    EXPECT_EQ(std::string(reinterpret_cast<char*>(head + 1), 3), "PNG") << f;
    const auto be32 = [&](int at) {
      return (unsigned(head[at]) << 24) | (unsigned(head[at + 1]) << 16) |
             (unsigned(head[at + 2]) << 8) | unsigned(head[at + 3]);
    };
    EXPECT_GT(be32(16), 100u) << f;  // width
    EXPECT_GT(be32(20), 100u) << f;  // height
  }
  // Fig 15 also as SVG: a complete document with the two curves, axes and text drawn.
  const std::string svg = testing::slurp((dir / "cmp" / "fig15_octants.svg").string());
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  std::size_t paths = 0;
  for (std::size_t p = svg.find("<path"); p != std::string::npos; p = svg.find("<path", p + 1))
    ++paths;
  EXPECT_GT(paths, 20u);
  std::ifstream js(dir / "cmp" / "comparison.json");
  const auto j = nlohmann::json::parse(js);
  // Homogeneous over the same region at every resolution: each halving is ×8.
  for (double f : j["table2"]["homogeneous"]["factors"]) EXPECT_DOUBLE_EQ(f, 8.0);
  // The semioctree refines only near surfaces: each halving multiplies its octants by
  // less than the homogeneous grid's 8 (surfaces scale by ~4).
  for (double f : j["table2"]["semioctree"]["factors"]) {
    EXPECT_LT(f, 8.0);
    EXPECT_GT(f, 1.0);
  }
  EXPECT_LT(j["table2"]["semioctree"]["average"].get<double>(), 6.0);
  // Table 1: both methods at each of the three leaves, the six classes' volumes adding
  // up to the whole.
  ASSERT_EQ(j["table1"].size(), 6u);
  std::map<std::string, std::set<double>> leaves;
  for (const auto& row : j["table1"]) {
    leaves[row["method"].get<std::string>()].insert(row["leaf"].get<double>());
    double sum = 0;
    for (const auto& v : row["volume_percent"]) sum += v.get<double>();
    EXPECT_NEAR(sum, 100.0, 1e-6) << row.dump();
  }
  const std::set<double> expected{0.4, 0.2, 0.1};
  EXPECT_EQ(leaves["semioctree"], expected);
  EXPECT_EQ(leaves["homogeneous"], expected);
  std::ifstream md(dir / "cmp" / "comparison.md");
  std::stringstream mds;
  mds << md.rdbuf();
  EXPECT_NE(mds.str().find("Table 2"), std::string::npos);
}

}  // namespace
}  // namespace semioctree
