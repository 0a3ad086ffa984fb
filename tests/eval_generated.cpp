// Evaluation: whole surveys of generated scenes (sim/.../scene_generator.h). For each seed
// of a range, the scene is generated and surveyed as `semioctree survey` does it (the
// scene's scanner and robot, the CLI's planning defaults, the NBV policy), then judged:
// how the survey ended, scans, coverage of the reference, the doors and windows found
// against the room's true ones (precision, recall at IoU ≥ 0.5), the largest pose error,
// registrations failed (and recovered), predicted against achieved overlap, seconds. Prints one
// JSON document (per scene and totals); a line per scene on stderr.
// --check exits 1 when the totals miss the acceptance thresholds
// (docs/generated-scenes.md).
//
//   eval_generated [--seeds 1-50] [--kind any|room|l-shape|hall|floor] [--rooms R] [--size WxD]
//                  [--threads T] [--max-scans N] [--cache DIR] [--check]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "planning_options.h"
#include "semioctree/sim/coverage.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene_generator.h"
#include "semioctree/sim_platform/opening_match.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/survey.h"
#include "semioctree/timing.h"

using namespace semioctree;
using nlohmann::json;

namespace {

struct Options {
  std::string seeds = "1-50";
  std::string kind = "any";
  int rooms = 0;
  std::string size;  // a floor's WxD
  unsigned threads = 0;
  int max_scans = 10;
  std::string cache;
  bool check = false;
  double min_coverage = 90.0, mean_coverage = 96.0, min_precision = 0.95, min_recall = 0.95;
};

// "A-B" or "N" → [first, last].
std::pair<std::uint64_t, std::uint64_t> seed_range(const std::string& text) {
  std::size_t used = 0;
  try {
    const std::size_t dash = text.find('-');
    const std::uint64_t first = std::stoull(text.substr(0, dash), &used);
    if (used != (dash == std::string::npos ? text.size() : dash)) throw std::invalid_argument("");
    std::uint64_t last = first;
    if (dash != std::string::npos) {
      last = std::stoull(text.substr(dash + 1), &used);
      if (used != text.size() - dash - 1) throw std::invalid_argument("");
    }
    if (last < first) throw std::invalid_argument("");
    return {first, last};
  } catch (const std::exception&) {
    throw std::invalid_argument("--seeds " + text + ": expected A-B (A ≤ B) or N");
  }
}

struct SceneResult {
  json record;
  bool finished = false;  // ended by the stop percentage, without error
  double coverage = 0;
  std::size_t detections = 0, truths = 0, matched = 0;
  std::size_t registration_failures = 0;
  std::vector<double> overlap_differences;  // predicted - achieved, per registered scan
};

SceneResult evaluate(std::uint64_t seed, sim::GeneratedKind asked, const Options& o) {
  const auto t0 = Clock::now();
  const sim::GeneratedKind kind = sim::resolve_generated_kind(seed, asked);
  SceneResult r;
  json& j = r.record;
  j["seed"] = seed;
  j["kind"] = sim::to_string(kind);
  try {
    sim::FloorRequest floor;
    floor.rooms = o.rooms;
    if (!o.size.empty()) std::tie(floor.width, floor.depth) = sim::floor_size_from_string(o.size);
    const sim::Scene scene = sim::generate_scene(seed, kind, floor);
    j["name"] = scene.name;
    j["robot_radius"] = scene.robot.radius;
    j["scanner_height"] = scene.scanner.height;
    j["room_height"] = scene.walls.front().z1;
    j["elevation_deg"] = {scene.scanner.elevation_min_deg, scene.scanner.elevation_max_deg};
    bool ceiling = false;
    for (const sim::Slab& slab : scene.slabs)
      ceiling = ceiling || slab.z0 == scene.walls.front().z1;
    j["ceiling"] = ceiling;
    const sim::GroundTruth truth(scene);
    const sim::FloorPlan plan = truth.floor_plan(0.05);
    if (!plan.in_survey_area(scene.robot.start) || !truth.standing_free(scene.robot.start))
      throw std::runtime_error("the robot's start is not on free floor in the survey area");

    SurveyParams p;
    sim_platform::apply_scene(scene, p);
    cli::PlanningOptions planning;  // the CLI's defaults
    planning.threads = o.threads;
    cli::apply_planning_options(planning, p);
    p.max_scans = std::size_t(o.max_scans);
    const sim::CoverageReference ref = sim::load_or_compute_coverage_reference(
        truth, o.cache.empty() ? sim::default_cache_dir() : o.cache, 0.5, 0.02, o.threads);
    sim::CoverageAccumulator coverage(ref);
    sim_platform::SimulatedPlatform platform(
        scene, seed, o.threads,
        [&coverage, &o](const Cloud& points, const Eigen::Isometry3d& to_world) {
          sim_platform::add_to_coverage(coverage, points, to_world, o.threads);
        });
    p.may_stand = platform.survey_area_rule();
    BestScorePolicy policy;
    Survey survey(p);
    const SurveyOutcome outcome = survey.run(platform, policy);
    j["stopped_because"] = to_string(outcome.stopped_because);
    if (!outcome.error.empty()) j["error"] = outcome.error;
    j["scans"] = survey.records().size();
    r.registration_failures = outcome.registration_failures.size();
    j["registration_failures"] = r.registration_failures;  // recovered ones and a last one
    json overlaps = json::array();  // [predicted, achieved] of each scan registered by ICP
    for (const ScanRecord& rec : survey.records())
      if (rec.predicted_overlap && rec.registration) {
        overlaps.push_back({*rec.predicted_overlap, rec.registration->icp.overlap});
        r.overlap_differences.push_back(*rec.predicted_overlap - rec.registration->icp.overlap);
      }
    j["overlap_predicted_achieved"] = overlaps;
    r.finished = outcome.stopped_because == StopReason::kStopPercentage;
    if (!survey.records().empty()) {
      const ScanRecord& last = survey.records().back();
      if (last.stop_percent()) j["stop_percent"] = *last.stop_percent();
      const CandidateReport& c = last.nbv.candidate_report;  // why none was feasible
      j["last_candidates"] = {
          {"grid_points", c.grid_points},           {"not_empty", c.not_empty},
          {"cylinder_blocked", c.cylinder_blocked}, {"unreachable", c.unreachable},
          {"already_scanned", c.already_scanned},   {"feasible", c.feasible}};
    }

    if (!survey.records().empty() && survey.records().back().scope == SurveyScope::kFloor) {
      // The scene's rooms (the floor plan's, inside the survey area) against the map's.
      std::set<int> true_rooms;
      for (std::size_t i = 0; i < plan.room.size(); ++i)
        if (plan.survey[i] && plan.room[i] >= 0) true_rooms.insert(plan.room[i]);
      std::size_t complete = 0;
      for (const RoomStatus& room : survey.records().back().rooms)
        complete += room.state == RoomState::kComplete;
      // The scene's rooms some scan stood in (its true position).
      std::set<int> stood_in;
      for (const sim_platform::ScanTruth& t : platform.truths()) {
        const int room = plan.room_at(t.scanner_to_world.translation().head<2>());
        if (true_rooms.count(room)) stood_in.insert(room);
      }
      j["rooms"] = {{"in_scene", true_rooms.size()},
                    {"stood_in", stood_in.size()},
                    {"found", survey.records().back().rooms.size()},
                    {"complete", complete}};
    }
    j["path_m"] = outcome.path_m;
    r.coverage = coverage.count().percent;
    j["coverage_percent"] = r.coverage;

    double max_m = 0, max_deg = 0;
    for (const sim_platform::ScanTruth& t : platform.truths())
      max_m = std::max(max_m, t.pose_error_m), max_deg = std::max(max_deg, t.pose_error_deg);
    j["pose_error"] = {{"max_m", max_m}, {"max_deg", max_deg}};

    // A room's own openings; every opening of a floor (those of the outside ring: none).
    const std::vector<sim::OpeningRect> truths =
        kind == sim::GeneratedKind::floor
            ? sim::opening_rects(scene)
            : sim_platform::openings_of_room(truth, plan, plan.start_room);
    const sim_platform::OpeningsMatch m = sim_platform::match_openings(
        survey.map().openings(), truths, platform.survey_to_world().inverse());
    // In view: the hole's centre seen from some scan's true optical centre.
    std::size_t in_view = 0;
    for (const sim::OpeningRect& g : truths) {
      const Eigen::Vector3d c = 0.25 * (g.corners[0] + g.corners[1] + g.corners[2] + g.corners[3]);
      bool seen = false;
      for (const sim_platform::ScanTruth& t : platform.truths())
        seen = seen || truth.segment_free(t.scanner_to_world.translation(), c);
      in_view += seen;
    }
    json missed = json::array(), false_positives = json::array();
    for (std::size_t i = 0; i < truths.size(); ++i)
      if (m.truth_iou[i] == 0)
        missed.push_back(std::string(sim::to_string(truths[i].kind)) + " walls[" +
                         std::to_string(truths[i].wall) + "].openings[" +
                         std::to_string(truths[i].index) + "]");
    for (std::size_t i = 0; i < m.detections; ++i)
      if (m.detection_iou[i] == 0) {
        const DetectedOpening& d = survey.map().openings()[i];
        const Eigen::Vector3d c =
            platform.survey_to_world() *
            (0.25 * (d.corners[0] + d.corners[1] + d.corners[2] + d.corners[3]));
        char at[160];
        std::snprintf(at, sizeof at, "%s at (%.2f, %.2f, %.2f) %.2f x %.2f", to_string(d.kind),
                      c.x(), c.y(), c.z(), d.width, d.height);
        false_positives.push_back(at);
      }
    j["openings"] = {{"truths", m.truths},         {"in_view", in_view},
                     {"detections", m.detections}, {"matched", m.matched},
                     {"precision", m.precision},   {"recall", m.recall},
                     {"missed", missed},           {"false_positives", false_positives}};
    r.detections = m.detections, r.truths = m.truths, r.matched = m.matched;
  } catch (const std::exception& e) {
    r.finished = false;
    j["stopped_because"] = "error";
    j["error"] = e.what();
  }
  j["finished"] = r.finished;
  j["seconds"] = seconds_since(t0);         // the coverage reference included (unless cached)
  j["peak_rss_mib"] = peak_resident_mib();  // of the process so far (all scenes before too)
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  map_large_allocations();  // as the CLI does: the same peak memory
  Options o;
  CLI::App app{
      "Surveys of generated scenes: per scene and in total, how the survey ended, scans, "
      "coverage of the reference, openings precision/recall, pose error, seconds (JSON on "
      "stdout, a line per scene on stderr)."};
  app.add_option("--seeds", o.seeds, "seeds A-B (inclusive) or one seed N")->capture_default_str();
  app.add_option("--kind", o.kind,
                 "scene kind: any (room, l-shape or hall, drawn from each seed), room, l-shape, "
                 "hall, floor")
      ->check(CLI::IsMember(sim::generated_kind_names()))
      ->capture_default_str();
  app.add_option("--rooms", o.rooms, "--kind floor: rooms of each floor (default: drawn, 3-10)")
      ->check(CLI::Range(sim::kMinFloorRooms, sim::kMaxFloorRooms));
  app.add_option("--size", o.size,
                 "--kind floor: each floor's outline WxD in metres (e.g. 60x45), cut into rooms");
  app.add_option("--threads", o.threads, "worker threads of each survey (0: one per core)")
      ->check(CLI::Range(0u, 256u))
      ->capture_default_str();
  app.add_option("--max-scans", o.max_scans, "scan budget of each survey (as survey --max-scans)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--cache", o.cache,
                 "directory of cached coverage references (default: the survey command's)");
  app.add_flag("--check", o.check,
               "exit 1 unless every survey ended by the stop percentage without error, each "
               "coverage ≥ --min-coverage, their mean ≥ --mean-coverage, and openings "
               "precision ≥ --min-precision and recall ≥ --min-recall (over all scenes)");
  app.add_option("--min-coverage", o.min_coverage, "--check: lowest coverage of a scene, %")
      ->capture_default_str();
  app.add_option("--mean-coverage", o.mean_coverage, "--check: lowest mean coverage, %")
      ->capture_default_str();
  app.add_option("--min-precision", o.min_precision, "--check: lowest openings precision")
      ->capture_default_str();
  app.add_option("--min-recall", o.min_recall, "--check: lowest openings recall")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const auto [first, last] = seed_range(o.seeds);
    const sim::GeneratedKind kind = sim::generated_kind_from_string(o.kind);
    const auto t0 = Clock::now();
    json scenes = json::array();
    std::size_t finished = 0, detections = 0, truths = 0, matched = 0, failures = 0;
    std::vector<double> differences;
    double coverage_sum = 0, coverage_min = std::numeric_limits<double>::infinity();
    json stopped = json::object();
    for (std::uint64_t seed = first; seed <= last; ++seed) {
      const SceneResult r = evaluate(seed, kind, o);
      const json& j = r.record;
      finished += r.finished;
      coverage_sum += r.coverage;
      coverage_min = std::min(coverage_min, r.coverage);
      detections += r.detections, truths += r.truths, matched += r.matched;
      failures += r.registration_failures;
      differences.insert(differences.end(), r.overlap_differences.begin(),
                         r.overlap_differences.end());
      const std::string why = j["stopped_because"];
      stopped[why] = stopped.value(why, 0) + 1;
      std::fprintf(stderr, "%s\n", j.dump().c_str());
      std::fflush(stderr);
      scenes.push_back(j);
    }
    const std::size_t n = scenes.size();
    const double mean = coverage_sum / double(n);
    const double precision = detections ? double(matched) / double(detections) : 1.0;
    const double recall = truths ? double(matched) / double(truths) : 1.0;
    double abs_sum = 0, signed_sum = 0;
    for (double d : differences) abs_sum += std::abs(d), signed_sum += d;
    const double scans_compared = std::max<double>(1.0, double(differences.size()));
    const bool pass = finished == n && coverage_min >= o.min_coverage && mean >= o.mean_coverage &&
                      precision >= o.min_precision && recall >= o.min_recall;
    const json doc = {{"seeds", o.seeds},
                      {"kind", o.kind},
                      {"scenes", scenes},
                      {"totals",
                       {{"scenes", n},
                        {"finished", finished},
                        {"stopped_because", stopped},
                        {"coverage_mean_percent", mean},
                        {"coverage_min_percent", coverage_min},
                        {"openings",
                         {{"truths", truths},
                          {"detections", detections},
                          {"matched", matched},
                          {"precision", precision},
                          {"recall", recall}}},
                        {"registration_failures", failures},
                        {"overlap",
                         {{"scans", differences.size()},
                          {"mean_abs_difference", abs_sum / scans_compared},
                          {"mean_difference", signed_sum / scans_compared}}},
                        {"seconds", seconds_since(t0)},
                        {"thresholds_met", pass}}}};
    std::printf("%s\n", doc.dump(2).c_str());
    if (o.check && !pass) {
      std::fprintf(stderr,
                   "eval_generated: thresholds missed: %zu of %zu finished, coverage mean %.2f "
                   "%% (≥ %.1f), min %.2f %% (≥ %.1f), openings precision %.3f (≥ %.2f), recall "
                   "%.3f (≥ %.2f)\n",
                   finished, n, mean, o.mean_coverage, coverage_min, o.min_coverage, precision,
                   o.min_precision, recall, o.min_recall);
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "eval_generated: error: %s\n", e.what());
    return 1;
  }
}
