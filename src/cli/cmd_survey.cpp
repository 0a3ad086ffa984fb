// `semioctree survey --scene FILE --out DIR ...`: the autonomous survey of a
// scene with the simulated robot and scanner: scan → preprocess → register →
// update → NBV → move, until the stop percentage falls below its threshold, no
// feasible candidate remains, or the scan budget is spent.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>

#include "commands.h"
#include "option_checks.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/sim/coverage.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/robot.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "sim_input.h"
#include "survey_session.h"

namespace semioctree::cli {

namespace {

// The reference samples a survey missed, for CloudCompare beside cloud.ply: binary PLY,
// x y z as float, an RGB colour (orange: in view of a scan but sampled too sparsely,
// blue: hidden from every scan) and `hidden` (0 or 1) to filter on.
void write_missed_samples_ply(const sim::CoverageReference& ref, const sim::MissedSamples& missed,
                              const std::string& path) {
  write_file_atomically(path, [&](std::ostream& os) {
    os << "ply\nformat binary_little_endian 1.0\ncomment semioctree reference samples a survey "
          "missed\nelement vertex "
       << missed.in_view_samples.size() + missed.hidden_samples.size()
       << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
          "property uchar green\nproperty uchar blue\nproperty uchar hidden\nend_header\n";
    auto put = [&](const std::vector<std::uint32_t>& samples, const std::uint8_t(&rgbh)[4]) {
      for (std::uint32_t i : samples) {
        const Eigen::Vector3f p = ref.points.at(i).cast<float>();  // x86: little-endian
        os.write(reinterpret_cast<const char*>(p.data()), 3 * sizeof(float));
        os.write(reinterpret_cast<const char*>(rgbh), sizeof rgbh);
      }
    };
    put(missed.in_view_samples, {255, 140, 0, 0});
    put(missed.hidden_samples, {30, 90, 255, 1});
  });
}

struct SurveyOptions {
  std::string scene;
  std::string out;
  PlanningOptions plan;
  int max_scans = 10;
  bool homogeneous = false;
  std::uint64_t seed = 1;
  // "random": a random feasible candidate (the baseline); "oracle": the feasible
  // candidate that adds the most surface, known from the scene (the yardstick).
  std::string policy = "nbv";
  std::vector<double> start;  // X,Y: replaces the scene's robot start
  std::string cache;
  bool skip_coverage = false;
};

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// survey.json lists the scene elements with the most missed samples, not all of them.
constexpr std::size_t kMissedPartsListed = 8;

nlohmann::json true_pose_json(const sim::Scan& s) {
  return pose_json(s.sensor_to_world());
}

struct OracleChoice {
  Point3 position;          // survey frame
  double gain_percent = 0;  // reference samples it newly covers, % of the reference
};

// --policy oracle: scans every feasible candidate in the simulator and takes the
// one whose points cover the most reference samples not covered yet. Perfect
// knowledge, one scan ahead, among the planner's own candidates: what the best
// greedy score could choose, for comparison with the NBV score.
OracleChoice oracle_choice(const std::vector<NbvCandidate>& candidates, const sim::Scene& scene,
                           const sim::RayCaster& caster, const sim::CoverageReference& ref,
                           const std::vector<Eigen::Vector3f>& measured,
                           const Eigen::Isometry3d& survey_to_world, double yaw_deg,
                           std::uint64_t seed, unsigned threads) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<bool> have = sim::covered_samples(ref, measured);
  OracleChoice best;
  std::size_t best_gain = 0;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Point3& p = candidates[c].position;
    const Eigen::Vector3d w = survey_to_world * Eigen::Vector3d(p.x, p.y, 0.0);
    sim::ScanOptions so;
    so.seed = seed;
    so.threads = threads;
    so.with_intensity = false;
    const sim::Scan s = sim::scan(caster, scene.scanner, {w.x(), w.y(), yaw_deg}, so);
    const Eigen::Affine3f to_world = s.sensor_to_world().cast<float>();
    std::vector<Eigen::Vector3f> points;
    points.reserve(s.points.size());
    for (const Eigen::Vector3f& q : s.points) points.push_back(to_world * q);
    const std::vector<bool> got = sim::covered_samples(ref, points);
    std::size_t gain = 0;
    for (std::size_t k = 0; k < got.size(); ++k) gain += got[k] && !have[k];
    if (c == 0 || gain > best_gain) best_gain = gain, best.position = p;
    if ((c + 1) % 20 == 0 || c + 1 == candidates.size()) {
      std::printf("  oracle: scanned %zu of %zu candidates [%.1f s]\n", c + 1, candidates.size(),
                  since(t0));
      std::fflush(stdout);
    }
  }
  best.gain_percent = have.empty() ? 0.0 : 100.0 * double(best_gain) / double(have.size());
  return best;
}

void run_survey(const SurveyOptions& o) {
  const auto t_start = std::chrono::steady_clock::now();
  if (o.policy == "oracle" && o.skip_coverage)
    throw std::invalid_argument("--policy oracle chooses by coverage: drop --no-coverage");
  if (o.max_scans < 1)
    throw std::invalid_argument("--max-scans must be at least 1 (got " +
                                std::to_string(o.max_scans) + ")");

  std::optional<Eigen::Vector2d> start_override;
  if (!o.start.empty()) {
    if (o.start.size() != 2) throw std::invalid_argument("--start: expected X,Y (2 numbers)");
    start_override = Eigen::Vector2d(o.start[0], o.start[1]);
  }
  const sim::Scene scene = sim::load_scene(o.scene, start_override);
  const sim::GroundTruth truth(scene);
  const Eigen::Vector2d start = scene.robot.start;
  const sim::FloorPlan plan = truth.floor_plan(0.05);
  check_robot_start(scene, truth, plan, o.scene);
  std::printf(
      "survey of %s: start (%.2f, %.2f), survey area %.1f m², robot radius %.2f m, "
      "scanner at %.2f m\n",
      o.scene.c_str(), start.x(), start.y(), plan.survey_area_m2, scene.robot.radius,
      scene.scanner.height);

  SessionParams p;
  p.out = o.out;
  p.map.limits.min_range = scene.scanner.min_range;
  p.map.limits.max_range = scene.scanner.max_range;
  p.map.limits.elevation_min_deg = scene.scanner.elevation_min_deg;
  p.map.limits.elevation_max_deg = scene.scanner.elevation_max_deg;
  apply_planning_options(o.plan, p, o.homogeneous);
  p.robot.radius = scene.robot.radius;
  p.robot.scanner_height = scene.scanner.height;
  if (o.homogeneous)
    std::printf("homogeneous grid of %.3f m voxels (the baseline): expect it to be slow\n",
                o.plan.leaf);
  std::filesystem::create_directories(o.out);

  const std::string cache = o.cache.empty() ? sim::default_cache_dir() : o.cache;
  std::optional<sim::CoverageReference> reference;  // loaded once, when first needed
  auto coverage_reference = [&]() -> const sim::CoverageReference& {
    if (!reference) reference = sim::load_or_compute_coverage_reference(truth, cache);
    return *reference;
  };
  const auto caster = sim::make_ray_caster(sim::tessellate(scene));
  sim::Robot robot(scene.robot, o.seed);
  std::mt19937_64 choice(o.seed);  // --policy random
  SurveySession session(p);
  std::vector<Eigen::Vector3f> measured;         // every registered point, world frame (coverage)
  std::vector<Eigen::Vector3d> optical_centres;  // true, world frame (why samples were missed)
  Eigen::Isometry3d survey_to_world = Eigen::Isometry3d::Identity();
  std::string stopped_because = "max_scans";
  nlohmann::json pose_errors = nlohmann::json::array();
  sim::Pose2 previous_reported;
  Eigen::Isometry3d previous_estimate = Eigen::Isometry3d::Identity();
  double previous_distance = 0;
  for (int i = 0; i < o.max_scans; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    sim::ScanOptions so;
    so.seed = o.seed * 1000 + std::uint64_t(i);
    so.threads = o.plan.threads;
    so.with_intensity = false;
    const sim::Scan s = sim::scan(*caster, scene.scanner, robot.true_pose(), so);
    const double scan_seconds = since(t0);
    const sim::Pose2 reported = robot.reported_pose();
    std::printf("scan %d at (%.3f, %.3f) reported (%.3f, %.3f, %.2f°): %zu points [%.2f s]\n", i,
                robot.true_pose().x, robot.true_pose().y, reported.x, reported.y, reported.yaw_deg,
                s.points.size(), scan_seconds);
    std::fflush(stdout);

    IncomingScan in;
    in.points.reset(new Cloud);
    in.points->reserve(s.points.size());
    for (const Eigen::Vector3f& q : s.points) in.points->push_back({q.x(), q.y(), q.z()});
    in.points_raw = s.points.size();
    // Initial guess: the previous scan's registered pose moved by the odometry
    // of the leg since (odometry drifts; only its increments are trusted).
    if (i == 0) {
      in.x = reported.x;
      in.y = reported.y;
      in.yaw_deg = reported.yaw_deg;
    } else {
      const Eigen::Isometry3d leg =
          planar_pose(previous_reported.x, previous_reported.y, previous_reported.yaw_deg)
              .inverse() *
          planar_pose(reported.x, reported.y, reported.yaw_deg);
      const Eigen::Isometry3d guess = previous_estimate * leg;
      in.x = guess.translation().x();
      in.y = guess.translation().y();
      in.yaw_deg = yaw_deg_of(guess);
      const double d = robot.distance_driven() - previous_distance;
      in.max_correction_m = 0.1 + 5 * scene.robot.odometry_sigma_xy * d;
      in.max_correction_deg = 1.0 + 5 * scene.robot.odometry_sigma_yaw_deg * d;
    }
    if (i > 0) {
      const Eigen::Vector3d g(in.x, in.y, 0), t = survey_to_world.inverse() * s.origin();
      std::printf("  initial guess (odometry of the leg): %.3f m off the true position\n",
                  (g - t).head<2>().norm());
    }
    ScanOutcome r;
    try {
      r = session.add_scan(in);
    } catch (const RegistrationError& e) {
      // Stop before the map is touched: what was built so far stays valid.
      nlohmann::json extra = {{"scene", o.scene},
                              {"seed", o.seed},
                              {"error", e.what()},
                              {"seconds_total", since(t_start)}};
      session.write_survey_json("registration_failed", extra);
      throw;
    }
    previous_reported = reported;
    previous_distance = robot.distance_driven();
    {
      const Eigen::Vector3d t = r.scanner_to_survey.translation();
      previous_estimate = planar_pose(t.x(), t.y(), yaw_deg_of(r.scanner_to_survey));
    }

    // The survey frame is the first scan's estimate of the world; map back through it.
    const Eigen::Isometry3d truth_pose = s.sensor_to_world();
    if (i == 0) survey_to_world = truth_pose * r.scanner_to_survey.inverse();
    const Eigen::Isometry3d estimated_world = survey_to_world * r.scanner_to_survey;
    const double err_m = (estimated_world.translation() - truth_pose.translation()).norm();
    double err_deg = std::remainder(yaw_deg_of(estimated_world) - yaw_deg_of(truth_pose), 360.0);
    err_deg = std::abs(err_deg);
    nlohmann::json& rec = session.last_record();
    rec["true_pose"] = true_pose_json(s);
    rec["pose_error"] = {{"m", err_m}, {"deg", err_deg}};
    rec["seconds"]["scan"] = scan_seconds;
    if (i > 0) pose_errors.push_back({{"m", err_m}, {"deg", err_deg}});
    if (i > 0)
      std::printf("  pose error after registration: %.1f mm, %.3f°\n", 1000 * err_m, err_deg);
    if (!o.skip_coverage) {
      const Eigen::Affine3f to_world = (survey_to_world * r.scanner_to_survey).cast<float>();
      for (const Eigen::Vector3f& q : s.points) measured.push_back(to_world * q);
      optical_centres.push_back(truth_pose.translation());
    }

    if (!r.nbv) {
      stopped_because = "no_candidate";
      std::printf("stop: no feasible candidate remains\n");
      break;
    }
    if (r.stop_percent < o.plan.stop) {
      stopped_because = "stop_percentage";
      std::printf("stop: stop percentage %.3f %% < %.3f %%\n", r.stop_percent, o.plan.stop);
      break;
    }
    if (i + 1 == o.max_scans) {
      std::printf("stop: scan budget of %d spent (stop percentage %.3f %%)\n", o.max_scans,
                  r.stop_percent);
      break;
    }
    // Drive to the NBV (the survey frame mapped to the world through the first
    // scan), or, as the baseline, to a random feasible candidate.
    Point3 next = r.nbv->position;
    const char* what = "NBV";
    if (o.policy == "random") {
      std::uniform_int_distribution<std::size_t> pick(0, r.candidates.size() - 1);
      next = r.candidates[pick(choice)].position;
      what = "random candidate";
    } else if (o.policy == "oracle") {
      const OracleChoice best = oracle_choice(r.candidates, scene, *caster, coverage_reference(),
                                              measured, survey_to_world, robot.true_pose().yaw_deg,
                                              o.seed * 1000 + 999, o.plan.threads);
      next = best.position;
      what = "oracle's choice";
      session.last_record()["oracle_gain_percent"] = best.gain_percent;
      std::printf("  oracle: (%.3f, %.3f) adds %.2f %% of the reference surface\n", next.x, next.y,
                  best.gain_percent);
    }
    const Eigen::Vector3d target = survey_to_world * Eigen::Vector3d(next.x, next.y, 0.0);
    robot.move_to({target.x(), target.y(), robot.true_pose().yaw_deg});
    std::printf("move to the %s (%.3f, %.3f): %.2f m driven so far\n", what, target.x(), target.y(),
                robot.distance_driven());
    std::fflush(stdout);
  }

  nlohmann::json extra;
  extra["scene"] = o.scene;
  extra["seed"] = o.seed;
  extra["homogeneous"] = o.homogeneous;
  extra["policy"] = o.policy;
  extra["distance_driven_m"] = robot.distance_driven();
  if (!o.skip_coverage) {
    const auto t0 = std::chrono::steady_clock::now();
    const sim::CoverageReference& ref = coverage_reference();
    const std::vector<bool> covered = sim::covered_samples(ref, measured);
    const sim::Coverage c = sim::count_covered(covered);
    const sim::MissedSamples missed =
        sim::explain_missed_samples(truth, ref, covered, optical_centres, o.plan.threads);
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
    extra["coverage"] = {{"reference_points", c.reference_points},
                         {"covered", c.covered},
                         {"percent", c.percent},
                         {"reference_cached", ref.from_cache},
                         {"missed",
                          {{"in_view", missed.in_view},
                           {"in_view_percent", percent_of(missed.in_view)},
                           {"hidden", missed.hidden},
                           {"hidden_percent", percent_of(missed.hidden)},
                           {"parts", parts}}}};
    std::printf(
        "coverage: %zu of %zu reference surface samples within 3 cm of a point: %.2f %% "
        "(reference %s) [%.2f s]\n",
        c.covered, c.reference_points, c.percent, ref.from_cache ? "from the cache" : "computed",
        since(t0));
    std::printf(
        "  missed: %.2f %% in view of a scan but sampled too sparsely there, %.2f %% hidden "
        "from every scan\n",
        percent_of(missed.in_view), percent_of(missed.hidden));
    for (std::size_t k = 0; k < missed.parts.size() && k < 3; ++k)
      std::printf("    %s: %.2f %% in view, %.2f %% hidden\n", missed.parts[k].label.c_str(),
                  percent_of(missed.parts[k].in_view), percent_of(missed.parts[k].hidden));
    const std::string missed_ply = (std::filesystem::path(o.out) / "coverage_missed.ply").string();
    write_missed_samples_ply(ref, missed, missed_ply);
    std::printf("  wrote %s (orange: in view but too sparse, blue: hidden)\n", missed_ply.c_str());
  }
  extra["seconds_total"] = since(t_start);
  session.write_survey_json(stopped_because, extra);
  std::printf("survey: %zu scans, stopped because %s; wrote %s/survey.json [%.1f s]\n",
              session.scans(), stopped_because.c_str(), o.out.c_str(), since(t_start));
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
      "survey.json and scan_NN/ (semioctree.ot, labels_color.ot, occupancy.bt, slice.png, "
      "cloud.ply) per scan, and coverage_missed.ply (the reference surface it missed).");
  cmd->add_option("--scene", o->scene, "scene file (.scene.json, mesh or .bt)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out,
                  "output directory (a survey.json and scan_NN/ folders of an earlier run "
                  "there are replaced)")
      ->required();
  add_planning_options(*cmd, o->plan);
  cmd->add_option("--max-scans", o->max_scans, "scan budget")->capture_default_str();
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
                  "score; about a minute per scan on the lab)")
      ->check(CLI::IsMember({"nbv", "random", "oracle"}))
      ->capture_default_str();
  cmd->add_option("--start", o->start, "robot start X,Y in the scene (default: the scene's)")
      ->delimiter(',')
      ->expected(2)
      ->check(finite_in(-sim::kMaxSceneNumber, sim::kMaxSceneNumber));
  cmd->add_option("--cache", o->cache,
                  "directory of cached coverage references (default: $XDG_CACHE_HOME/semioctree "
                  "or ~/.cache/semioctree)");
  cmd->add_flag("--no-coverage", o->skip_coverage,
                "skip the coverage of the scene's surfaces in survey.json");
  cmd->callback([o] { run_survey(*o); });
}

}  // namespace semioctree::cli
