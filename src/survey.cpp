#include "semioctree/survey.h"

#include <pcl/common/transforms.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "semioctree/timing.h"

namespace semioctree {

const char* to_string(StopReason reason) {
  switch (reason) {
    case StopReason::kStopPercentage:
      return "stop_percentage";
    case StopReason::kMaxScans:
      return "max_scans";
    case StopReason::kNoCandidate:
      return "no_candidate";
    case StopReason::kRegistrationFailed:
      return "registration_failed";
  }
  return "?";
}

const char* to_string(PlacedBy placed_by) {
  switch (placed_by) {
    case PlacedBy::kPose:
      return "pose";
    case PlacedBy::kPoseAndIcp:
      return "pose+icp";
    case PlacedBy::kGlobalAndIcp:
      return "global+icp";
    case PlacedBy::kPoseGlobalAndIcp:
      return "pose+global+icp";
  }
  return "?";
}

double yaw_deg_of(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x = pose.rotation() * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) * 180.0 / M_PI;
}

Point3 ScanRecord::scanner() const {
  const Eigen::Vector3d o = scanner_to_survey.translation();
  return Point3(o.x(), o.y(), o.z());
}

std::optional<double> ScanRecord::stop_percent() const {
  if (!nbv.best) return std::nullopt;
  return nbv.stop_percent;
}

NextScanChoice BestScorePolicy::choose(const ScanRecord& scan, const SurveyMap&) {
  if (!scan.nbv.best) throw std::logic_error("BestScorePolicy: no candidate to choose from");
  return {scan.nbv.best->position, std::nullopt};
}

NextScanChoice RandomCandidatePolicy::choose(const ScanRecord& scan, const SurveyMap&) {
  const std::vector<NbvCandidate>& c = scan.nbv.candidates;
  if (c.empty()) throw std::logic_error("RandomCandidatePolicy: no candidate to choose from");
  std::uniform_int_distribution<std::size_t> pick(0, c.size() - 1);
  return {c[pick(rng_)].position, std::nullopt};
}

Survey::Survey(const SurveyParams& params, SurveyObserver* observer)
    : params_(params), observer_(observer ? observer : &silent_), map_(params.map) {
  if (params_.max_scans < 1) throw std::invalid_argument("Survey: max_scans must be at least 1");
}

namespace {

// ICP's correction as a movement of the scanner (the correction's own translation is
// about the survey origin, far away), checked against what the platform can be wrong by.
double checked_scanner_shift(const RegistrationResult& r, const Eigen::Isometry3d& place,
                             const IncomingScan& in) {
  const Eigen::Vector3d c = place.translation();
  const double shift = (r.correction * c - c).head<2>().norm();
  if ((in.max_correction_m > 0 && shift > in.max_correction_m) ||
      (in.max_correction_deg > 0 && r.rotation_deg > in.max_correction_deg)) {
    char m[256];
    std::snprintf(m, sizeof m,
                  "ICP moved the scanner %.2f m and turned it %.2f°, more than its "
                  "odometry can be wrong (%.2f m, %.2f°): a false match",
                  shift, r.rotation_deg, in.max_correction_m, in.max_correction_deg);
    throw RegistrationError(m);
  }
  return shift;
}

// The global alignment's placement as a correction of the reported pose, for
// checked_scanner_shift.
RegistrationResult as_correction(const GlobalAlignResult& g) {
  RegistrationResult r = g.icp;
  r.correction = g.transform;
  r.rotation_deg = Eigen::AngleAxisd(g.transform.linear()).angle() * 180.0 / M_PI;
  return r;
}

}  // namespace

GlobalAlignResult Survey::recover_by_global_alignment(const Cloud& placed,
                                                      const Eigen::Isometry3d& place,
                                                      const IncomingScan& in,
                                                      const std::string& pose_failure,
                                                      double* scanner_shift_m) const {
  try {
    GlobalAlignResult g =
        global_align(placed, map_.merged_cloud(), params_.registration, params_.global_align);
    *scanner_shift_m = checked_scanner_shift(as_correction(g), place, in);
    return g;
  } catch (const RegistrationError& e) {
    throw RegistrationError(pose_failure + "; nor by a global alignment: " + e.what());
  }
}

const ScanRecord& Survey::add_scan(const IncomingScan& in,
                                   const std::optional<Point3>& robot_position) {
  const auto t_total = Clock::now();
  ScanRecord rec;
  rec.index = records_.size();
  rec.points_raw = in.points_raw ? in.points_raw : in.points->size();

  // Stage 1: drop the returns outside the scanner's limits (its mount, the robot), level
  // this scan in its own frame, then place it by the reported pose.
  auto t0 = Clock::now();
  const Cloud::Ptr seen = within_limits(in.points, params_.map.limits, &rec.points_outside_limits);
  const PreprocessResult pre = preprocess(*seen, params_.preprocess);
  rec.points_kept = pre.output_points;
  rec.ceiling_height = pre.ceiling_height;
  rec.ceiling_found = pre.ceiling_found;
  rec.height_from = pre.height_from;
  rec.tilt_alpha_deg = pre.alpha_deg;
  rec.tilt_beta_deg = pre.beta_deg;
  rec.seconds.preprocess = seconds_since(t0);
  observer_->stage_done(SurveyStage::kPreprocessed, rec);
  const bool no_pose = in.placement == ScanPlacement::kNoPose;
  const Eigen::Isometry3d place =
      no_pose ? Eigen::Isometry3d::Identity() : planar_pose(in.x, in.y, in.yaw_deg);
  Cloud::Ptr guess(new Cloud);
  pcl::transformPointCloud(*pre.cloud, *guess, place.matrix().cast<float>());

  // Stage 2: ICP against the merged cloud of the previous scans, from the reported
  // pose or, without one, from the global alignment's guess.
  t0 = Clock::now();
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  if (rec.index > 0 && in.placement != ScanPlacement::kExact) {
    ScanRecord::Registration reg;
    try {
      if (no_pose) {
        GlobalAlignResult g =
            global_align(*guess, map_.merged_cloud(), params_.registration, params_.global_align);
        const Eigen::Vector3d c = g.guess * pre.transform.translation();
        reg.scanner_shift_m = (g.icp.correction * c - c).head<2>().norm();
        reg.icp = g.icp;
        correction = g.transform;
        reg.global = std::move(g);
        rec.placed_by = PlacedBy::kGlobalAndIcp;
      } else {
        try {
          reg.icp = register_scan(*guess, map_.merged_cloud(), params_.registration);
          reg.scanner_shift_m = checked_scanner_shift(reg.icp, place, in);
          correction = reg.icp.correction;
          rec.placed_by = PlacedBy::kPoseAndIcp;
        } catch (const RegistrationError& from_pose) {
          // The reported pose may be off by more than ICP reaches (a long drive, a turn):
          // recover as a robot would, by a global alignment, kept only within what the
          // pose can be wrong by.
          GlobalAlignResult g = recover_by_global_alignment(*guess, place, in, from_pose.what(),
                                                            &reg.scanner_shift_m);
          reg.icp = g.icp;
          correction = g.transform;
          reg.global = std::move(g);
          reg.pose_icp_failure = from_pose.what();
          rec.placed_by = PlacedBy::kPoseGlobalAndIcp;
        }
      }
    } catch (const RegistrationError& e) {
      throw RegistrationError("scan " + std::to_string(rec.index) + " could not be registered (" +
                              e.what() + "); the map of the previous scans is kept");
    }
    rec.registration = reg;
  }
  rec.seconds.registration = seconds_since(t0);
  rec.scanner_to_survey = correction * place * pre.transform;
  Cloud::Ptr registered(new Cloud);
  pcl::transformPointCloud(*guess, *registered, correction.matrix().cast<float>());
  const Point3 scanner = rec.scanner();
  // One floor for the whole survey: a scan levelled onto another plane (the ground
  // outside a window, a table) would shift the map up or down.
  if (!map_.empty() && std::abs(scanner.z - map_.scanners().front().z) > 0.1) {
    char m[200];
    std::snprintf(m, sizeof m,
                  "scan %zu: its floor was found %.2f m from the first scan's (scanner at %.2f m "
                  "above it instead of %.2f m); the map of the previous scans is kept",
                  rec.index, scanner.z - map_.scanners().front().z, scanner.z,
                  map_.scanners().front().z);
    throw RegistrationError(m);
  }
  if (rec.registration) observer_->stage_done(SurveyStage::kRegistered, rec);

  // Stages 3-5 (8 for later scans): occupancy, openings, occlusion.
  ReturnDirectionsOptions returns;
  returns.open_above = !pre.ceiling_found;
  if (in.from_robot) returns.body = platform_body(params_.robot, params_.map.grid.leaf);
  returns.min_range = params_.map.limits.min_range;
  rec.update = map_.add_scan(*registered, scanner, pre.ceiling_height,
                             return_directions(*seen, rec.scanner_to_survey.linear(), returns));
  rec.seconds.occupancy = rec.update.seconds_occupancy;
  rec.seconds.openings = rec.update.seconds_openings;
  rec.seconds.occlusion = rec.update.seconds_occlusion;
  observer_->stage_done(SurveyStage::kMapped, rec);

  // Stages 6-7: next best view and stop percentage, in the room the scans stand in.
  t0 = Clock::now();
  NbvParams nbv = params_.nbv;
  nbv.grid_anchor = map_.scanners().front();  // see NbvParams::grid_anchor
  nbv.overlap_top = map_.ceiling_height();
  nbv.min_overlap = params_.min_overlap.value_or(params_.registration.min_overlap);
  rec.room_only = params_.room_only;
  if (params_.room_only) {
    nbv.room = room_box(map_.tree(), map_.scanners(), params_.robot.scanner_height, 0.0,
                        map_.ceiling_height());
    rec.room = nbv.room;
    observer_->stage_done(SurveyStage::kRoomFound, rec);
  }
  SurveyObserver* observer = observer_;
  nbv.progress = [observer](std::size_t done, std::size_t total) {
    observer->candidates_scored(done, total);
  };
  rec.nbv = next_best_view(map_.tree(), params_.robot, robot_position.value_or(scanner),
                           map_.scanners(), nbv);
  rec.seconds.nbv = seconds_since(t0);
  rec.seconds.total = seconds_since(t_total);
  observer_->stage_done(SurveyStage::kPlanned, rec);
  records_.push_back(std::move(rec));
  return records_.back();
}

namespace {
double planar_distance(const Point3& a, const Point3& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}
}  // namespace

std::optional<Point3> recovery_position(const ScanRecord& last, const Point3& failed,
                                        double fraction, const std::vector<Point3>& tried) {
  const Point3 from = last.scanner();
  const double x = from.x + fraction * (failed.x - from.x);
  const double y = from.y + fraction * (failed.y - from.y);
  double nearest_tried = std::numeric_limits<double>::infinity();
  for (const Point3& t : tried) nearest_tried = std::min(nearest_tried, planar_distance(t, from));
  std::optional<Point3> best;
  double best_d = 0;
  for (const NbvCandidate& c : last.nbv.candidates) {
    const Point3& p = c.position;
    if (planar_distance(p, from) >= nearest_tried) continue;
    const double d = planar_distance(p, Point3(x, y, 0));
    if (!best || d < best_d) best = p, best_d = d;
  }
  return best;
}

double Survey::predicted_overlap_at(const Point3& position) const {
  NbvParams nbv = params_.nbv;
  nbv.overlap_top = map_.ceiling_height();
  return predict_overlap(map_.tree(), position, nbv).share;
}

std::optional<double> Survey::path_between(const Point3& from, const Point3& to) const {
  NbvParams nbv = params_.nbv;
  nbv.grid_anchor = map_.scanners().front();
  std::vector<double> path_m;
  const std::vector<Point3> positions =
      find_candidates(map_.tree(), params_.robot, from, map_.scanners(), nbv, nullptr, &path_m);
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (positions[i].x == to.x && positions[i].y == to.y) return path_m[i];
  return std::nullopt;
}

SurveyOutcome Survey::run(ScanPlatform& platform, NextScanPolicy& policy) {
  SurveyOutcome out;
  std::optional<Point3> target;         // where the platform was sent (none: the first scan)
  std::optional<double> predicted;      // the overlap predicted there
  std::optional<double> path;           // the robot's path there
  std::vector<Point3> failed_in_a_row;  // where the scans since the last placed one failed
  for (std::size_t i = records_.size(); i < params_.max_scans;) {
    const IncomingScan in = platform.scan();
    observer_->scan_taken(i, in);
    try {
      add_scan(in);
    } catch (const RegistrationError& e) {
      platform.rejected();
      RegistrationFailure f;
      f.after_scan = records_.empty() ? 0 : records_.back().index;
      f.position = target.value_or(Point3());
      f.error = e.what();
      f.path_m = path;
      if (target) failed_in_a_row.push_back(*target);
      // Halfway back to the last placed scan, then a quarter of the way, ...
      if (target && !records_.empty() && failed_in_a_row.size() <= params_.max_recoveries)
        f.retry = recovery_position(records_.back(), failed_in_a_row.front(),
                                    std::ldexp(1.0, -int(failed_in_a_row.size())), failed_in_a_row);
      out.registration_failures.push_back(f);
      if (!f.retry) {
        observer_->registration_failed(f);
        out.stopped_because = StopReason::kRegistrationFailed;
        out.error = e.what();
        return out;
      }
      path = path_between(*target, *f.retry);
      platform.move_to(*f.retry);
      target = f.retry;
      predicted = predicted_overlap_at(*f.retry);
      observer_->registration_failed(f);
      continue;
    }
    failed_in_a_row.clear();
    ++i;
    records_.back().predicted_overlap = predicted;
    records_.back().path_m = path;
    const ScanRecord& rec = records_.back();
    platform.placed(rec.scanner_to_survey);
    observer_->scan_done(rec, map_);
    if (!rec.nbv.best) {
      out.stopped_because = StopReason::kNoCandidate;
      return out;
    }
    if (rec.nbv.stop_percent < params_.stop_percent) {
      out.stopped_because = StopReason::kStopPercentage;
      return out;
    }
    if (i == params_.max_scans) break;
    const NextScanChoice next = policy.choose(rec, map_);
    platform.move_to(next.position);
    target = next.position;
    // The chosen candidate's prediction (the NBV's was made while choosing it) and path.
    const auto chosen = std::find_if(
        rec.nbv.candidates.begin(), rec.nbv.candidates.end(), [&](const NbvCandidate& c) {
          return c.position.x == next.position.x && c.position.y == next.position.y;
        });
    const bool known = chosen != rec.nbv.candidates.end();
    predicted = known && chosen->predicted_overlap ? *chosen->predicted_overlap
                                                   : predicted_overlap_at(next.position);
    path = known ? std::optional<double>(chosen->path_m) : std::nullopt;
    observer_->moved(rec, next, policy);
  }
  out.stopped_because = StopReason::kMaxScans;
  return out;
}

}  // namespace semioctree
