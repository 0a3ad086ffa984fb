// The synthetic TLS: rows of rays cast in parallel, one noise stream per row.
#include "semioctree/sim/scanner.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

#include "parallel.h"

namespace semioctree::sim {

ScanGrid scan_grid(const ScannerConfig& c) {
  // The small slack keeps e.g. (90 − (−60)) / 0.1 = 1500 from rounding down to 1499.
  const double rows =
      std::floor((c.elevation_max_deg - c.elevation_min_deg) / c.elevation_step_deg + 1e-6) + 1;
  const double cols = std::ceil(360.0 / c.azimuth_step_deg - 1e-6);
  // Each ray keeps up to ~30 bytes of output. 0.02° steps, finer than most
  // surveys use, give 1.35e8 rays; a step typed a few orders too small would
  // ask for terabytes.
  if (!(rows * cols <= double(kMaxRaysPerScan))) {
    char msg[300];
    std::snprintf(msg, sizeof msg,
                  "scanner steps of %g° (azimuth) and %g° (elevation) make %.3g rays per scan "
                  "(at most %.3g)",
                  c.azimuth_step_deg, c.elevation_step_deg, rows * cols, double(kMaxRaysPerScan));
    throw std::invalid_argument(msg);
  }
  ScanGrid g;
  g.elevation_min_deg = c.elevation_min_deg;
  g.elevation_step_deg = c.elevation_step_deg;
  g.azimuth_step_deg = c.azimuth_step_deg;
  g.rows = static_cast<std::uint32_t>(rows);
  g.cols = static_cast<std::uint32_t>(cols);
  return g;
}

Eigen::Vector3d scan_direction(const ScanGrid& grid, std::uint32_t row, std::uint32_t col) {
  const double el = grid.elevation_deg(row) * M_PI / 180.0;
  const double az = grid.azimuth_deg(col) * M_PI / 180.0;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

Eigen::Isometry3d Scan::sensor_to_world() const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(origin());
  t.rotate(Eigen::AngleAxisd(pose.yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()));
  return t;
}

namespace {

// SplitMix64: turns (seed, row) into well-spread seeds for the per-row generators.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

std::vector<ScanRow> scan_rows(const RayCaster& caster, const ScannerConfig& config,
                               const Pose2& pose, const ScanOptions& options, Scan& out) {
  out = Scan();
  out.pose = pose;
  out.sensor_height = config.height;
  out.grid = scan_grid(config);
  const ScanGrid& g = out.grid;
  out.rays_cast = static_cast<std::uint64_t>(g.rows) * g.cols;

  const double yaw = pose.yaw_deg * M_PI / 180.0;
  std::vector<double> cos_az(g.cols), sin_az(g.cols), cos_world(g.cols), sin_world(g.cols);
  for (std::uint32_t c = 0; c < g.cols; ++c) {
    const double az = g.azimuth_deg(c) * M_PI / 180.0;
    cos_az[c] = std::cos(az);
    sin_az[c] = std::sin(az);
    cos_world[c] = std::cos(az + yaw);
    sin_world[c] = std::sin(az + yaw);
  }
  const Eigen::Vector3f origin(static_cast<float>(pose.x), static_cast<float>(pose.y),
                               static_cast<float>(config.height));
  const double sigma = config.range_noise_sigma;
  // Cast a little past max_range so that a surface just beyond it can still be measured
  // inside it with noise; the measured range decides what is kept.
  const float t_far = static_cast<float>(config.max_range + 6 * sigma);

  std::vector<ScanRow> rows(g.rows);
  std::atomic<std::uint32_t> next_row{0};
  std::atomic<std::uint32_t> rows_done{0};
  auto work = [&](bool report) {
    std::vector<Ray> rays(g.cols);
    std::vector<RayHit> hits(g.cols);
    std::vector<float> noise(g.cols + 1, 0.0f);
    for (std::uint32_t r = next_row++; r < g.rows; r = next_row++) {
      const double el = g.elevation_deg(r) * M_PI / 180.0;
      const double ce = std::cos(el), se = std::sin(el);
      for (std::uint32_t c = 0; c < g.cols; ++c) {
        Ray& ray = rays[c];
        ray.origin = origin;
        ray.direction =
            Eigen::Vector3f(static_cast<float>(ce * cos_world[c]),
                            static_cast<float>(ce * sin_world[c]), static_cast<float>(se));
        ray.t_near = 0.0f;
        ray.t_far = t_far;
      }
      caster.intersect(rays.data(), hits.data(), g.cols);

      // One noise value per grid cell, hit or not, drawn in column order from this row's
      // own stream: the values do not depend on which thread runs the row.
      std::mt19937_64 rng(mix(options.seed ^ mix(r + 1)));
      if (sigma > 0) {
        for (std::uint32_t c = 0; c < g.cols; c += 2) {
          // Box–Muller written out: std::normal_distribution differs between libraries.
          // Single precision is ample for millimetre noise and twice as fast.
          const float u1 = (static_cast<float>(rng() >> 40) + 1.0f) * 0x1.0p-24f;  // (0, 1]
          const float u2 = static_cast<float>(rng() >> 40) * 0x1.0p-24f;
          const float radius = static_cast<float>(sigma) * std::sqrt(-2.0f * std::log(u1));
          const float angle = 6.2831853f * u2;
          noise[c] = radius * std::cos(angle);
          noise[c + 1] = radius * std::sin(angle);
        }
      }
      ScanRow& row = rows[r];
      row.points.reserve(g.cols);
      if (options.with_grid_indices) row.col.reserve(g.cols);
      if (options.with_intensity) row.intensity.reserve(g.cols);
      for (std::uint32_t c = 0; c < g.cols; ++c) {
        if (!hits[c].hit) continue;
        const double range = static_cast<double>(hits[c].distance) + static_cast<double>(noise[c]);
        if (range < config.min_range || range > config.max_range) continue;
        row.points.emplace_back(static_cast<float>(ce * cos_az[c] * range),
                                static_cast<float>(ce * sin_az[c] * range),
                                static_cast<float>(se * range));
        if (options.with_intensity)
          row.intensity.push_back(std::abs(rays[c].direction.dot(hits[c].normal)));
        if (options.with_grid_indices) row.col.push_back(c);
      }
      const std::uint32_t done = ++rows_done;
      if (report && options.progress && done % 64 == 0) options.progress(done, g.rows);
    }
  };
  const unsigned threads = std::min<unsigned>(detail::thread_count(options.threads), g.rows);
  detail::run_on_threads(threads, work);
  if (options.progress) options.progress(g.rows, g.rows);
  return rows;
}

Scan scan(const RayCaster& caster, const ScannerConfig& config, const Pose2& pose,
          const ScanOptions& options) {
  Scan out;
  std::vector<ScanRow> rows = scan_rows(caster, config, pose, options, out);
  const ScanGrid& g = out.grid;
  const unsigned threads = std::min<unsigned>(detail::thread_count(options.threads), g.rows);

  // Gather the rows in grid order, in parallel as well (a fine scan is ~100 MB).
  std::vector<std::size_t> offset(g.rows + 1, 0);
  for (std::uint32_t r = 0; r < g.rows; ++r) offset[r + 1] = offset[r] + rows[r].points.size();
  const std::size_t total = offset[g.rows];
  out.points.resize(total);
  if (options.with_grid_indices) {
    out.row.resize(total);
    out.col.resize(total);
  }
  if (options.with_intensity) out.intensity.resize(total);
  std::atomic<std::uint32_t> next_copy{0};
  detail::run_on_threads(threads, [&](bool) {
    for (std::uint32_t r = next_copy++; r < g.rows; r = next_copy++) {
      ScanRow& row = rows[r];
      std::copy(row.points.begin(), row.points.end(),
                out.points.begin() + static_cast<long>(offset[r]));
      if (options.with_grid_indices) {
        std::copy(row.col.begin(), row.col.end(), out.col.begin() + static_cast<long>(offset[r]));
        std::fill_n(out.row.begin() + static_cast<long>(offset[r]), row.col.size(), r);
      }
      if (options.with_intensity)
        std::copy(row.intensity.begin(), row.intensity.end(),
                  out.intensity.begin() + static_cast<long>(offset[r]));
      row = ScanRow();  // free as we go
    }
  });
  return out;
}

}  // namespace semioctree::sim
