// `semioctree survey --scene FILE --out DIR ...`: the autonomous survey of a
// scene with the simulated robot and scanner: options → the survey stage (with the
// simulated platform and the chosen policy) → survey.json, report.html, scan_NN/ and the
// coverage.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands.h"
#include "option_checks.h"
#include "planning_options.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/outputs.h"
#include "semioctree/sim/coverage.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/timing.h"
#include "sim_input.h"
#include "survey_output.h"

namespace semioctree::cli {

namespace {

using sim_platform::OraclePolicy;
using sim_platform::ScanTruth;
using sim_platform::SimulatedPlatform;

// The reference samples a survey missed, for CloudCompare beside cloud.ply: an RGB colour
// (orange: in view of a scan but sampled too sparsely, blue: hidden from every scan) and
// `hidden` (0 or 1) to filter on.
void write_missed_samples_ply(const sim::CoverageReference& ref, const sim::MissedSamples& missed,
                              const std::string& path) {
  const std::size_t in_view = missed.in_view_samples.size();
  write_ply(path, in_view + missed.hidden_samples.size(),
            {"semioctree reference samples a survey missed", true, "hidden"}, [&](std::size_t i) {
              const bool hidden = i >= in_view;
              const Eigen::Vector3f p =
                  ref.points
                      .at(hidden ? missed.hidden_samples[i - in_view] : missed.in_view_samples[i])
                      .cast<float>();
              return hidden ? PlyVertex{p.x(), p.y(), p.z(), 30, 90, 255, 1}
                            : PlyVertex{p.x(), p.y(), p.z(), 255, 140, 0, 0};
            });
}

struct SurveyOptions {
  std::string scene;
  std::string out;
  PlanningOptions plan;
  int max_scans = 10;
  int max_recoveries = 3;
  double max_path = 0;  // m; 0: no path budget
  bool homogeneous = false;
  std::uint64_t seed = 1;
  // "random": a random feasible candidate (the baseline); "oracle": the feasible
  // candidate that adds the most surface, known from the scene (the yardstick).
  std::string policy = "nbv";
  std::vector<double> start;  // X,Y: replaces the scene's robot start
  // Replace the scene's platform (unset: the scene's values).
  std::optional<double> robot_radius, scanner_height, elevation_min, elevation_max, min_range,
      max_range;
  std::string cache;
  bool skip_coverage = false;
};

// survey.json lists the scene elements with the most missed samples, not all of them.
constexpr std::size_t kMissedPartsListed = 8;

// The scene's surface covered by the survey as it goes: each placed scan's points flag the
// reference samples near them (survey.json's coverage), and are not kept.
class SurveyCoverage {
 public:
  SurveyCoverage(const sim::GroundTruth& truth, const std::string& cache_dir, unsigned threads)
      : reference_(sim::load_or_compute_coverage_reference(truth, cache_dir)),
        accumulator_(reference_),
        threads_(threads) {}

  // SimulatedPlatform's PlacedPoints.
  void add(const Cloud& points, const Eigen::Isometry3d& scanner_to_world) {
    const auto t0 = Clock::now();
    sim_platform::add_to_coverage(accumulator_, points, scanner_to_world, threads_);
    last_seconds_ = seconds_since(t0);
  }

  const sim::CoverageAccumulator& accumulator() const { return accumulator_; }
  double last_seconds() const { return last_seconds_; }  // of the last add

 private:
  sim::CoverageReference reference_;
  sim::CoverageAccumulator accumulator_;
  unsigned threads_;
  double last_seconds_ = 0;
};

// Prints what the simulation knows beside the survey's own output (true poses, pose
// errors, moves, and the surface covered so far when `coverage` is given) and adds it to
// the scans' records.
class SimulatedSurveyOutput : public SurveyOutput {
 public:
  SimulatedSurveyOutput(std::string dir, const SurveyParams& params,
                        const SimulatedPlatform& platform, const SurveyCoverage* coverage)
      : SurveyOutput(std::move(dir), params), platform_(platform), coverage_(coverage) {}

  void scan_taken(std::size_t index, const IncomingScan&) override {
    const ScanTruth& t = platform_.truths().at(index);
    std::printf("scan %zu at (%.3f, %.3f) reported (%.3f, %.3f, %.2f°): %zu points [%.2f s]\n",
                index, t.true_pose.x, t.true_pose.y, t.reported_pose.x, t.reported_pose.y,
                t.reported_pose.yaw_deg, t.points, t.scan_seconds);
    if (t.guess_error_m)
      std::printf("  initial guess (odometry of the leg): %.3f m off the true position\n",
                  *t.guess_error_m);
    std::fflush(stdout);
  }

  void scan_done(const ScanRecord& scan, const SurveyMap& map) override {
    SurveyOutput::scan_done(scan, map);
    const ScanTruth& t = platform_.truths().at(scan.index);
    nlohmann::json& rec = record(scan.index);
    rec["true_pose"] = pose_json(t.scanner_to_world);
    rec["pose_error"] = {{"m", t.pose_error_m}, {"deg", t.pose_error_deg}};
    rec["seconds"]["scan"] = t.scan_seconds;
    if (scan.index > 0)
      std::printf("  pose error after registration: %.1f mm, %.3f°\n", 1000 * t.pose_error_m,
                  t.pose_error_deg);
    if (coverage_) {  // the platform added this scan's points when it was placed
      const double percent = coverage_->accumulator().count().percent;
      rec["coverage_percent"] = percent;
      std::printf("  coverage so far: %.2f %% of the reference surface [%.2f s]\n", percent,
                  coverage_->last_seconds());
    }
    std::fflush(stdout);
  }

  void moved(const ScanRecord& scan, const NextScanChoice& choice,
             const NextScanPolicy& policy) override {
    if (choice.predicted_gain_percent) {
      record(scan.index)["oracle_gain_percent"] = *choice.predicted_gain_percent;
      std::printf("  oracle: (%.3f, %.3f) adds %.2f %% of the reference surface\n",
                  choice.position.x, choice.position.y, *choice.predicted_gain_percent);
    }
    const sim::Pose2& at = platform_.robot().true_pose();
    std::printf("move to the %s (%.3f, %.3f): %.2f m driven so far\n", policy.what(), at.x, at.y,
                platform_.robot().distance_driven());
    std::fflush(stdout);
  }

 private:
  const SimulatedPlatform& platform_;
  const SurveyCoverage* coverage_;  // null: no coverage measured
};

// survey.json's "coverage" of the scene's surfaces by the survey's registered points,
// and coverage_missed.ply.
nlohmann::json coverage_summary(const sim::GroundTruth& truth,
                                const sim::CoverageAccumulator& coverage,
                                const SimulatedPlatform& platform, const std::string& out_dir,
                                unsigned threads) {
  const auto t0 = Clock::now();
  const sim::CoverageReference& ref = coverage.reference();
  const std::vector<bool>& covered = coverage.covered();
  const sim::Coverage c = coverage.count();
  const sim::MissedSamples missed =
      sim::explain_missed_samples(truth, ref, covered, platform.optical_centres(), threads);
  auto percent_of = [&](std::size_t n) {
    return c.reference_points ? 100.0 * double(n) / double(c.reference_points) : 0.0;
  };
  nlohmann::json parts = nlohmann::json::array();
  for (std::size_t k = 0; k < missed.parts.size() && k < kMissedPartsListed; ++k) {
    const sim::MissedPart& mp = missed.parts[k];
    parts.push_back({{"part", mp.label},
                     {"in_view_percent", percent_of(mp.in_view)},
                     {"hidden_percent", percent_of(mp.hidden)}});
  }
  std::printf(
      "coverage: %zu of %zu reference surface samples within 3 cm of a point: %.2f %% "
      "(reference %s) [%.2f s]\n",
      c.covered, c.reference_points, c.percent, ref.from_cache ? "from the cache" : "computed",
      seconds_since(t0));
  std::printf(
      "  missed: %.2f %% in view of a scan but sampled too sparsely there, %.2f %% hidden "
      "from every scan\n",
      percent_of(missed.in_view), percent_of(missed.hidden));
  for (std::size_t k = 0; k < missed.parts.size() && k < 3; ++k)
    std::printf("    %s: %.2f %% in view, %.2f %% hidden\n", missed.parts[k].label.c_str(),
                percent_of(missed.parts[k].in_view), percent_of(missed.parts[k].hidden));
  const std::string missed_ply = (std::filesystem::path(out_dir) / "coverage_missed.ply").string();
  write_missed_samples_ply(ref, missed, missed_ply);
  std::printf("  wrote %s (orange: in view but too sparse, blue: hidden)\n", missed_ply.c_str());
  return {{"reference_points", c.reference_points},
          {"covered", c.covered},
          {"percent", c.percent},
          {"reference_cached", ref.from_cache},
          {"missed",
           {{"in_view", missed.in_view},
            {"in_view_percent", percent_of(missed.in_view)},
            {"hidden", missed.hidden},
            {"hidden_percent", percent_of(missed.hidden)},
            {"parts", parts}}}};
}

// The platform options replace the scene's robot and scanner values; the ranges each
// option takes are checked by CLI11, the pairs here.
void apply_platform_options(const SurveyOptions& o, sim::Scene& scene) {
  sim::ScannerConfig& s = scene.scanner;
  if (o.robot_radius) scene.robot.radius = *o.robot_radius;
  if (o.scanner_height) s.height = *o.scanner_height;
  if (o.elevation_min) s.elevation_min_deg = *o.elevation_min;
  if (o.elevation_max) s.elevation_max_deg = *o.elevation_max;
  if (o.min_range) s.min_range = *o.min_range;
  if (o.max_range) s.max_range = *o.max_range;
  char m[200];
  if (!(s.elevation_max_deg > s.elevation_min_deg)) {
    std::snprintf(m, sizeof m,
                  "--elevation-max (%g°) must be above --elevation-min (%g°), scene's values "
                  "where not given",
                  s.elevation_max_deg, s.elevation_min_deg);
    throw std::invalid_argument(m);
  }
  if (!(s.max_range > s.min_range)) {
    std::snprintf(m, sizeof m,
                  "--max-range (%g m) must be above --min-range (%g m), scene's values where "
                  "not given",
                  s.max_range, s.min_range);
    throw std::invalid_argument(m);
  }
}

void run_survey(const SurveyOptions& o) {
  const auto t_start = Clock::now();
  if (o.policy == "oracle" && o.skip_coverage)
    throw std::invalid_argument("--policy oracle chooses by coverage: drop --no-coverage");
  if (o.max_scans < 1)
    throw std::invalid_argument("--max-scans must be at least 1 (got " +
                                std::to_string(o.max_scans) + ")");
  check_outputs_spare_inputs({{"--scene", o.scene}}, {},
                             {{{"--out", o.out}, survey_files_written()}});

  std::optional<Eigen::Vector2d> start_override;
  if (!o.start.empty()) {
    if (o.start.size() != 2) throw std::invalid_argument("--start: expected X,Y (2 numbers)");
    start_override = Eigen::Vector2d(o.start[0], o.start[1]);
  }
  sim::Scene scene = sim::load_scene(o.scene, start_override);
  apply_platform_options(o, scene);
  const sim::GroundTruth truth(scene);
  const Eigen::Vector2d start = scene.robot.start;
  const sim::FloorPlan plan = truth.floor_plan(0.05);
  check_robot_start(scene, truth, plan, o.scene);
  std::printf(
      "survey of %s: start (%.2f, %.2f), survey area %.1f m², robot radius %.2f m, "
      "scanner at %.2f m\n",
      o.scene.c_str(), start.x(), start.y(), plan.survey_area_m2, scene.robot.radius,
      scene.scanner.height);

  SurveyParams p;
  sim_platform::apply_scene(scene, p);
  apply_planning_options(o.plan, p, o.homogeneous);
  p.max_scans = std::size_t(o.max_scans);
  p.max_recoveries = std::size_t(o.max_recoveries);
  if (o.max_path > 0) p.max_path_m = o.max_path;
  if (o.homogeneous)
    std::printf("homogeneous grid of %.3f m voxels (the baseline): expect it to be slow\n",
                o.plan.leaf);
  std::filesystem::create_directories(o.out);

  const std::string cache = o.cache.empty() ? sim::default_cache_dir() : o.cache;
  remove_stale_temporaries(cache);  // the simulator's cache writer leaves them when killed
  // The reference is read or computed before the first scan, while nothing else is held.
  std::unique_ptr<SurveyCoverage> coverage;
  SimulatedPlatform::PlacedPoints count_coverage;
  if (!o.skip_coverage) {
    coverage = std::make_unique<SurveyCoverage>(truth, cache, o.plan.threads);
    count_coverage = [&coverage](const Cloud& points, const Eigen::Isometry3d& to_world) {
      coverage->add(points, to_world);
    };
  }
  SimulatedPlatform platform(scene, o.seed, o.plan.threads, count_coverage);
  p.may_stand = platform.survey_area_rule();
  SimulatedSurveyOutput output(o.out, p, platform, coverage.get());
  Survey survey(p, &output);
  std::unique_ptr<NextScanPolicy> policy;
  if (o.policy == "random") {
    policy = std::make_unique<RandomCandidatePolicy>(o.seed);
  } else if (o.policy == "oracle") {
    const auto t_oracle = Clock::now();
    policy = std::make_unique<OraclePolicy>(
        platform, coverage->accumulator(), o.seed * 1000 + 999,
        [t_oracle](std::size_t done, std::size_t total) {
          std::printf("  oracle: scanned %zu of %zu candidates [%.1f s]\n", done, total,
                      seconds_since(t_oracle));
          std::fflush(stdout);
        });
  } else {
    policy = std::make_unique<BestScorePolicy>();
  }

  const SurveyOutcome outcome = survey.run(platform, *policy);
  const std::string stopped_because = to_string(outcome.stopped_because);
  if (outcome.stopped_because == StopReason::kRegistrationFailed) {
    // Stopped before the map was touched: what was built so far stays valid.
    const std::string error = outcome.error + " in " + o.out;
    nlohmann::json extra = {{"scene", o.scene},
                            {"seed", o.seed},
                            {"error", error},
                            {"seconds_total", seconds_since(t_start)}};
    output.write_survey_json(stopped_because, extra, &survey.map());
    throw RegistrationError(error);
  }
  const ScanRecord& last = survey.records().back();
  switch (outcome.stopped_because) {
    case StopReason::kNoCandidate:
      std::printf("stop: no feasible candidate remains\n");
      break;
    case StopReason::kStopPercentage:
      if (last.scope == SurveyScope::kFloor)
        std::printf("stop: every room the robot can reach is below the stop percentage (%.3f %%)\n",
                    o.plan.stop);
      else
        std::printf("stop: stop percentage %.3f %% < %.3f %%\n", last.nbv.stop_percent,
                    o.plan.stop);
      break;
    case StopReason::kMaxPath:
      std::printf(
          "stop: the next move would take the path beyond --max-path %.1f m (%.1f m so "
          "far)\n",
          o.max_path, outcome.path_m);
      break;
    default:
      std::printf("stop: scan budget of %d spent (stop percentage %.3f %%)\n", o.max_scans,
                  last.nbv.stop_percent);
  }

  nlohmann::json extra;
  extra["scene"] = o.scene;
  extra["seed"] = o.seed;
  extra["homogeneous"] = o.homogeneous;
  extra["policy"] = o.policy;
  extra["distance_driven_m"] = platform.robot().distance_driven();
  if (coverage)
    extra["coverage"] =
        coverage_summary(truth, coverage->accumulator(), platform, o.out, o.plan.threads);
  extra["seconds_total"] = seconds_since(t_start);
  output.write_survey_json(stopped_because, extra, &survey.map());
  std::printf("survey: %zu scans, stopped because %s; wrote %s/survey.json [%.1f s]\n",
              survey.records().size(), stopped_because.c_str(), o.out.c_str(),
              seconds_since(t_start));
}

}  // namespace

void add_survey_command(CLI::App& app) {
  auto o = std::make_shared<SurveyOptions>();
  auto* cmd = app.add_subcommand(
      "survey",
      "Autonomous survey of a scene with the simulated robot and laser scanner: scan, "
      "preprocess, register (odometry + ICP), update the semioctree (occupancy, doors and "
      "windows, occlusion), choose the next best view, drive there; until the stop percentage "
      "is below --stop, no feasible candidate remains, or --max-scans scans are taken. Writes "
      "survey.json, report.html (the survey on one page for any browser) and scan_NN/ "
      "(semioctree.ot, labels_color.ot, occupancy.bt, slice.png, cloud.ply) per scan, and "
      "coverage_missed.ply (the reference surface it missed).");
  cmd->add_option("--scene", o->scene, "scene file (.scene.json, mesh or .bt)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out,
                  "output directory (a survey.json and scan_NN/ folders of an earlier run "
                  "there are replaced)")
      ->required();
  add_planning_options(*cmd, o->plan);
  cmd->add_option("--max-scans", o->max_scans, "scan budget")->capture_default_str();
  cmd->add_option("--max-path", o->max_path,
                  "path budget, m: the survey ends before a move that would take the robot's "
                  "path (over the cells its safety cylinder clears) beyond it; 0: none")
      ->check(finite_in(0, 1e6))
      ->capture_default_str();
  cmd->add_option("--max-recoveries", o->max_recoveries,
                  "a scan that cannot be registered is dropped and taken again back along the "
                  "robot's path towards the last placed scan (at most half the path, then a "
                  "quarter, ...): at most this many times in a row before the survey ends; 0: "
                  "the first failure ends it")
      ->check(whole_in(0, 100))
      ->capture_default_str();
  cmd->add_flag("--homogeneous", o->homogeneous,
                "use the homogeneous grid of leaf-size voxels (the paper's baseline) instead of "
                "the semioctree");
  cmd->add_option("--seed", o->seed, "seed of the scanner noise and the odometry drift")
      ->check(seed_value())
      ->capture_default_str();
  cmd->add_option("--policy", o->policy,
                  "where to scan next: nbv (the best candidate), random (a random feasible "
                  "candidate: the baseline the NBV is compared with) or oracle (the feasible "
                  "candidate whose scan adds the most reference surface, found by scanning "
                  "each one in the simulator: perfect knowledge, a yardstick for the NBV "
                  "score; about a minute per scan on the lab); random and oracle choose, as "
                  "the NBV does, among the candidates predicted to overlap the map by "
                  "--min-overlap")
      ->check(CLI::IsMember({"nbv", "random", "oracle"}))
      ->capture_default_str();
  cmd->add_option("--start", o->start, "robot start X,Y in the scene (default: the scene's)")
      ->delimiter(',')
      ->expected(2)
      ->check(finite_in(-sim::kMaxSceneNumber, sim::kMaxSceneNumber));
  cmd->add_option("--robot-radius", o->robot_radius,
                  "radius of the robot's safety cylinder, m (default: the scene's robot.radius)")
      ->check(finite_positive(100));
  cmd->add_option("--scanner-height", o->scanner_height,
                  "height of the scanner's optical centre above the floor, m (default: the "
                  "scene's scanner.height)")
      ->check(finite_positive(100));
  cmd->add_option("--elevation-min", o->elevation_min,
                  "the scanner's lowest elevation, degrees from horizontal (default: the scene's "
                  "scanner.elevation_min_deg)")
      ->check(finite_in(-90, 90));
  cmd->add_option("--elevation-max", o->elevation_max,
                  "the scanner's highest elevation, degrees (default: the scene's "
                  "scanner.elevation_max_deg)")
      ->check(finite_in(-90, 90));
  cmd->add_option("--min-range", o->min_range,
                  "the scanner's minimum range, m: nearer surfaces give no returns (default: the "
                  "scene's scanner.min_range)")
      ->check(finite_positive(1000));
  cmd->add_option("--max-range", o->max_range,
                  "the scanner's maximum range, m (default: the scene's scanner.max_range)")
      ->check(finite_positive(1e4));
  cmd->add_option("--cache", o->cache,
                  "directory of cached coverage references (default: $XDG_CACHE_HOME/semioctree "
                  "or ~/.cache/semioctree)");
  cmd->add_flag("--no-coverage", o->skip_coverage,
                "skip the coverage of the scene's surfaces in survey.json");
  cmd->callback([o] { run_survey(*o); });
}

}  // namespace semioctree::cli
