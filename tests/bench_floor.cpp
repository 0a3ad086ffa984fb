// Benchmark: a survey at floor scale. Generates a floor of the asked size (default 60 × 45 m,
// one room per 20 m², sim/.../scene_generator.h); computes its coverage reference in a
// child process (timed, its peak memory from wait4) into a fresh cache directory; then
// loads it and surveys the floor as `semioctree survey` does with a cached reference (the
// scene's robot and scanner, the CLI's planning defaults, coverage measured scan by scan)
// for a budget of scans. Prints one JSON document: the floor, the reference (seconds,
// samples, spacing, positions, peak MiB), each scan's stage seconds, the NBV's largest and
// mean seconds, the survey's peak MiB (the reference it holds included), how it ended.
// Progress on stderr. The targets it checks (docs/benchmarks.md): NBV ≤ 3 s a scan,
// reference ≤ 2 minutes, survey peak ≤ 1.5 GB.
//
//   bench_floor [--size 60x45] [--seed 1] [--rooms R] [--scans 30] [--threads T]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "semioctree/sim/coverage.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene_generator.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/survey.h"
#include "semioctree/timing.h"
#include "support/cli_survey_params.h"

using namespace semioctree;
using nlohmann::json;

namespace {

// A line on stderr per scan planned.
class Progress : public SurveyObserver {
 public:
  void stage_done(SurveyStage stage, const ScanRecord& r) override {
    if (stage != SurveyStage::kPlanned) return;
    std::fprintf(stderr,
                 "bench_floor: scan %zu: NBV %.2f s, scan %.2f s, %zu rooms, peak %.0f MiB\n",
                 r.index, r.seconds.nbv, r.seconds.total, r.rooms.size(), peak_resident_mib());
  }
};

// Computes the reference of `scene` into `cache` in a child process; its wall seconds and
// peak resident MiB. Throws if the child fails.
std::pair<double, double> reference_in_child(const sim::Scene& scene, const std::string& cache,
                                             unsigned threads) {
  const auto t0 = Clock::now();
  const pid_t child = fork();
  if (child < 0) throw std::runtime_error("fork failed");
  if (child == 0) {
    int code = 0;
    try {
      const sim::GroundTruth truth(scene);
      const sim::CoverageReference ref =
          sim::load_or_compute_coverage_reference(truth, cache, 0.5, 0.02, threads);
      code = ref.cache_file.empty() ? 2 : 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_floor: coverage reference: %s\n", e.what());
      code = 1;
    }
    std::_Exit(code);
  }
  int status = 0;
  rusage usage{};
  if (wait4(child, &status, 0, &usage) != child || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("the coverage reference's process failed");
  return {seconds_since(t0), double(usage.ru_maxrss) / 1024.0};
}

}  // namespace

int main(int argc, char** argv) {
  map_large_allocations();  // as the CLI does: the same peak memory
  std::string size = "60x45";
  std::uint64_t seed = 1;
  int rooms = 0, scans = 30;
  unsigned threads = 0;
  CLI::App app{
      "A survey at floor scale: a generated floor of --size, its coverage reference "
      "(computed afresh in a child process: seconds, peak memory), then --scans scans of the "
      "survey (NBV seconds, peak memory); JSON on stdout, progress on stderr."};
  app.add_option("--size", size, "the floor inside the outer walls, WxD metres")
      ->capture_default_str();
  app.add_option("--seed", seed, "the floor's seed (and the scanner noise's)")
      ->capture_default_str();
  app.add_option("--rooms", rooms, "rooms of the floor (default: one per 20 m²)")
      ->check(CLI::Range(sim::kMinFloorRooms, sim::kMaxFloorRooms));
  app.add_option("--scans", scans, "scan budget of the survey")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (0: one per core)")
      ->check(CLI::Range(0u, 256u))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    sim::FloorRequest request;
    request.rooms = rooms;
    std::tie(request.width, request.depth) = sim::floor_size_from_string(size);
    auto t0 = Clock::now();
    const sim::Scene scene = sim::generate_scene(seed, sim::GeneratedKind::floor, request);
    std::size_t doors = 0, windows = 0;
    for (const sim::Wall& w : scene.walls)
      for (const sim::Opening& op : w.openings)
        ++(op.kind == sim::OpeningKind::door ? doors : windows);
    json doc = {{"benchmark", "floor"},
                {"floor",
                 {{"name", scene.name},
                  {"size_m", {request.width, request.depth}},
                  {"walls", scene.walls.size()},
                  {"doors", doors},
                  {"windows", windows},
                  {"boxes", scene.boxes.size()},
                  {"cylinders", scene.cylinders.size()},
                  {"robot_radius", scene.robot.radius},
                  {"description", scene.description},
                  {"seconds", seconds_since(t0)}}},
                {"threads", threads}};
    std::fprintf(stderr, "bench_floor: %s\n", scene.description.c_str());

    // The reference in a child (before this process starts any thread), cached in a
    // directory of its own, then loaded here as the survey command loads a cached one.
    const std::filesystem::path cache =
        std::filesystem::temp_directory_path() / ("bench_floor-" + std::to_string(getpid()));
    std::filesystem::create_directories(cache);
    struct RemoveCache {
      std::filesystem::path dir;
      ~RemoveCache() {
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
      }
    } remove_cache{cache};
    const auto [reference_seconds, reference_mib] = reference_in_child(scene, cache, threads);
    const sim::GroundTruth truth(scene);
    const sim::CoverageReference ref =
        sim::load_or_compute_coverage_reference(truth, cache, 0.5, 0.02, threads);
    if (!ref.from_cache) throw std::runtime_error("the reference was not read from the cache");
    doc["reference"] = {{"seconds", reference_seconds},  {"peak_mib", reference_mib},
                        {"samples", ref.sample_count},   {"sample_spacing", ref.sample_spacing},
                        {"visible", ref.visible.size()}, {"positions", ref.positions.size()},
                        {"load_seconds", ref.seconds}};
    std::fprintf(stderr,
                 "bench_floor: coverage reference %.1f s, %.0f MiB, %zu of %zu samples at %g m "
                 "visible\n",
                 reference_seconds, reference_mib, ref.visible.size(), ref.sample_count,
                 ref.sample_spacing);

    SurveyParams p = testing::cli_survey_params(scene, threads, std::size_t(scans));
    sim::CoverageAccumulator coverage(ref);
    sim_platform::SimulatedPlatform platform(
        scene, seed, threads,
        [&coverage, threads](const Cloud& points, const Eigen::Isometry3d& to_world) {
          sim_platform::add_to_coverage(coverage, points, to_world, threads);
        });
    p.may_stand = platform.survey_area_rule();
    BestScorePolicy policy;
    Progress progress;
    Survey survey(p, &progress);
    t0 = Clock::now();
    const SurveyOutcome outcome = survey.run(platform, policy);
    json per_scan = json::array();
    double nbv_max = 0, nbv_sum = 0;
    for (const ScanRecord& r : survey.records()) {
      per_scan.push_back({{"preprocess", r.seconds.preprocess},
                          {"registration", r.seconds.registration},
                          {"returns", r.seconds.returns},
                          {"occupancy", r.seconds.occupancy},
                          {"openings", r.seconds.openings},
                          {"occlusion", r.seconds.occlusion},
                          {"nbv", r.seconds.nbv},
                          {"total", r.seconds.total},
                          {"occlusion_segments",
                           {{"new_space", r.update.new_space.segments},
                            {"retest", r.update.retest.segments},
                            {"through_openings", r.update.through_openings.segments}}},
                          {"rooms", r.rooms.size()}});
      nbv_max = std::max(nbv_max, r.seconds.nbv);
      nbv_sum += r.seconds.nbv;
    }
    const std::size_t n = survey.records().size();
    doc["survey"] = {{"scans", n},
                     {"stopped_because", to_string(outcome.stopped_because)},
                     {"error", outcome.error},
                     {"seconds", seconds_since(t0)},
                     {"nbv_seconds_max", nbv_max},
                     {"nbv_seconds_mean", n ? nbv_sum / double(n) : 0.0},
                     {"path_m", outcome.path_m},
                     {"coverage_percent", coverage.count().percent},
                     {"peak_mib", peak_resident_mib()},  // this process: the survey
                     {"per_scan_seconds", per_scan}};
    std::printf("%s\n", doc.dump(2).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_floor: error: %s\n", e.what());
    return 1;
  }
}
