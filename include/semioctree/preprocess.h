// Stage 1 (paper 2.1): level the cloud and cut floor and ceiling out of it.
// RANSAC finds the largest horizontal plane (normal within max_tilt_deg of z) among
// points spread evenly over the surfaces (one per cube 2 · ransac_distance wide),
// the other horizontal planes are the peaks of the heights along its normal
// (floor and ceiling are parallel); the rotation of Eq 1-2 levels them, a translation puts
// the floor at z = 0; a Gaussian fitted to the floor and the ceiling peaks of
// the z histogram gives σ, and points within 2σ of either are removed (they
// carry no information for the NBV). Finally the cloud is decimated to a
// minimum point spacing or a target count. A cloud without a ceiling (open
// above, or a ceiling the scanner does not reach) is levelled by its floor
// alone, and the room's height is the top of its points (docs/data-flow.md).
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "semioctree/octomap_ext/packed_key_map.h"
#include "semioctree/scan_io.h"

namespace semioctree {

struct PreprocessParams {
  double max_tilt_deg = 15.0;     // a floor/ceiling normal is within this angle of z
  double ransac_distance = 0.03;  // RANSAC inlier distance, m
  int ransac_iterations = 500;
  std::size_t ransac_sample = 60000;  // planes are searched in subsets this large
  double min_plane_fraction = 0.01;   // a floor/ceiling holds at least this share of points
  double min_room_height = 1.8;       // floor and ceiling at least this far apart, m
  double histogram_bin = 0.01;        // z histogram bin, m
  double peak_window = 0.15;          // search for the peaks this far from the planes, m
  double sigma_factor = 2.0;          // remove points within this many σ of floor/ceiling
  double min_sigma = 0.002;           // σ is at least this (noise-free data), m
  double min_spacing = 0.0;           // decimation: minimum point spacing, m (0: off)
  std::size_t target_points = 0;      // decimation: aim for this many points (0: off)
  std::size_t min_points = 1000;      // fewer input points than this is an error
  // Without a ceiling, the room's height is this quantile of the heights of the points
  // left after the floor cut (a few stray returns above the room do not raise it).
  double top_quantile = 0.999;
  // > 0: the room's height above the floor, m, given (a ceiling found is still cut).
  double ceiling_height = 0;
  // Workers for the decimation's counts and thinning (0: one per core); the result does
  // not depend on it.
  unsigned threads = 0;
};

// Where PreprocessResult::ceiling_height comes from.
enum class RoomHeightFrom { kCeiling, kPoints, kGiven };
const char* to_string(RoomHeightFrom from);  // "ceiling", "points", "given"
// The room's height in words for progress lines: "ceiling 3.20 m", "no ceiling found,
// height 2.95 m from the points", ...
std::string describe_room_height(bool ceiling_found, RoomHeightFrom from, double height);

struct HeightPeak {
  double center = 0;  // z of the Gaussian's mean (levelled frame)
  double sigma = 0;   // its standard deviation
  std::size_t removed = 0;
  std::size_t plane_inliers = 0;
};

struct PreprocessResult {
  Cloud::Ptr cloud;                    // levelled, floor at z = 0, floor/ceiling removed, decimated
  Eigen::Isometry3d transform;         // input frame → levelled frame
  double alpha_deg = 0, beta_deg = 0;  // Eq 1 angles of the floor's normal
  Eigen::Vector3d normal_input;        // that normal in the input frame (z > 0)
  bool ceiling_found = false;          // else `ceiling` is all zero and nothing was cut there
  // The room's height above the floor (the map's top): the ceiling's, else the
  // top_quantile of the points' heights, or PreprocessParams::ceiling_height when given.
  double ceiling_height = 0;
  RoomHeightFrom height_from = RoomHeightFrom::kCeiling;
  HeightPeak floor, ceiling;
  std::size_t input_points = 0;
  std::size_t after_cut = 0;      // after removing floor and ceiling points
  std::size_t output_points = 0;  // after decimation
  double decimation_spacing = 0;  // spacing actually used (0: none)
  // The spacings the search for target_points counted, in order, with their cells.
  std::vector<std::pair<double, std::size_t>> spacing_counts;
};

class PreprocessError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws PreprocessError (with the reason) when the cloud has fewer than
// params.min_points points or more than 2^32 − 1, no plane within max_tilt_deg of horizontal, or
// neither a ceiling (a horizontal surface at least min_room_height above the
// floor), a given height nor a point above the floor.
PreprocessResult preprocess(const Cloud& input, const PreprocessParams& params = {});

// Decimates to a minimum spacing: one original point per world-aligned cell of that
// size, the one nearest the cell's centre (as PCL's UniformSampling keeps), in the order
// the cells are first met; non-finite points are dropped.
Cloud::Ptr decimate(const Cloud& cloud, double spacing);

// decimate, a cloud at a time: after add(a), add(b), ... cloud() is decimate(a + b + ...)
// (the same points in the same order), each add costing its own points only. Keeps the
// cells' table (12 bytes a slot, a slot or two a point kept) and, in front of it, the
// last 4 096 cells met (48 KB). Points added are placed 256 at a time (their cells worked
// out lanes at a time), and before cloud(), release() and release_after() read the result.
class CellThinning {
 public:
  explicit CellThinning(double spacing);       // spacing > 0, else std::invalid_argument
  CellThinning(const CellThinning&) = delete;  // (the kept cloud is not shared)
  CellThinning& operator=(const CellThinning&) = delete;
  CellThinning(CellThinning&&) = default;
  CellThinning& operator=(CellThinning&&) = default;
  // Room for `cells` cells at once (the points kept are the same; the table is not grown
  // by doubling on the way there).
  void reserve(std::size_t cells);
  void add(const Cloud& points);
  void add(const pcl::PointXYZ& point);  // one point (a non-finite one is skipped)
  const Cloud& cloud();                  // the points kept so far
  Cloud::Ptr release();  // the kept cloud, handed over (the thinning is empty after)
  // What thinning `earlier` and then the points added here keeps, written into `earlier`
  // in place. `earlier` must hold one point per cell of this spacing, in the order their
  // cells were first met (a thinning's cloud, as release() gives it): its points stay
  // where they are, each replaced by the point added here nearest its cell's centre if
  // that one is nearer, and the cells only added here follow in their order. `earlier`
  // is read once, its cells looked up in this thinning's table (no table of its own);
  // the thinning is empty after.
  void release_after(Cloud& earlier);
  double spacing() const { return 1.0 / inv_; }

 private:
  float centre_offset2(const pcl::PointXYZ& p) const;                    // squared, in cells
  void empty();                                                          // as constructed
  void place(const pcl::PointXYZ& q, std::uint64_t key, float offset2);  // q of that cell
  void place_pending();  // the points added and not placed yet, in order
  // The cells' keys (cell_key's) and squared offsets (centre_offset2's) of n <= 256 finite
  // points given by their coordinates, worked out lanes at a time (src/cell_lanes.h).
  void cells_of(std::size_t n, const float* x, const float* y, const float* z, std::uint64_t* keys,
                float* offsets2) const;
  double inv_;
  PackedKeyMap<std::uint32_t> slot_;  // cell → index of its point in kept_
  RecentKeys<std::uint32_t> recent_;  // the cells of the last points, in front of slot_
  std::vector<float> offset2_;        // per kept point: squared distance from its cell's centre
  Cloud::Ptr kept_;
  static constexpr std::size_t kBatch = 256;
  struct Pending {  // points added, not placed yet (finite)
    pcl::PointXYZ points[kBatch];
    float x[kBatch], y[kBatch], z[kBatch];
    std::size_t size = 0;
  } pending_;
};
// Number of cells of side `spacing` (world-aligned, as decimate's) holding a point of
// `cloud`, exactly, with tables of about `cap` keys at most: beyond that (a spacing much
// finer than the points' on a scan of millions) the keys are split by their hash and
// counted part by part, one pass over the points a part. Non-finite points are skipped.
// Contiguous shares of the cloud are counted on `threads` workers (0: one per core), a
// table of up to `cap` keys each (one worker alone: two, its keys split between them by
// hash), and the keys of their union counted by looking them up (no table grows). Where a
// bitmap of the cells over the cloud's bounds fits in the memory those tables would take,
// each worker counts in one instead (the same count; docs/data-flow.md, "Decimation").
std::size_t count_cells(const Cloud& cloud, double spacing, std::size_t cap, unsigned threads = 1);

}  // namespace semioctree
