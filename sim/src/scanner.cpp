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

void for_each_scan_row(const RayCaster& caster, const ScannerConfig& config, const Pose2& pose,
                       const ScanOptions& options, Scan& header,
                       const std::function<void(std::uint32_t, ScanRow&&)>& take_row) {
  header = Scan();
  header.pose = pose;
  header.sensor_height = config.height;
  header.grid = scan_grid(config);
  const ScanGrid g = header.grid;
  header.rays_cast = static_cast<std::uint64_t>(g.rows) * g.cols;

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

  // Rows are cast in parallel a batch at a time and handed over in order between
  // batches: only one batch is held here, whatever the scan's size.
  const unsigned threads = std::min<unsigned>(detail::thread_count(options.threads), g.rows);
  const std::uint32_t batch_rows = 32 * threads;
  std::vector<ScanRow> batch(batch_rows);
  for (std::uint32_t first = 0; first < g.rows; first += batch_rows) {
    const std::uint32_t end = std::min(g.rows, first + batch_rows);
    std::atomic<std::uint32_t> next_row{first};
    detail::run_on_threads(threads, [&](bool) {
      std::vector<Ray> rays(g.cols);
      std::vector<RayHit> hits(g.cols);
      std::vector<float> noise(g.cols + 1, 0.0f);
      for (std::uint32_t r = next_row++; r < end; r = next_row++) {
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
        ScanRow& row = batch[r - first];
        row.points.reserve(g.cols);
        if (options.with_grid_indices) row.col.reserve(g.cols);
        if (options.with_intensity) row.intensity.reserve(g.cols);
        for (std::uint32_t c = 0; c < g.cols; ++c) {
          if (!hits[c].hit) continue;
          const double range =
              static_cast<double>(hits[c].distance) + static_cast<double>(noise[c]);
          if (range < config.min_range || range > config.max_range) continue;
          row.points.emplace_back(static_cast<float>(ce * cos_az[c] * range),
                                  static_cast<float>(ce * sin_az[c] * range),
                                  static_cast<float>(se * range));
          if (options.with_intensity)
            row.intensity.push_back(std::abs(rays[c].direction.dot(hits[c].normal)));
          if (options.with_grid_indices) row.col.push_back(c);
        }
      }
    });
    for (std::uint32_t r = first; r < end; ++r) {
      take_row(r, std::move(batch[r - first]));
      batch[r - first] = ScanRow();
    }
    if (options.progress) options.progress(end, g.rows);
  }
}

Scan scan(const RayCaster& caster, const ScannerConfig& config, const Pose2& pose,
          const ScanOptions& options) {
  const ScanGrid g = scan_grid(config);
  // Room for every ray: the pages of rays without a return are never touched.
  const std::size_t rays = static_cast<std::size_t>(g.rows) * g.cols;
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;
  std::vector<std::uint32_t> row_of, col_of;
  points.reserve(rays);
  if (options.with_grid_indices) {
    row_of.reserve(rays);
    col_of.reserve(rays);
  }
  if (options.with_intensity) intensity.reserve(rays);
  Scan out;
  for_each_scan_row(caster, config, pose, options, out, [&](std::uint32_t r, ScanRow&& row) {
    points.insert(points.end(), row.points.begin(), row.points.end());
    if (options.with_grid_indices) {
      col_of.insert(col_of.end(), row.col.begin(), row.col.end());
      row_of.insert(row_of.end(), row.col.size(), r);
    }
    if (options.with_intensity)
      intensity.insert(intensity.end(), row.intensity.begin(), row.intensity.end());
  });
  out.points = std::move(points);
  out.intensity = std::move(intensity);
  out.row = std::move(row_of);
  out.col = std::move(col_of);
  return out;
}

}  // namespace semioctree::sim
