// The per-scene cache of coverage references: key, round trip, damaged files, directories.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <system_error>

#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "support/coverage_scenes.h"

namespace {

using namespace semioctree::sim;
using namespace semioctree::testing;
namespace fs = std::filesystem;

// A directory of this test process's own, removed at exit.
const fs::path& scratch() {
  static const struct Dir {
    fs::path path =
        fs::temp_directory_path() / ("semioctree_test_coverage_" + std::to_string(::getpid()));
    Dir() { fs::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } dir;
  return dir.path;
}

TEST(CoverageCache, RoundTripsAndIsKeyedByTheScene) {
  const fs::path dir = scratch() / "roundtrip";
  const GroundTruth truth(load("box-room"));
  const CoverageReference first = load_or_compute_coverage_reference(truth, dir.string());
  EXPECT_FALSE(first.from_cache);
  ASSERT_FALSE(first.cache_file.empty());
  EXPECT_TRUE(fs::exists(first.cache_file));
  EXPECT_EQ(fs::path(first.cache_file).parent_path(), dir);
  // Only the final file is left (the temporary was renamed).
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);

  const CoverageReference second = load_or_compute_coverage_reference(truth, dir.string());
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.cache_file, first.cache_file);
  EXPECT_EQ(second.visible, first.visible);
  EXPECT_EQ(second.positions, first.positions);
  EXPECT_EQ(second.points, first.points);
  EXPECT_EQ(second.sample_count, first.sample_count);
  EXPECT_EQ(second.segment_queries, 0u);  // nothing recomputed (times are the benchmarks')
  std::cout << "box-room reference: computed in " << first.seconds << " s, loaded in "
            << second.seconds << " s\n";
  // The computed and the cached results equal a plain computation.
  const CoverageReference plain = compute_coverage_reference(truth);
  EXPECT_EQ(plain.visible, first.visible);
  EXPECT_EQ(plain.key, first.key);  // its samples' digest taken from them at hand

  // Same scene, same key; any parameter the reference depends on changes it.
  const std::string key = coverage_cache_key(truth);
  EXPECT_EQ(key, first.key);
  EXPECT_EQ(key, coverage_cache_key(GroundTruth(load("box-room"))));
  EXPECT_NE(key, coverage_cache_key(truth, 0.25));
  EXPECT_NE(key, coverage_cache_key(truth, 0.5, 0.05));
  Scene changed = load("box-room");
  changed.scanner.height = 1.4;
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.robot.radius = 0.4;
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.walls[2].z1 = 2.7;  // geometry
  EXPECT_NE(key, coverage_cache_key(GroundTruth(changed)));
  changed = load("box-room");
  changed.scanner.elevation_min_deg = -10;
  const CoverageReference other =
      load_or_compute_coverage_reference(GroundTruth(changed), dir.string());
  EXPECT_FALSE(other.from_cache);
  EXPECT_NE(other.cache_file, first.cache_file);
  // Wall feet are more than 10° below every position within the room's 7.2 m diagonal.
  EXPECT_LT(other.visible.size(), first.visible.size());
}

TEST(CoverageCache, ACorruptOrTruncatedFileIsRecomputed) {
  const fs::path dir = scratch() / "corrupt";
  const GroundTruth truth(load("one-door-window"));
  const CoverageReference good = load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05);
  ASSERT_FALSE(good.cache_file.empty());
  const auto size = fs::file_size(good.cache_file);
  ASSERT_GT(size, 100u);
  std::string bytes;
  {
    std::ifstream in(good.cache_file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_EQ(bytes.size(), size);
  auto write = [&](const std::string& data) {
    std::ofstream out(good.cache_file, std::ios::binary | std::ios::trunc);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  };
  const std::string flipped = [&] {
    std::string b = bytes;
    b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 0x10);  // one bit in the indices
    return b;
  }();
  for (const std::string& bad :
       {bytes.substr(0, bytes.size() - 4), bytes.substr(0, bytes.size() / 2), flipped,
        std::string(), std::string("not a cache file"), bytes + "x"}) {
    write(bad);
    const CoverageReference again =
        load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05);
    EXPECT_FALSE(again.from_cache) << "a damaged file of " << bad.size() << " bytes was trusted";
    EXPECT_EQ(again.visible, good.visible);
    EXPECT_EQ(again.cache_file, good.cache_file);
    // The file was rewritten whole.
    EXPECT_EQ(fs::file_size(good.cache_file), size);
    EXPECT_TRUE(load_or_compute_coverage_reference(truth, dir.string(), 0.5, 0.05).from_cache);
  }
}

TEST(CoverageCache, AnUnwritableOrEmptyCacheDirectoryOnlyCostsTheCache) {
  const fs::path blocker = scratch() / "not-a-directory";
  std::ofstream(blocker) << "a file where the cache directory should be";
  const GroundTruth truth(load("box-room"));
  const CoverageReference plain = compute_coverage_reference(truth, 0.5, 0.05);
  const CoverageReference unwritable =
      load_or_compute_coverage_reference(truth, (blocker / "cache").string(), 0.5, 0.05);
  EXPECT_FALSE(unwritable.from_cache);
  EXPECT_TRUE(unwritable.cache_file.empty());
  EXPECT_EQ(unwritable.visible, plain.visible);
  const CoverageReference none = load_or_compute_coverage_reference(truth, "", 0.5, 0.05);
  EXPECT_FALSE(none.from_cache);
  EXPECT_TRUE(none.cache_file.empty());
  EXPECT_EQ(none.visible, plain.visible);
  EXPECT_EQ(none.key, plain.key);
}

TEST(CoverageCache, DefaultDirectoryFollowsXdgThenHome) {
  const char* old_xdg = std::getenv("XDG_CACHE_HOME");
  const std::string saved = old_xdg ? old_xdg : "";
  ::setenv("XDG_CACHE_HOME", "/some/cache", 1);
  EXPECT_EQ(default_cache_dir(), "/some/cache/semioctree");
  ::unsetenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  if (home && home[0]) {
    EXPECT_EQ(default_cache_dir(), std::string(home) + "/.cache/semioctree");
  }
  if (old_xdg) ::setenv("XDG_CACHE_HOME", saved.c_str(), 1);
}

}  // namespace
