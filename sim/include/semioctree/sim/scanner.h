// Static terrestrial laser scanner with a rotating head: one ray per cell of an
// azimuth × elevation grid, from the optical centre at scanner height above the floor.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <vector>

#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scene.h"

namespace semioctree::sim {

// Robot / scanner position on the floor (z = 0) and heading.
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double yaw_deg = 0.0;
};

struct ScanOptions {
  std::uint64_t seed = 1;  // range noise; the same seed gives the same scan
  unsigned threads = 0;    // 0: one per hardware thread; the result does not depend on it
  bool with_intensity = true;
  bool with_grid_indices = true;  // Scan::row and Scan::col (8 bytes a point)
  // Called now and then from the calling thread with the number of grid rows done.
  std::function<void(std::uint32_t rows_done, std::uint32_t rows)> progress;
};

// Size of the grid a ScannerConfig sweeps: rows are elevations from elevation_min_deg up
// (row r at elevation_min_deg + r * step), columns azimuths from 0° counter-clockwise.
struct ScanGrid {
  std::uint32_t rows = 0;
  std::uint32_t cols = 0;
  double elevation_deg(std::uint32_t row) const {
    return elevation_min_deg + row * elevation_step_deg;
  }
  double azimuth_deg(std::uint32_t col) const { return col * azimuth_step_deg; }
  double elevation_min_deg = 0.0;
  double elevation_step_deg = 0.0;
  double azimuth_step_deg = 0.0;
};
// Most rays one scan may have (scan_grid throws std::invalid_argument beyond).
constexpr std::uint64_t kMaxRaysPerScan = 200'000'000;
ScanGrid scan_grid(const ScannerConfig& config);
// Unit direction of grid cell (row, col) in the scanner frame (x forward, z up).
Eigen::Vector3d scan_direction(const ScanGrid& grid, std::uint32_t row, std::uint32_t col);

struct Scan {
  Pose2 pose;                  // where the scan was taken (true pose)
  double sensor_height = 0.0;  // optical centre above the floor
  ScanGrid grid;
  // Returned points in the scanner frame (origin at the optical centre, x along the
  // heading, z up), in row-major grid order; rays without a return in range are absent.
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;    // |cos| of the incidence angle, one per point (if asked)
  std::vector<std::uint32_t> row;  // grid row and column, one per point (if asked)
  std::vector<std::uint32_t> col;
  std::uint64_t rays_cast = 0;

  // Scanner frame → world frame.
  Eigen::Isometry3d sensor_to_world() const;
  Eigen::Vector3d origin() const { return {pose.x, pose.y, sensor_height}; }
};

// Casts the whole grid of `config` from `pose`. The range is drawn with N(0, sigma) noise
// from an RNG stream per grid row (seeded by `options.seed` and the row), so the result
// is identical whatever the number of threads.
Scan scan(const RayCaster& caster, const ScannerConfig& config, const Pose2& pose,
          const ScanOptions& options = {});

// One grid row of a scan: Scan's per-point vectors for that row alone.
struct ScanRow {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;
  std::vector<std::uint32_t> col;  // (the row is the index of the ScanRow)
};

// The scan `scan` would return, row by row: take_row(r, row) is called for r = 0, 1, ...
// in grid order, on the calling thread, as the rows are cast (in parallel, a batch of
// rows at a time). `header` gets Scan's other fields (its point vectors are left empty).
// A caller that turns the points into its own type never holds the scan twice, and this
// holds one batch of rows at most (a lab scan's 5.4 M points are 65 MB).
void for_each_scan_row(const RayCaster& caster, const ScannerConfig& config, const Pose2& pose,
                       const ScanOptions& options, Scan& header,
                       const std::function<void(std::uint32_t row_index, ScanRow&& row)>& take_row);

}  // namespace semioctree::sim
