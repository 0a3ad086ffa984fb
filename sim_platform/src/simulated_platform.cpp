#include "semioctree/sim_platform/simulated_platform.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "semioctree/sim/geometry.h"
#include "semioctree/timing.h"

namespace semioctree::sim_platform {

namespace {

// Points only: no intensity, no grid indices.
sim::ScanOptions points_only(const SimulatedPlatform& p, std::uint64_t seed) {
  sim::ScanOptions so;
  so.seed = seed;
  so.threads = p.threads();
  so.with_intensity = false;
  so.with_grid_indices = false;
  return so;
}

sim::Scan scan_at(const SimulatedPlatform& p, const sim::Pose2& pose, std::uint64_t seed) {
  return sim::scan(p.caster(), p.scene().scanner, pose, points_only(p, seed));
}

}  // namespace

ScannerView scanner_limits(const sim::Scene& scene) {
  ScannerView limits;
  limits.min_range = scene.scanner.min_range;
  limits.max_range = scene.scanner.max_range;
  limits.elevation_min_deg = scene.scanner.elevation_min_deg;
  limits.elevation_max_deg = scene.scanner.elevation_max_deg;
  return limits;
}

void apply_scene(const sim::Scene& scene, SurveyParams& params) {
  params.map.limits = scanner_limits(scene);
  params.nbv.limits = params.map.limits;
  params.robot.radius = scene.robot.radius;
  params.robot.scanner_height = scene.scanner.height;
}

SimulatedPlatform::SimulatedPlatform(const sim::Scene& scene, std::uint64_t seed, unsigned threads,
                                     PlacedPoints on_placed)
    : scene_(scene),
      seed_(seed),
      threads_(threads),
      on_placed_(std::move(on_placed)),
      caster_(sim::make_ray_caster(sim::tessellate(scene))),
      robot_(scene.robot, seed) {}

bool SimulatedPlatform::in_survey_area(const Point3& p) const {
  if (!scene_.survey_area) return true;
  const Eigen::Vector3d w = survey_to_world_ * Eigen::Vector3d(p.x, p.y, p.z);
  return sim::point_in_polygon(*scene_.survey_area, w.head<2>());
}

std::function<bool(const Point3&)> SimulatedPlatform::survey_area_rule() const {
  if (!scene_.survey_area) return {};
  return [this](const Point3& p) { return in_survey_area(p); };
}

IncomingScan SimulatedPlatform::scan() {
  if (last_points_) throw std::logic_error("SimulatedPlatform: the last scan was not placed");
  const std::size_t i = truths_.size();
  const auto t0 = Clock::now();
  IncomingScan in;
  Eigen::Vector3d origin;
  {
    // Row by row into the cloud as the rows are cast: the scan is never held twice.
    sim::Scan s;
    const sim::ScanGrid grid = sim::scan_grid(scene_.scanner);
    auto cloud = std::make_shared<Cloud>();
    // Room for every ray: the pages of rays without a return are never touched.
    cloud->reserve(std::size_t(grid.rows) * grid.cols);
    sim::for_each_scan_row(*caster_, scene_.scanner, robot_.true_pose(),
                           points_only(*this, seed_ * 1000 + std::uint64_t(i)), s,
                           [&](std::uint32_t, sim::ScanRow&& row) {
                             for (const Eigen::Vector3f& q : row.points)
                               cloud->push_back({q.x(), q.y(), q.z()});
                           });
    last_sensor_to_world_ = s.sensor_to_world();
    origin = s.origin();
    in.points = cloud;
    last_points_ = cloud;
  }
  ScanTruth truth;
  truth.scan_seconds = seconds_since(t0);
  truth.true_pose = robot_.true_pose();
  truth.reported_pose = robot_.reported_pose();
  truth.scanner_to_world = last_sensor_to_world_;
  truth.points = last_points_->size();
  in.points_raw = last_points_->size();
  const sim::Pose2& reported = truth.reported_pose;
  if (i == 0) {
    in.x = reported.x;
    in.y = reported.y;
    in.yaw_deg = reported.yaw_deg;
  } else {
    const Eigen::Isometry3d leg =
        planar_pose(previous_reported_.x, previous_reported_.y, previous_reported_.yaw_deg)
            .inverse() *
        planar_pose(reported.x, reported.y, reported.yaw_deg);
    const Eigen::Isometry3d guess = previous_estimate_ * leg;
    in.x = guess.translation().x();
    in.y = guess.translation().y();
    in.yaw_deg = yaw_deg_of(guess);
    const double d = robot_.distance_driven() - previous_distance_;
    in.max_correction_m = 0.1 + 5 * scene_.robot.odometry_sigma_xy * d;
    in.max_correction_deg = 1.0 + 5 * scene_.robot.odometry_sigma_yaw_deg * d;
    const Eigen::Vector3d g(in.x, in.y, 0), t = survey_to_world_.inverse() * origin;
    truth.guess_error_m = (g - t).head<2>().norm();
  }
  truths_.push_back(truth);
  return in;
}

void SimulatedPlatform::placed(const Eigen::Isometry3d& scanner_to_survey) {
  if (!last_points_) throw std::logic_error("SimulatedPlatform: no scan to place");
  ScanTruth& truth = truths_.back();
  previous_reported_ = truth.reported_pose;
  previous_distance_ = robot_.distance_driven();
  const Eigen::Vector3d t = scanner_to_survey.translation();
  previous_estimate_ = planar_pose(t.x(), t.y(), yaw_deg_of(scanner_to_survey));

  // The survey frame is the first scan's estimate of the world; map back through it.
  const Eigen::Isometry3d& true_pose = truth.scanner_to_world;
  if (truths_.size() == 1) survey_to_world_ = true_pose * scanner_to_survey.inverse();
  const Eigen::Isometry3d estimated_world = survey_to_world_ * scanner_to_survey;
  truth.pose_error_m = (estimated_world.translation() - true_pose.translation()).norm();
  truth.pose_error_deg =
      std::abs(std::remainder(yaw_deg_of(estimated_world) - yaw_deg_of(true_pose), 360.0));
  optical_centres_.push_back(true_pose.translation());
  if (on_placed_) on_placed_(*last_points_, estimated_world);
  last_points_.reset();
}

void SimulatedPlatform::rejected() {
  if (!last_points_) throw std::logic_error("SimulatedPlatform: no scan to reject");
  truths_.pop_back();
  last_points_.reset();
}

void SimulatedPlatform::move_to(const Point3& target) {
  const Eigen::Vector3d w = survey_to_world_ * Eigen::Vector3d(target.x, target.y, 0.0);
  robot_.move_to({w.x(), w.y(), robot_.true_pose().yaw_deg});
}

void add_to_coverage(sim::CoverageAccumulator& coverage, const Cloud& points,
                     const Eigen::Isometry3d& scanner_to_world, unsigned threads) {
  coverage.add(
      points.size(),
      [&](std::size_t i) {
        return Eigen::Vector3d(scanner_to_world * points[i].getVector3fMap().cast<double>());
      },
      threads);
}

OraclePolicy::OraclePolicy(const SimulatedPlatform& platform,
                           const sim::CoverageAccumulator& covered, std::uint64_t seed,
                           std::function<void(std::size_t, std::size_t)> progress)
    : platform_(platform), covered_(covered), seed_(seed), progress_(std::move(progress)) {}

NextScanChoice OraclePolicy::choose(const ScanRecord& scan, const SurveyMap&,
                                    const RegistrationSafe& safe) {
  const std::vector<NbvCandidate>& candidates = scan.nbv.candidates;
  if (candidates.empty()) throw std::logic_error("OraclePolicy: no candidate to choose from");
  const std::vector<bool>& have = covered_.covered();
  const double yaw_deg = platform_.robot().true_pose().yaw_deg;
  std::vector<std::size_t> gain(candidates.size(), 0);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Point3& p = candidates[c].position;
    const Eigen::Vector3d w = platform_.survey_to_world() * Eigen::Vector3d(p.x, p.y, 0.0);
    const sim::Scan s = scan_at(platform_, {w.x(), w.y(), yaw_deg}, seed_);
    const Eigen::Affine3f to_world = s.sensor_to_world().cast<float>();
    std::vector<Eigen::Vector3f> points;
    points.reserve(s.points.size());
    for (const Eigen::Vector3f& q : s.points) points.push_back(to_world * q);
    const std::vector<bool> got = covered_.flags_of(points);
    for (std::size_t k = 0; k < got.size(); ++k) gain[c] += got[k] && !have[k];
    if (progress_ && ((c + 1) % 20 == 0 || c + 1 == candidates.size()))
      progress_(c + 1, candidates.size());
  }
  // Largest gain first (candidate order on ties), the first safe one.
  std::vector<std::size_t> order(candidates.size());
  for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return gain[a] > gain[b]; });
  const auto first_safe = std::find_if(order.begin(), order.end(),
                                       [&](std::size_t c) { return !safe || safe(candidates[c]); });
  if (first_safe == order.end())
    throw std::logic_error("OraclePolicy: no candidate is registration-safe");
  NextScanChoice best;
  best.position = candidates[*first_safe].position;
  best.predicted_gain_percent =
      have.empty() ? 0.0 : 100.0 * double(gain[*first_safe]) / double(have.size());
  return best;
}

}  // namespace semioctree::sim_platform
