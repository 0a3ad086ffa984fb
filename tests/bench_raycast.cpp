// Rays per second of the synthetic scanner on the lab scene at 0.1° x 0.1° (about 5.4 M
// rays per scan), with 1 thread and with all threads (one per hardware thread). A benchmark,
// not a test: run it in Release.
//   bench_raycast [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <memory>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "support/bench_common.h"

namespace {

using namespace semioctree::sim;

struct Lab {
  Scene scene = load_scene_json(SEMIOCTREE_SOURCE_DIR "/sim/scenes/lab.scene.json");
  SceneTriangles triangles = tessellate(scene);
  std::unique_ptr<RayCaster> caster = make_ray_caster(triangles);
};

const Lab& lab() {
  static const Lab instance;
  return instance;
}

// Whole scans: ray generation, casting, noise and point output.
void BM_ScanLab(benchmark::State& state) {
  const Lab& l = lab();
  ScannerConfig config = l.scene.scanner;
  config.azimuth_step_deg = 0.1;
  config.elevation_step_deg = 0.1;
  ScanOptions options;
  options.threads = static_cast<unsigned>(state.range(0));
  std::uint64_t rays = 0;
  for (auto _ : state) {
    const Scan s = scan(*l.caster, config, {5.2, 3.6, 0.0}, options);
    rays += s.rays_cast;
    benchmark::DoNotOptimize(s.points.data());
  }
  state.counters["rays/s"] =
      benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
  state.counters["rays/s/thread"] = benchmark::Counter(
      static_cast<double>(rays) / static_cast<double>(state.range(0)), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ScanLab)
    ->Apply([](benchmark::internal::Benchmark* b) {
      for (unsigned threads : semioctree::bench::thread_counts()) b->Arg(int(threads));
    })
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// The ray caster alone, one row of 3600 rays at a time as the scanner calls it.
void BM_IntersectRows(benchmark::State& state) {
  const Lab& l = lab();
  const ScanGrid grid = scan_grid([] {
    ScannerConfig c;
    c.azimuth_step_deg = 0.1;
    c.elevation_step_deg = 0.1;
    return c;
  }());
  std::vector<std::vector<Ray>> rows(grid.rows, std::vector<Ray>(grid.cols));
  for (std::uint32_t r = 0; r < grid.rows; ++r)
    for (std::uint32_t c = 0; c < grid.cols; ++c) {
      rows[r][c].origin = Eigen::Vector3f(5.2f, 3.6f, 1.5f);
      rows[r][c].direction = scan_direction(grid, r, c).cast<float>();
    }
  std::vector<RayHit> hits(grid.cols);
  std::uint64_t rays = 0;
  for (auto _ : state) {
    for (const auto& row : rows) {
      l.caster->intersect(row.data(), hits.data(), row.size());
      rays += row.size();
    }
    benchmark::DoNotOptimize(hits.data());
  }
  state.counters["rays/s"] =
      benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IntersectRows)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
