// The cache of coverage references: its key and its file format (internal; the layout is
// described in docs/coverage.md, "The cache").
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "coverage/content_hash.h"
#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/ground_truth.h"

namespace semioctree::sim::detail {

// Bump when the visibility rule, the grid of positions or the file layout changes: old
// cache files then get another name and are never read. 2: nothing seen through an
// opening; 3: reachable positions only; 4: nor through one from a position standing in
// its doorway; 5: searched room by room, a gap between walls narrower than a plan cell
// counting as closed (docs/coverage.md, "Rooms"); 6: the visible samples' positions in
// the file.
constexpr std::uint32_t kCoverageRuleVersion = 6;
// The floor-plan cell coverage_grid_positions finds the survey area with (part of the key).
constexpr double kCoveragePlanCell = 0.05;

// The digest of a scene's surface samples, taken one at a time in their order (a scene's
// samples need not be held to key its reference).
class SamplesDigest {
 public:
  void add(const SurfaceSample& s) {
    hash_.bytes(s.position.data(), 3 * sizeof(double));
    hash_.bytes(s.normal.data(), 3 * sizeof(double));
    ++count_;
  }
  std::size_t count() const { return count_; }
  std::string hex() const { return hash_.hex(); }  // of the positions and normals

 private:
  ContentHash hash_;
  std::size_t count_ = 0;
};

// The digest of the samples GroundTruth::surface_samples(sample_spacing) returns,
// streamed; and of samples at hand.
SamplesDigest digest_of_samples(const GroundTruth& truth, double sample_spacing);
SamplesDigest digest_of_samples(const std::vector<SurfaceSample>& samples);

// The cache key (coverage_cache_key) of the reference of `truth` from its samples' digest.
std::string reference_key(const GroundTruth& truth, const SamplesDigest& samples,
                          double grid_spacing, double sample_spacing);

// `<cache_dir>/coverage-<key>.bin`.
std::filesystem::path cache_file_path(const std::string& cache_dir, const std::string& key);

// Reads `file` into ref.grid_spacing, sample_spacing, sample_count, positions, visible
// and points.
// False (and `ref` unusable) unless it exists and its size, header, key, spacings, sample
// count, checksum and indices all check out.
bool read_cached_reference(const std::filesystem::path& file, const std::string& key,
                           double grid_spacing, double sample_spacing, std::size_t sample_count,
                           CoverageReference& ref);

// Writes `ref` to `file` (a temporary name in the same directory, then renamed over it),
// creating the directory. False if that fails; nothing is left behind then.
bool write_cached_reference(const std::filesystem::path& file, const CoverageReference& ref);

}  // namespace semioctree::sim::detail
