// The coverage reference: the surface samples of a scene that a grid of scan positions
// over the survey area can see, computed once per scene and cached (docs/coverage.md).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/sim/ground_truth.h"

namespace semioctree::sim {

// The surface samples that are visible from at least one scan position of a grid.
struct CoverageReference {
  double grid_spacing = 0.5;     // metres between scan positions
  double sample_spacing = 0.02;  // spacing passed to GroundTruth::surface_samples (see
                                 // coverage_sample_spacing)
  std::size_t sample_count = 0;  // all surface samples of the scene at that spacing
  // Optical centres of the grid positions (world frame, z = scanner height); see
  // coverage_grid_positions.
  std::vector<Eigen::Vector3d> positions;
  // Indices into GroundTruth::surface_samples(sample_spacing) of the visible samples,
  // ascending, and their positions (what measure_coverage compares with).
  std::vector<std::uint32_t> visible;
  std::vector<Eigen::Vector3d> points;

  std::string key;  // hash of everything the result depends on (coverage_cache_key)
  bool from_cache = false;
  std::string cache_file;             // the file read or written ("" if none)
  std::uint64_t segment_queries = 0;  // ray-caster queries made (0 when loaded)
  // Samples searched among the positions of the room they face only, the walls shutting
  // the rooms off from each other (docs/coverage.md, "Rooms"; 0 when loaded).
  std::uint64_t samples_by_room = 0;
  double seconds = 0.0;  // wall time of this call (compute or load)
};

// The scan positions of the reference: a grid `grid_spacing` apart anchored at
// robot.start, inside the survey area, where the robot can stand and can drive to from
// robot.start; z is the scanner height. Throws std::invalid_argument unless spacing > 0.
std::vector<Eigen::Vector3d> coverage_grid_positions(const GroundTruth& truth,
                                                     double grid_spacing = 0.5);

// The most surface samples a reference takes (docs/coverage.md, "Floor scale"): 8 million
// samples are 450 MB while the reference is computed, under 200 MB of points after.
constexpr std::size_t kMaxCoverageSamples = 8'000'000;

// The sample spacing of a reference: `finest` where the scene's surface holds at most
// `max_samples` samples at it, else the spacing (whole millimetres) that brings the count
// down to about `max_samples`. The coverage then measured is that of a sparser, evenly
// spread subset of the same surfaces. Throws std::invalid_argument unless finest > 0.
double coverage_sample_spacing(const GroundTruth& truth, double finest = 0.02,
                               std::size_t max_samples = kMaxCoverageSamples);

// sample_visible_from applied to every sample (at coverage_sample_spacing(truth,
// sample_spacing)) and grid position, on `threads` threads (0: one per hardware thread);
// the result does not depend on the number of threads. Throws std::invalid_argument
// unless both spacings are > 0.
CoverageReference compute_coverage_reference(const GroundTruth& truth, double grid_spacing = 0.5,
                                             double sample_spacing = 0.02, unsigned threads = 0);

// A hash of the surface samples, the scene's triangles, the scanner and robot parameters,
// the survey area, both spacings and the version of the rule: any change gives another key.
std::string coverage_cache_key(const GroundTruth& truth, double grid_spacing = 0.5,
                               double sample_spacing = 0.02);

// The reference at coverage_sample_spacing(truth, sample_spacing):
// `<cache_dir>/coverage-<key>.bin` if present and intact, else computes the reference and
// writes that file (cache_file is "" if it cannot be written: not an error). An empty
// `cache_dir` means no cache: computed, nothing written.
CoverageReference load_or_compute_coverage_reference(const GroundTruth& truth,
                                                     const std::string& cache_dir,
                                                     double grid_spacing = 0.5,
                                                     double sample_spacing = 0.02,
                                                     unsigned threads = 0);

// $XDG_CACHE_HOME/semioctree if XDG_CACHE_HOME is set to an absolute path, else
// $HOME/.cache/semioctree, else <temp dir>/semioctree-cache. Not created here.
std::string default_cache_dir();

}  // namespace semioctree::sim
