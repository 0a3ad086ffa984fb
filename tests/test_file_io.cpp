// Reading and writing .ot / .bt files: round trips, and bad files (missing,
// truncated, corrupted, wrong type) giving a clear error that names the file.
#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <tuple>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"
#include "support/sample_trees.h"
#include "support/scratch.h"

namespace semioctree {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}
void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(s.data(), std::streamsize(s.size()));
}

struct SampleFiles {
  fs::path dir, semi, color, bt;
};

SampleFiles write_samples(const std::string& name) {
  SampleFiles f;
  f.dir = testing::temp_dir(name);
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  f.semi = f.dir / "semioctree.ot";
  f.color = f.dir / "labels_color.ot";
  f.bt = f.dir / "occupancy.bt";
  write_tree_file(t, f.semi.string());
  write_tree_file(*to_color_octree(t), f.color.string());
  write_binary_file(*to_occupancy_octree(t), f.bt.string());
  return f;
}

void expect_error_naming(const fs::path& p, const char* what_part = nullptr) {
  try {
    read_tree_file(p.string());
    ADD_FAILURE() << "no error for " << p;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    if (what_part) {
      EXPECT_NE(std::string(e.what()).find(what_part), std::string::npos) << e.what();
    }
  }
}

TEST(FileIo, ReadsEachTypeBack) {
  const auto f = write_samples("types");
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  auto semi = read_tree_file(f.semi.string());
  EXPECT_EQ(semi.type, "SemiOcTree");
  EXPECT_FALSE(semi.binary);
  const auto* semi_tree = dynamic_cast<SemiOcTree*>(semi.tree.get());
  ASSERT_NE(semi_tree, nullptr);
  EXPECT_EQ(semi.tree->size(), t.size());
  // The same octants (min-corner key, level) with the same labels.
  using OctantId = std::tuple<unsigned, unsigned, unsigned, unsigned>;
  auto labels_of = [](const SemiOcTree& tree) {
    std::map<OctantId, Label> m;
    tree.for_each_octant([&](const Octant& o) {
      m[{o.key.k[0], o.key.k[1], o.key.k[2], o.level}] = o.label();
    });
    return m;
  };
  const auto want_labels = labels_of(t);
  EXPECT_GT(want_labels.size(), 100u);
  EXPECT_EQ(labels_of(*semi_tree), want_labels);

  auto color = read_tree_file(f.color.string());
  EXPECT_EQ(color.type, "ColorOcTree");
  const auto* color_tree = dynamic_cast<octomap::ColorOcTree*>(color.tree.get());
  ASSERT_NE(color_tree, nullptr);
  // Leaf by leaf (key, depth), the colours of the tree that was written.
  auto colours_of = [](const octomap::ColorOcTree& tree) {
    std::map<std::tuple<unsigned, unsigned, unsigned, unsigned>, std::tuple<int, int, int>> m;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const octomap::OcTreeKey k = it.getKey();
      const auto c = it->getColor();
      m[{k.k[0], k.k[1], k.k[2], it.getDepth()}] = {c.r, c.g, c.b};
    }
    return m;
  };
  const auto want_colours = colours_of(*to_color_octree(t));
  EXPECT_GT(want_colours.size(), 100u);
  EXPECT_EQ(colours_of(*color_tree), want_colours);
  auto bt = read_tree_file(f.bt.string());
  EXPECT_TRUE(bt.binary);
  EXPECT_NE(dynamic_cast<octomap::OcTree*>(bt.tree.get()), nullptr);
  EXPECT_EQ(bt.tree->size(), bt.header_size);
  // No temporary file is left behind.
  for (const auto& e : fs::directory_iterator(f.dir))
    EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST(FileIo, MissingFileIsAClearError) {
  expect_error_naming("/nonexistent/dir/map.ot", "cannot open");
}

TEST(FileIo, NotAnOctoMapFile) {
  const auto dir = testing::temp_dir("notoctomap");
  write_bytes(dir / "text.ot", "hello\nworld\n");
  expect_error_naming(dir / "text.ot", "not an OctoMap file");
  write_bytes(dir / "empty.bt", "");
  expect_error_naming(dir / "empty.bt", "empty");
}

TEST(FileIo, WrongTypeIsAClearError) {
  const auto f = write_samples("wrongtype");
  try {
    read_semioctree_file(f.bt.string());
    FAIL();
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("not a SemiOcTree"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(f.bt.string()), std::string::npos) << e.what();
  }
  // An unknown tree type in the header.
  std::string bytes = read_bytes(f.color);
  bytes.replace(bytes.find("ColorOcTree"), 11, "StampOcTree");
  write_bytes(f.dir / "stamp.ot", bytes);
  expect_error_naming(f.dir / "stamp.ot", "unsupported tree type");
}

// Every strict prefix of a valid file is rejected with an error naming it.
TEST(FileIo, TruncationsAreRejected) {
  const auto f = write_samples("trunc");
  for (const fs::path& src : {f.semi, f.color, f.bt}) {
    const std::string bytes = read_bytes(src);
    ASSERT_GT(bytes.size(), 100u);
    const fs::path cut = f.dir / ("cut-" + src.filename().string());
    const std::size_t step = std::max<std::size_t>(1, bytes.size() / 400);
    int tried = 0;
    for (std::size_t len = 0; len < bytes.size(); len += (len < 200 ? 1 : step)) {
      write_bytes(cut, bytes.substr(0, len));
      expect_error_naming(cut);
      ++tried;
    }
    EXPECT_GT(tried, 300) << src;
  }
}

// Random byte flips never crash the reader. A SemiOcTree file carries a
// checksum: a flip is either reported or leaves the map exactly as it was.
TEST(FileIo, ByteFlipsAreRejectedOrHarmless) {
  const auto f = write_samples("flip");
  std::mt19937 rng(9);
  const auto original_tree = testing::sample_tree();
  const SemiOcTree& original = *original_tree;
  std::map<std::tuple<unsigned, unsigned, unsigned, unsigned>, Label> want;
  original.for_each_octant([&](const Octant& o) {
    want[{o.key.k[0], o.key.k[1], o.key.k[2], o.level}] = o.label();
  });
  for (const fs::path& src : {f.semi, f.color, f.bt}) {
    const std::string bytes = read_bytes(src);
    const fs::path bad = f.dir / ("flip-" + src.filename().string());
    std::uniform_int_distribution<std::size_t> pos(0, bytes.size() - 1);
    std::uniform_int_distribution<int> bit(0, 7);
    int rejected = 0;
    for (int i = 0; i < 300; ++i) {
      std::string b = bytes;
      const int flips = 1 + i % 3;
      for (int j = 0; j < flips; ++j) b[pos(rng)] ^= char(1 << bit(rng));
      write_bytes(bad, b);
      try {
        TreeFile tf = read_tree_file(bad.string());
        EXPECT_EQ(tf.tree->size(), tf.header_size) << "a file that reads holds what it says";
        if (auto* semi = dynamic_cast<SemiOcTree*>(tf.tree.get())) {
          std::map<std::tuple<unsigned, unsigned, unsigned, unsigned>, Label> got;
          semi->for_each_octant([&](const Octant& o) {
            got[{o.key.k[0], o.key.k[1], o.key.k[2], o.level}] = o.label();
          });
          EXPECT_EQ(got, want) << "a corrupted SemiOcTree must not read as a different map";
        }
      } catch (const FileError& e) {
        EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
        ++rejected;
      }
    }
    // With its checksum, nearly every flip of a SemiOcTree file is caught; the
    // stock formats only catch flips that break the structure.
    EXPECT_GT(rejected, src == f.semi ? 280 : 30) << src;
  }
}

TEST(FileIo, WriteToUnwritablePlaceIsAClearError) {
  const auto t_tree = testing::sample_tree();
  const SemiOcTree& t = *t_tree;
  try {
    write_tree_file(t, "/nonexistent/dir/out.ot");
    FAIL();
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/out.ot"), std::string::npos);
  }
}

}  // namespace
}  // namespace semioctree
