// Bad input through the command line: every row of the table is an input a new
// user could give that once ended in exit 0 with a wrong output, or in a
// message without the cause. Each must now exit non-zero with a message naming
// the file (or option) and the cause. The files are written by the test.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/file_io.h"
#include "support/cli_run.h"
#include "support/sample_trees.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::scratch;

const std::string kScenes = std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/";

std::string write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

std::string pcd_header(int points, const std::string& data,
                       const std::string& viewpoint = "0 0 0 1 0 0 0") {
  const std::string n = std::to_string(points);
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " + n +
         "\nHEIGHT 1\nVIEWPOINT " + viewpoint + "\nPOINTS " + n + "\nDATA " + data + "\n";
}

// `n` lines "x y z" on a 1 m grid in front of the scanner: a readable cloud.
std::string xyz_rows(int n) {
  std::string rows;
  for (int i = 0; i < n; ++i)
    rows += std::to_string(2 + i % 10) + " " + std::to_string(i / 10 % 10) + " " +
            std::to_string(i / 100) + "\n";
  return rows;
}

// One PTX scan of 2 x 1 points whose transformation matrix has `rotation` rows
// (3 lines) and `translation` (1 line).
std::string ptx(const std::string& rotation, const std::string& translation) {
  return "2\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n" + rotation + translation + "\n1 2 3 0.5\n4 5 6 0.5\n";
}
const std::string kIdentityRows = "1 0 0 0\n0 1 0 0\n0 0 1 0\n";

// A PCL-written binary_compressed PCD of a small room.
std::string compressed_pcd(const fs::path& path) {
  fs::create_directories(path.parent_path());
  pcl::io::savePCDFileBinaryCompressed(path.string(), *testing::synthetic_room(6, 4, 2.8, 0.2));
  return path.string();
}

struct Case {
  std::string name;
  // Writes the row's files into `dir` and returns the command's arguments.
  std::function<std::string(const fs::path& dir)> args;
  std::vector<std::string> expect;  // in the error: the file or option, and the cause
};

std::vector<Case> cases() {
  std::vector<Case> c;
  auto discretize = [](const std::string& cloud, const fs::path& dir,
                       const std::string& more = "") {
    return "discretize --cloud " + cloud + " --out " + (dir / "out").string() + more;
  };
  // 1. More data rows than POINTS (PCL drops them silently).
  c.push_back({"pcd-ascii-rows-beyond-points",
               [=](const fs::path& d) {
                 return discretize(
                     write(d / "rows.pcd", pcd_header(2, "ascii") + "1 2 3\n4 5 6\n7 8 9\n"), d);
               },
               {"rows.pcd:14:", "POINTS (2) is less than the file's data rows"}});
  c.push_back({"pcd-binary-rows-beyond-points",
               [=](const fs::path& d) {
                 return discretize(
                     write(d / "rowsb.pcd", pcd_header(2, "binary") + std::string(36, '\1')), d);
               },
               {"rowsb.pcd:", "POINTS is less than the file's data rows", "(3 rows)"}});
  // 2. PTX transforms that are not rigid.
  c.push_back({"ptx-scaled",
               [=](const fs::path& d) {
                 return discretize(
                     write(d / "scaled.ptx", ptx("2 0 0 0\n0 2 0 0\n0 0 2 0\n", "0 0 0 1")), d);
               },
               {"scaled.ptx:7:", "is not rigid", "not orthonormal (axis lengths 2, 2, 2"}});
  c.push_back({"ptx-mirrored",
               [=](const fs::path& d) {
                 return discretize(
                     write(d / "mirror.ptx", ptx("1 0 0 0\n0 1 0 0\n0 0 -1 0\n", "0 0 0 1")), d);
               },
               {"mirror.ptx:7:", "is not rigid", "reflection"}});
  c.push_back({"ptx-projective",
               [=](const fs::path& d) {
                 return discretize(
                     write(d / "proj.ptx", ptx("1 0 0 0.5\n0 1 0 0\n0 0 1 0\n", "0 0 0 1")), d);
               },
               {"proj.ptx:7:", "is not rigid", "projection"}});
  // 7. Poses out of range, wherever they come from.
  c.push_back({"ptx-nan-pose",
               [=](const fs::path& d) {
                 return discretize(write(d / "nan.ptx", ptx(kIdentityRows, "nan 0 0 1")), d);
               },
               {"nan.ptx:7:", "not finite (NaN or Inf)"}});
  c.push_back({"ptx-far-pose",
               [=](const fs::path& d) {
                 return discretize(write(d / "far.ptx", ptx(kIdentityRows, "1e308 0 0 1")), d);
               },
               {"far.ptx:7:", "puts the scanner at (1e+308, 0, 0), beyond ±100000 m"}});
  c.push_back(
      {"pcd-far-viewpoint",
       [=](const fs::path& d) {
         return discretize(
             write(d / "vp.pcd", pcd_header(1200, "ascii", "1e9 0 0 1 0 0 0") + xyz_rows(1200)), d);
       },
       {"vp.pcd: the file's viewpoint puts the scanner at (1e+09, 0, 0), beyond"}});
  c.push_back({"pose-option-far",
               [=](const fs::path& d) {
                 return discretize(write(d / "ok.xyz", xyz_rows(1200)), d, " --pose 1e308,0,0");
               },
               {"pose '1e308,0,0'", "beyond ±100000 m"}});
  c.push_back({"pose-option-heading",
               [=](const fs::path& d) {
                 return discretize(write(d / "ok.xyz", xyz_rows(1200)), d, " --pose 0,0,0,1e300");
               },
               {"pose '0,0,0,1e300'", "heading must be within ±360 degrees"}});
  c.push_back({"pose-json-far",
               [=](const fs::path& d) {
                 const std::string pose =
                     write(d / "pose.json", R"({"x": 1e308, "y": 0, "z": 0, "yaw_deg": 0})");
                 return discretize(write(d / "ok.xyz", xyz_rows(1200)), d, " --pose-file " + pose);
               },
               {"pose.json: the pose puts the scanner at (1e+308, 0, 0), beyond"}});
  // 3. An output that is an input (or another output).
  c.push_back({"export-over-its-input",
               [](const fs::path& d) {
                 fs::create_directories(d);
                 write_tree_file(*testing::sample_tree(), (d / "map.ot").string());
                 return "export " + (d / "map.ot").string() + " --color " + (d / "map.ot").string();
               },
               {"--color", "map.ot is the input IN", "would be overwritten"}});
  c.push_back({"export-two-outputs-one-file",
               [](const fs::path& d) {
                 fs::create_directories(d);
                 write_tree_file(*testing::sample_tree(), (d / "map.ot").string());
                 return "export " + (d / "map.ot").string() + " --color " + (d / "x.ot").string() +
                        " --bt " + (d / "sub/../x.ot").string();
               },
               {"--bt", "x.ot is also --color", "would be overwritten"}});
  c.push_back({"discretize-out-is-the-cloud",
               [=](const fs::path& d) {
                 const std::string cloud = write(d / "room.xyz", xyz_rows(1200));
                 return "discretize --cloud " + cloud + " --out " + cloud;
               },
               {"--out", "room.xyz is the input --cloud"}});
  c.push_back({"discretize-pose-file-in-out",
               [=](const fs::path& d) {
                 const std::string pose =
                     write(d / "out" / "stats.json", R"({"x": 0, "y": 0, "z": 0, "yaw_deg": 0})");
                 return discretize(write(d / "ok.xyz", xyz_rows(1200)), d, " --pose-file " + pose);
               },
               {"--pose-file", "stats.json lies where this command writes"}});
  c.push_back({"map-nbv-map-in-out",
               [](const fs::path& d) {
                 const std::string map = write(d / "occupancy.bt", "not read");
                 return "map-nbv --map " + map + " --scanner 1,1,1.5 --out " + d.string();
               },
               {"--map", "occupancy.bt lies where this command writes (occupancy.bt)"}});
  c.push_back({"nbv-cloud-in-a-scan-folder",
               [](const fs::path& d) {
                 const std::string cloud = write(d / "scan_00" / "cloud.xyz", xyz_rows(1200));
                 return "nbv --cloud " + cloud + " --out " + d.string();
               },
               {"--cloud", "cloud.xyz lies where this command writes (scan_[0-9][0-9]/)"}});
  // 6. Clouds nothing can be mapped from.
  c.push_back({"all-points-equal",
               [=](const fs::path& d) {
                 std::string rows;
                 for (int i = 0; i < 1200; ++i) rows += "3 1 1\n";
                 return discretize(write(d / "same.xyz", rows), d);
               },
               {"same.xyz: all 1200 points lie within 1 mm of each other"}});
  c.push_back({"all-points-far",
               [=](const fs::path& d) {
                 std::string rows;
                 for (int i = 0; i < 1200; ++i) rows += "1e5 " + std::to_string(i) + " 1\n";
                 return discretize(write(d / "far.xyz", rows), d);
               },
               {"far.xyz: no points within the scanner's range limits (0.6 to 60 m",
                "all 1200 lie outside"}});
  c.push_back({"nbv-all-points-far",
               [](const fs::path& d) {
                 std::string rows;
                 for (int i = 0; i < 1200; ++i) rows += "1e5 " + std::to_string(i) + " 1\n";
                 return "nbv --cloud " + write(d / "far.xyz", rows) + " --out " +
                        (d / "out").string();
               },
               {"far.xyz: no points within the scanner's range limits"}});
  c.push_back({"ptx-scan-without-a-return",
               [=](const fs::path& d) {
                 std::string two = ptx(kIdentityRows, "0 0 0 1");
                 two += two.substr(0, two.size() - 20) + "0 0 0 0.5\n0 0 0 0.5\n";
                 return discretize(write(d / "empty.ptx", two), d);
               },
               {"empty.ptx#1: holds no valid points"}});
  // 8. Corrupt data, said as such.
  c.push_back({"pcd-compressed-corrupt",
               [=](const fs::path& d) {
                 const std::string path = compressed_pcd(d / "c.pcd");
                 std::string bytes = testing::slurp(path);
                 const std::size_t block = bytes.find("DATA binary_compressed\n") + 23 + 8;
                 for (std::size_t i = block; i < bytes.size(); ++i) bytes[i] = '\xff';
                 return discretize(write(path, bytes), d);
               },
               {"c.pcd:", "binary_compressed data is corrupt"}});
  c.push_back({"pcd-compressed-truncated",
               [=](const fs::path& d) {
                 const std::string path = compressed_pcd(d / "t.pcd");
                 const std::string bytes = testing::slurp(path);
                 return discretize(write(path, bytes.substr(0, bytes.size() - 100)), d);
               },
               {"t.pcd:", "binary_compressed data is truncated"}});
  c.push_back({"ply-ascii-truncated",
               [=](const fs::path& d) {
                 std::string rows;
                 for (int i = 0; i < 5; ++i) rows += "1.000000 2.000000 3.000000\n";
                 return discretize(
                     write(d / "cut.ply",
                           "ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\n"
                           "property float y\nproperty float z\nend_header\n" +
                               rows),
                     d);
               },
               {"cut.ply:", "ascii PLY ends after 5 of 10 vertices"}});
#ifdef SEMIOCTREE_TEST_SIM
  // 3. The synthetic scanner's inputs and outputs.
  c.push_back({"scan-over-its-mesh",
               [](const fs::path& d) {
                 const std::string mesh = write(d / "room.ply", "not read");
                 return "scan --scene " + mesh + " --at 1,1 --out " + mesh;
               },
               {"--out", "room.ply is the input --scene"}});
  c.push_back({"coverage-bound-over-its-scene",
               [](const fs::path& d) {
                 const std::string scene =
                     write(d / "box.scene.json", testing::slurp(kScenes + "box-room.scene.json"));
                 return "coverage-bound --scene " + scene + " --out " + scene;
               },
               {"--out", "box.scene.json is the input --scene"}});
  // 4. A scan from beyond the scanner's range of the scene, or with no return at all.
  c.push_back({"scan-beyond-range-of-the-scene",
               [](const fs::path& d) {
                 return "scan --scene " + kScenes + "box-room.scene.json --at 1e5,0 --out " +
                        (d / "far.pcd").string();
               },
               {"--at", "the scanner at (100000, 0) is", "from the scene", "box-room.scene.json",
                "beyond the scanner's maximum range of 60 m"}});
  c.push_back({"scan-without-a-return",
               [](const fs::path& d) {
                 nlohmann::json scene =
                     nlohmann::json::parse(testing::slurp(kScenes + "box-room.scene.json"));
                 scene["scanner"] = {{"min_range", 0.6}, {"max_range", 0.7}};
                 const std::string file = write(d / "short.scene.json", scene.dump());
                 return "scan --scene " + file + " --at 3,2 --out " + (d / "none.pcd").string();
               },
               {"short.scene.json", "has no return", "nothing written"}});
#endif
  return c;
}

TEST(BadInput, EveryRowIsANonZeroExitNamingTheFileAndTheCause) {
  for (const Case& row : cases()) {
    SCOPED_TRACE(row.name);
    const fs::path dir = scratch() / row.name;
    const std::string args = row.args(dir);
    const auto before = fs::exists(dir) ? testing::slurp((dir / "map.ot").string()) : "";
    const testing::CliRun r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.all();
    for (const std::string& text : row.expect)
      EXPECT_NE(r.err.find(text), std::string::npos) << args << "\nexpected: " << text << "\n"
                                                     << r.err;
    EXPECT_NE(r.err.find("semioctree: error:"), std::string::npos) << r.err;
    // Refused before anything was written.
    EXPECT_FALSE(fs::exists(dir / "out" / "semioctree.ot")) << args;
    EXPECT_FALSE(fs::exists(dir / "survey.json")) << args;
    EXPECT_FALSE(fs::exists(dir / "far.pcd") || fs::exists(dir / "none.pcd")) << args;
    EXPECT_EQ(before, fs::exists(dir) ? testing::slurp((dir / "map.ot").string()) : "") << args;
    // PCL's console says nothing of its own.
    EXPECT_EQ(r.all().find("[pcl::"), std::string::npos) << r.all();
  }
}

// A run that writes into a directory removes the temporaries an interrupted
// run of ours left there (its process gone), and nothing else.
TEST(BadInput, StaleTemporariesAreRemovedByTheNextRun) {
  const fs::path dir = scratch() / "stale";
  fs::create_directories(dir);
  write_tree_file(*testing::sample_tree(), (dir / "map.ot").string());
  const pid_t gone = fork();  // a PID no process holds once reaped
  if (gone == 0) _exit(0);
  ASSERT_GT(gone, 0);
  waitpid(gone, nullptr, 0);
  const std::string dead = std::to_string(gone), alive = std::to_string(getpid());
  const std::vector<std::string> stale = {"c.ot.tmp-" + dead, "scan.pcd.tmp-" + dead + "-12345"};
  const std::vector<std::string> kept = {"c.ot.tmp-" + alive, "notes.tmp-" + dead + "x",
                                         "notes.txt", "c.ot.tmp-" + dead + "-"};
  for (const auto& name : stale) write(dir / name, "half");
  for (const auto& name : kept) write(dir / name, "keep");
  const auto r =
      run_cli("export " + (dir / "map.ot").string() + " --color " + (dir / "c.ot").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  for (const auto& name : stale) EXPECT_FALSE(fs::exists(dir / name)) << name;
  for (const auto& name : kept) EXPECT_TRUE(fs::exists(dir / name)) << name;
}

}  // namespace
}  // namespace semioctree
