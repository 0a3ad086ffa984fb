// `semioctree coverage-bound`: how much of a scene's reference surface a survey of k
// scans from the robot's start could cover at best, found with perfect knowledge (every
// position of a grid is scanned by the simulator). A yardstick for the NBV planner, which
// only knows what it has scanned so far.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "option_checks.h"
#include "progress_line.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/sim/coverage.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

namespace {

struct CoverageBoundArgs {
  std::string scene;
  double spacing = 0.25;
  int max_scans = 6;
  std::string out;
  std::string cache;
  unsigned threads = 0;
  std::uint64_t seed = 1;
};

nlohmann::json plan_json(const sim::CoveragePlan& plan,
                         const std::vector<Eigen::Vector3d>& positions) {
  nlohmann::json views = nlohmann::json::array();
  for (std::size_t v : plan.views) views.push_back({positions[v].x(), positions[v].y()});
  return {{"coverage_percent", plan.percent}, {"positions", views}};
}

void run_coverage_bound(const CoverageBoundArgs& a) {
  if (a.max_scans < 1) throw std::invalid_argument("--max-scans must be at least 1");
  check_outputs_spare_inputs({{"--scene", a.scene}}, {{"--out", a.out}});
  const auto t0 = Clock::now();
  const sim::Scene scene = sim::load_scene(a.scene);
  const sim::GroundTruth truth(scene);
  const std::string cache = a.cache.empty() ? sim::default_cache_dir() : a.cache;
  remove_stale_temporaries(cache);  // the simulator's cache writer leaves them when killed
  const sim::CoverageReference ref = sim::load_or_compute_coverage_reference(truth, cache);
  std::printf("reference: %zu surface samples seen from %zu positions 0.5 m apart%s\n",
              ref.points.size(), ref.positions.size(), ref.from_cache ? " (from the cache)" : "");

  // Scan positions: the grid of the reference's rule at --spacing, which holds the start.
  const std::vector<Eigen::Vector3d> positions = sim::coverage_grid_positions(truth, a.spacing);
  if (positions.empty()) throw std::runtime_error("no position where the robot can stand");
  const Eigen::Vector2d start = scene.robot.start;
  std::size_t first = 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const double d = (positions[v].head<2>() - start).norm();
    if (d < nearest) nearest = d, first = v;
  }
  if (nearest > 1e-6)
    throw std::runtime_error("the robot's start is not a position where it can stand");

  std::vector<std::vector<bool>> covered;
  covered.reserve(positions.size());
  sim::ScanOptions so;
  so.seed = a.seed;
  so.threads = a.threads;
  so.with_intensity = false;
  so.with_grid_indices = false;
  ProgressLine progress(stdout);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const sim::Scan s =
        sim::scan(truth.ray_caster(), scene.scanner, {positions[v].x(), positions[v].y(), 0.0}, so);
    const Eigen::Isometry3d to_world = s.sensor_to_world();
    std::vector<Eigen::Vector3f> world;
    world.reserve(s.points.size());
    for (const auto& p : s.points) world.push_back((to_world * p.cast<double>()).cast<float>());
    covered.push_back(sim::covered_samples(ref, world));
    if ((v + 1) % 20 == 0 || v + 1 == positions.size()) {
      progress.update("scanned " + std::to_string(v + 1) + " of " +
                      std::to_string(positions.size()) + " positions");
    }
  }
  progress.finish();

  nlohmann::json plans = nlohmann::json::array();
  std::printf("%6s  %14s  %14s\n", "scans", "greedy %", "local search %");
  std::size_t max_scans = std::size_t(a.max_scans);
  if (max_scans > positions.size()) {
    std::printf("plans of at most %zu scans: the grid has %zu positions\n", positions.size(),
                positions.size());
    max_scans = positions.size();
  }
  for (std::size_t k = 1; k <= max_scans; ++k) {
    const sim::CoveragePlan greedy = sim::greedy_coverage_plan(covered, first, k);
    if (greedy.views.size() < k) {
      std::printf("plans end at %zu scan%s: no position adds a surface sample to them (%.2f %%)\n",
                  k - 1, k - 1 == 1 ? "" : "s", greedy.percent);
      break;
    }
    const sim::CoveragePlan best = sim::improve_coverage_plan(covered, greedy);
    std::printf("%6zu  %14.2f  %14.2f\n", k, greedy.percent, best.percent);
    plans.push_back({{"scans", k},
                     {"greedy", plan_json(greedy, positions)},
                     {"local_search", plan_json(best, positions)}});
  }
  const double seconds = seconds_since(t0);
  std::printf("%zu positions %.2f m apart, %.1f s\n", positions.size(), a.spacing, seconds);
  if (!a.out.empty()) {
    const nlohmann::json j = {{"scene", a.scene},
                              {"spacing_m", a.spacing},
                              {"positions", positions.size()},
                              {"reference_points", ref.points.size()},
                              {"seed", a.seed},
                              {"plans", plans},
                              {"seconds", seconds}};
    std::ofstream f(a.out);
    if (!(f << j.dump(2) << "\n")) throw std::runtime_error("cannot write " + a.out);
    std::printf("wrote %s\n", a.out.c_str());
  }
}

}  // namespace

void add_coverage_bound_command(CLI::App& app) {
  auto a = std::make_shared<CoverageBoundArgs>();
  CLI::App* cmd = app.add_subcommand(
      "coverage-bound",
      "Best coverage a survey of 1..N scans from the robot's start could reach, found with "
      "perfect knowledge: every position of a grid over the survey area is scanned by the "
      "simulator, then the plans are chosen greedily (each scan the one that adds most) and "
      "improved by local search (swap one scan while the union grows). Coverage is that of "
      "`survey` (reference surface samples within 3 cm of a point). A yardstick for the NBV "
      "planner, which only knows what it has scanned. One simulated scan per position: the lab "
      "at 0.25 m (645 positions) takes about 9 minutes on 2 cores.");
  cmd->add_option("--scene", a->scene, "scene file (.scene.json)")->required();
  cmd->add_option("--spacing", a->spacing, "spacing of the grid of scan positions, m")
      ->check(finite_in(0.05, 10))
      ->capture_default_str();
  cmd->add_option("--max-scans", a->max_scans,
                  "plans of 1 to this many scans (at most the grid's position count)")
      ->capture_default_str();
  cmd->add_option("--out", a->out, "also write the plans to this JSON file");
  cmd->add_option("--cache", a->cache,
                  "directory of cached coverage references (default: $XDG_CACHE_HOME/semioctree "
                  "or ~/.cache/semioctree)");
  cmd->add_option("--seed", a->seed, "range noise seed of the simulated scans")
      ->check(seed_value())
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "worker threads (0: one per core; at most 256)")
      ->check(thread_count())
      ->capture_default_str();
  cmd->callback([a] { run_coverage_bound(*a); });
}

}  // namespace semioctree::cli
