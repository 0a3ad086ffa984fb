// The `semioctree` command line: --help, --version, info and export, and clear
// errors with a non-zero exit on bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "semioctree/octomap_ext/file_io.h"
#include "support/sample_trees.h"

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
  const CliRun r = run_cli("export " + ot.string() + " --color " + (dir / "c.ot").string() + " --bt " +
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

  std::ofstream(dir / "junk.ot") << "# Octomap OcTree file\nid SemiOcTree\nsize 99\nres 0.05\ndata\nxx";
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
  const CliRun wrong = run_cli("export " + (dir / "empty.bt").string() + " --ply " +
                            (dir / "x.ply").string());
  EXPECT_EQ(wrong.code, 1);
  EXPECT_NE(wrong.out.find("not a SemiOcTree"), std::string::npos) << wrong.out;
}

}  // namespace
}  // namespace semioctree
