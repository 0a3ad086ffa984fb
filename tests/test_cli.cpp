// The `semioctree` command line: --help, --version, info and export, and clear
// errors with a non-zero exit on bad input.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "semioctree/octomap_ext/file_io.h"
#include "support/sample_trees.h"
#include "support/synthetic_clouds.h"

namespace semioctree {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code;
  std::string out;  // stdout and stderr together
};

CliRun run_cli(const std::string& args) {
  const std::string cmd = std::string(SEMIOCTREE_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, ""};
  std::string out;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(Cli, VersionAndHelp) {
  const CliRun v = run_cli("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.out.find(SEMIOCTREE_VERSION), std::string::npos) << v.out;
  const CliRun h = run_cli("--help");
  EXPECT_EQ(h.code, 0);
  for (const char* sub : {"info", "export"}) EXPECT_NE(h.out.find(sub), std::string::npos) << h.out;
  const CliRun eh = run_cli("export --help");
  EXPECT_EQ(eh.code, 0);
  for (const char* opt : {"--color", "--bt", "--ply"})
    EXPECT_NE(eh.out.find(opt), std::string::npos) << eh.out;
  const CliRun none = run_cli("");
  EXPECT_NE(none.code, 0);
  const CliRun unknown = run_cli("frobnicate");
  EXPECT_NE(unknown.code, 0);
}

TEST(Cli, InfoDescribesASemiOcTree) {
  const auto dir = testing::temp_dir("cli-info");
  const SemiOcTree t = testing::sample_tree();
  const fs::path ot = dir / "map.ot";
  write_tree_file(t, ot.string());
  const CliRun r = run_cli("info " + ot.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("SemiOcTree"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("leaf size:      0.05"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("coarse size:    0.4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("octants:        " + std::to_string(t.statistics().total())),
            std::string::npos)
      << r.out;
  for (const char* label : {"occupied", "occluded", "door", "window", "out"})
    EXPECT_NE(r.out.find(label), std::string::npos) << label;
  EXPECT_NE(r.out.find("memory:"), std::string::npos);
}

TEST(Cli, ExportWritesFilesThatReadBack) {
  const auto dir = testing::temp_dir("cli-export");
  const SemiOcTree t = testing::sample_tree();
  const fs::path ot = dir / "map.ot";
  write_tree_file(t, ot.string());
  const CliRun r =
      run_cli("export " + ot.string() + " --color " + (dir / "c.ot").string() + " --bt " +
              (dir / "o.bt").string() + " --ply " + (dir / "p.ply").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_tree_file((dir / "c.ot").string()).type, "ColorOcTree");
  EXPECT_TRUE(read_tree_file((dir / "o.bt").string()).binary);
  EXPECT_GT(fs::file_size(dir / "p.ply"), 1000u);
  const CliRun info = run_cli("info " + (dir / "o.bt").string());
  EXPECT_EQ(info.code, 0) << info.out;
  EXPECT_NE(info.out.find("binary .bt"), std::string::npos) << info.out;
}

TEST(Cli, BadInputGivesAClearErrorAndNonZeroExit) {
  const auto dir = testing::temp_dir("cli-bad");
  const CliRun missing = run_cli("info " + (dir / "nope.ot").string());
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.out.find("semioctree: error:"), std::string::npos) << missing.out;
  EXPECT_NE(missing.out.find("nope.ot"), std::string::npos) << missing.out;

  std::ofstream(dir / "junk.ot")
      << "# Octomap OcTree file\nid SemiOcTree\nsize 99\nres 0.05\ndata\nxx";
  const CliRun junk = run_cli("info " + (dir / "junk.ot").string());
  EXPECT_EQ(junk.code, 1);
  EXPECT_NE(junk.out.find("junk.ot"), std::string::npos) << junk.out;

  // export needs a SemiOcTree and at least one output.
  const SemiOcTree t = testing::sample_tree();
  write_tree_file(t, (dir / "map.ot").string());
  const CliRun nothing = run_cli("export " + (dir / "map.ot").string());
  EXPECT_NE(nothing.code, 0);
  EXPECT_NE(nothing.out.find("--color"), std::string::npos) << nothing.out;
  write_binary_file(*std::make_unique<octomap::OcTree>(0.1), (dir / "empty.bt").string());
  const CliRun wrong =
      run_cli("export " + (dir / "empty.bt").string() + " --ply " + (dir / "x.ply").string());
  EXPECT_EQ(wrong.code, 1);
  EXPECT_NE(wrong.out.find("not a SemiOcTree"), std::string::npos) << wrong.out;
}

TEST(Cli, DiscretizeWritesEveryFile) {
  const auto dir = testing::temp_dir("cli-disc");
  pcl::io::savePCDFileBinary((dir / "room.pcd").string(),
                             *testing::synthetic_room(6, 4, 2.8, 0.04));
  const CliRun r =
      run_cli("discretize --cloud " + (dir / "room.pcd").string() +
              " --pose 3,2,1.5,0 --leaf 0.1 --coarse 0.8 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* f :
       {"semioctree.ot", "labels_color.ot", "occupancy.bt", "slice.png", "stats.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  EXPECT_NE(r.out.find("preprocess:"), std::string::npos) << r.out;
  const auto tree = read_semioctree_file((dir / "out" / "semioctree.ot").string());
  EXPECT_EQ(tree->coarse_level(), 3u);
  std::ifstream js(dir / "out" / "stats.json");
  const auto j = nlohmann::json::parse(js);
  EXPECT_EQ(j["octants"].get<std::uint64_t>(), tree->statistics().total());
  EXPECT_GT(j["volume_percent"]["occupied"].get<double>(), 0.0);
  // A bad coarse size is refused before anything is read.
  const CliRun bad = run_cli("discretize --cloud " + (dir / "room.pcd").string() +
                             " --leaf 0.1 --coarse 0.7 --out " + (dir / "x").string());
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.out.find("power of two"), std::string::npos) << bad.out;
  const CliRun missing = run_cli("discretize --cloud " + (dir / "nope.pcd").string() + " --out x");
  EXPECT_NE(missing.code, 0);
}

TEST(Cli, CompareWritesTablesAndChart) {
  const auto dir = testing::temp_dir("cli-cmp");
  pcl::io::savePCDFileBinary((dir / "room.pcd").string(),
                             *testing::synthetic_room(6, 4, 2.8, 0.04));
  const CliRun r = run_cli("compare --cloud " + (dir / "room.pcd").string() +
                           " --leaves 0.4,0.2,0.1 --out " + (dir / "cmp").string());
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* f : {"comparison.json", "comparison.md", "fig15_octants.png",
                        "slice_semioctree_0.1.png", "slice_homogeneous_0.1.png"})
    EXPECT_TRUE(fs::exists(dir / "cmp" / f)) << f;
  std::ifstream js(dir / "cmp" / "comparison.json");
  const auto j = nlohmann::json::parse(js);
  // Homogeneous over the same region at every resolution: each halving is ×8.
  for (double f : j["table2"]["homogeneous"]["factors"]) EXPECT_DOUBLE_EQ(f, 8.0);
  EXPECT_LT(j["table2"]["semioctree"]["average"].get<double>(), 6.0);
  EXPECT_EQ(j["table1"].size(), 6u);
  std::ifstream md(dir / "cmp" / "comparison.md");
  std::stringstream mds;
  mds << md.rdbuf();
  EXPECT_NE(mds.str().find("Table 2"), std::string::npos);
}

}  // namespace
}  // namespace semioctree
