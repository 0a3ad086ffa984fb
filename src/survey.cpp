#include "semioctree/survey.h"

#include <pcl/common/transforms.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "semioctree/timing.h"

namespace semioctree {

const char* to_string(StopReason reason) {
  switch (reason) {
    case StopReason::kStopPercentage:
      return "stop_percentage";
    case StopReason::kMaxScans:
      return "max_scans";
    case StopReason::kMaxPath:
      return "max_path";
    case StopReason::kNoCandidate:
      return "no_candidate";
    case StopReason::kRegistrationFailed:
      return "registration_failed";
  }
  return "?";
}

const char* to_string(SurveyScope scope) {
  switch (scope) {
    case SurveyScope::kRoom:
      return "room";
    case SurveyScope::kFloor:
      return "floor";
    case SurveyScope::kMap:
      return "map";
  }
  return "?";
}

SurveyScope survey_scope_from_string(const std::string& name) {
  for (SurveyScope s : {SurveyScope::kRoom, SurveyScope::kFloor, SurveyScope::kMap})
    if (name == to_string(s)) return s;
  throw std::invalid_argument("unknown survey scope '" + name + "' (room, floor or map)");
}

const char* to_string(RoomState state) {
  switch (state) {
    case RoomState::kComplete:
      return "complete";
    case RoomState::kOpen:
      return "open";
    case RoomState::kUnreachable:
      return "unreachable";
    case RoomState::kNotJudged:
      return "not_judged";
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

NextScanChoice BestScorePolicy::choose(const ScanRecord& scan, const SurveyMap&,
                                       const RegistrationSafe&) {
  if (!scan.nbv.best) throw std::logic_error("BestScorePolicy: no candidate to choose from");
  NextScanChoice choice;
  choice.position = scan.nbv.best->position;
  return choice;
}

NextScanChoice RandomCandidatePolicy::choose(const ScanRecord& scan, const SurveyMap&,
                                             const RegistrationSafe& safe) {
  const std::vector<NbvCandidate>& c = scan.nbv.candidates;
  if (c.empty()) throw std::logic_error("RandomCandidatePolicy: no candidate to choose from");
  // The candidates in a random order (a step of a Fisher-Yates shuffle per draw), up to
  // the first safe one.
  std::vector<std::size_t> order(c.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (std::size_t i = 0; i < order.size(); ++i) {
    std::swap(order[i], order[std::uniform_int_distribution<std::size_t>(i, c.size() - 1)(rng_)]);
    if (!safe || safe(c[order[i]])) {
      NextScanChoice choice;
      choice.position = c[order[i]].position;
      return choice;
    }
  }
  throw std::logic_error("RandomCandidatePolicy: no candidate is registration-safe");
}

Survey::Survey(const SurveyParams& params, SurveyObserver* observer)
    : params_(params), observer_(observer ? observer : &silent_), map_(params.map) {
  if (params_.max_scans < 1) throw std::invalid_argument("Survey: max_scans must be at least 1");
}

Survey::~Survey() {
  try {
    observer_->map_changing();
  } catch (...) {  // the observer reports its own failures; a destructor must not throw
  }
}

namespace {

// A placement sharing less than this share of the overlap predicted for where the scan
// was taken is doubted (docs/registration.md, "A placement that slid": correct ones
// shared at least 0.80 over 255 scans of generated rooms and 37 of the office floor,
// 0.56 beside the lab's window; one 1.7 m off shared 0.45).
constexpr double kSlidOverlapShare = 0.5;

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

// Whether corrections `a` and `b` place the scanner at `c` alike: within `tolerance` of
// each other there, and turned alike to within the angle that moves a surface 5 m away
// by `tolerance`.
bool same_placement(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                    const Eigen::Vector3d& c, double tolerance) {
  const double turn = Eigen::AngleAxisd((a.inverse() * b).linear()).angle();
  return (a * c - b * c).head<2>().norm() <= tolerance && 5.0 * turn <= tolerance;
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

GlobalAlignResult Survey::recover_by_global_alignment(
    const Cloud& placed, const Eigen::Isometry3d& place, const IncomingScan& in,
    const SurfaceFacing& facing, const std::string& pose_failure, double* scanner_shift_m) const {
  try {
    GlobalAlignResult g = global_align(placed, map_.merged_cloud(), params_.registration,
                                       params_.global_align, &facing);
    *scanner_shift_m = checked_scanner_shift(as_correction(g), place, in);
    return g;
  } catch (const RegistrationError& e) {
    throw RegistrationError(pose_failure + "; nor by a global alignment: " + e.what());
  }
}

const ScanRecord& Survey::add_scan(IncomingScan in, const std::optional<Point3>& robot_position,
                                   std::optional<double> predicted_overlap) {
  return add_scan_telling(std::move(in), robot_position, predicted_overlap, nullptr);
}

const ScanRecord& Survey::add_scan_telling(
    IncomingScan in, const std::optional<Point3>& robot_position,
    std::optional<double> predicted_overlap,
    const std::function<void(const Eigen::Isometry3d&)>& placed) {
  const auto t_total = Clock::now();
  ScanRecord rec;
  rec.index = records_.size();
  rec.points_raw = in.points_raw ? in.points_raw : in.points->size();

  // Stage 1: drop the returns outside the scanner's limits (its mount, the robot), level
  // this scan in its own frame, then place it by the reported pose.
  auto t0 = Clock::now();
  Cloud::Ptr seen = within_limits(in.points, params_.map.limits, &rec.points_outside_limits);
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
  // Which way the surfaces face: this scan's towards its scanner (placed by the guess),
  // the map's from where its scans saw them.
  const Eigen::Vector3d scanner_guess = place * pre.transform.translation();
  SurfaceFacing facing;
  if (!map_.empty()) {
    facing.source_viewpoint = scanner_guess;
    const SurveyMap* map = &map_;
    facing.target_side = [map](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
      return map->seen_side(p, n);
    };
  }

  // Stage 2: ICP against the merged cloud of the previous scans, from the reported
  // pose or, without one, from the global alignment's guess.
  t0 = Clock::now();
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  // A placement sharing less than half the predicted overlap with the map has slid.
  auto check_not_slid = [&](const RegistrationResult& r) {
    if (!predicted_overlap || !(r.overlap < kSlidOverlapShare * *predicted_overlap)) return;
    char m[256];
    std::snprintf(m, sizeof m,
                  "the placement shares %.0f %% with the map, less than half the %.0f %% "
                  "predicted where the scan was taken: it slid to a wrong fit",
                  100 * r.overlap, 100 * *predicted_overlap);
    throw RegistrationError(m);
  };
  if (rec.index > 0 && in.placement != ScanPlacement::kExact) {
    ScanRecord::Registration reg;
    try {
      if (no_pose) {
        GlobalAlignResult g = global_align(*guess, map_.merged_cloud(), params_.registration,
                                           params_.global_align, &facing);
        const Eigen::Vector3d c = g.guess * pre.transform.translation();
        reg.scanner_shift_m = (g.icp.correction * c - c).head<2>().norm();
        reg.icp = g.icp;
        correction = g.transform;
        reg.global = std::move(g);
        rec.placed_by = PlacedBy::kGlobalAndIcp;
      } else {
        std::optional<RegistrationResult> doubted;  // ICP's placement, sharing too little
        try {
          reg.icp = register_scan(*guess, map_.merged_cloud(), params_.registration, &facing);
          reg.scanner_shift_m = checked_scanner_shift(reg.icp, place, in);
          doubted = reg.icp;
          check_not_slid(reg.icp);
          doubted.reset();
          correction = reg.icp.correction;
          rec.placed_by = PlacedBy::kPoseAndIcp;
        } catch (const RegistrationError& from_pose) {
          // The reported pose may be off by more than ICP reaches (a long drive, a turn),
          // or ICP slid: recover as a robot would, by a global alignment, kept only within
          // what the pose can be wrong by.
          const double icp_shift = reg.scanner_shift_m;
          GlobalAlignResult g = recover_by_global_alignment(*guess, place, in, facing,
                                                            from_pose.what(), &reg.scanner_shift_m);
          std::string slid;
          try {
            check_not_slid(g.icp);
          } catch (const RegistrationError& e) {
            slid = e.what();
          }
          if (!slid.empty() && doubted &&
              same_placement(g.transform, doubted->correction, scanner_guess,
                             params_.registration.final_correspondence)) {
            // Both searches agree on a placement that shares little: the prediction was
            // off there (a view beside a window of what lies above the map's top).
            reg.icp = *doubted;
            reg.scanner_shift_m = icp_shift;
            correction = doubted->correction;
            rec.placed_by = PlacedBy::kPoseAndIcp;
          } else if (!slid.empty()) {
            throw RegistrationError(std::string(from_pose.what()) +
                                    "; nor by a global alignment: " + slid);
          } else {
            reg.icp = g.icp;
            correction = g.transform;
            reg.global = std::move(g);
            reg.pose_icp_failure = from_pose.what();
            rec.placed_by = PlacedBy::kPoseGlobalAndIcp;
          }
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
  if (placed) placed(rec.scanner_to_survey);

  // Stages 3-5 (8 for later scans): occupancy, openings, occlusion.
  ReturnDirectionsOptions returns;
  returns.open_above = !pre.ceiling_found;
  if (in.from_robot) returns.body = platform_body(params_.robot, params_.map.grid.leaf);
  returns.min_range = params_.map.limits.min_range;
  returns.elevation_min_deg = params_.map.limits.elevation_min_deg;
  returns.elevation_max_deg = params_.map.limits.elevation_max_deg;
  returns.threads = params_.map.threads;
  if (!map_.empty()) {  // what the scans before saw free around this one
    returns.map = &map_.tree();
    returns.optical_centre = scanner;
    // The same scanner most likely bins its depths as it did in the scan before.
    const std::vector<ScannerView> views = map_.views();
    if (views.back().returns)
      returns.expected_depth_bins_per_degree = views.back().returns->depth_bins_per_degree();
  }
  t0 = Clock::now();
  std::shared_ptr<const ReturnDirections> seen_directions =
      return_directions(*seen, rec.scanner_to_survey.linear(), returns);
  rec.seconds.returns = seconds_since(t0);
  // The scan's points are read (placed, levelled, decimated, their directions binned).
  seen.reset();
  in.points.reset();
  observer_->map_changing();
  rec.update = map_.add_scan(*registered, scanner, pre.ceiling_height, std::move(seen_directions));
  rec.seconds.occupancy = rec.update.seconds_occupancy;
  rec.seconds.openings = rec.update.seconds_openings;
  rec.seconds.occlusion = rec.update.seconds_occlusion;
  observer_->stage_done(SurveyStage::kMapped, rec);

  // Stages 6-7: next best view and stop percentage, in the room the scans stand in.
  t0 = Clock::now();
  NbvParams nbv = nbv_params();
  SurveyObserver* observer = observer_;
  nbv.progress = [observer](std::size_t done, std::size_t total) {
    observer->candidates_scored(done, total);
  };
  rec.scope = params_.scope;
  const Point3 robot = robot_position.value_or(scanner);
  if (params_.scope == SurveyScope::kFloor) {
    plan_floor(rec, nbv, robot);
  } else {
    if (params_.scope == SurveyScope::kRoom) {
      nbv.room = room_box(map_.tree(), map_.scanners(), params_.robot.scanner_height, 0.0,
                          map_.ceiling_height());
      rec.room = nbv.room;
      observer_->stage_done(SurveyStage::kRoomFound, rec);
    }
    rec.nbv = next_best_view(map_.tree(), params_.robot, robot, map_.scanners(), nbv);
    rec.scope_complete = rec.nbv.best && rec.nbv.stop_percent < params_.stop_percent;
  }
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

NbvParams Survey::nbv_params() const {
  NbvParams nbv = params_.nbv;
  nbv.grid_anchor = map_.scanners().front();  // see NbvParams::grid_anchor
  nbv.overlap_top = map_.ceiling_height();
  nbv.min_overlap = params_.min_overlap.value_or(params_.registration.min_overlap);
  nbv.may_stand = params_.may_stand;
  nbv.stand_beyond_openings = params_.scope == SurveyScope::kFloor;
  return nbv;
}

namespace {

// What lies beyond `door` on `side` (±1 along its wall normal) within `reach` of its
// centre, floor to `top`: the targets a doorway scan is judged by. A wall along neither
// axis gives the square around the door (both sides).
RoomBox beyond_door(const DetectedOpening& door, int side, double reach, double top) {
  const Eigen::Vector3d c = door.centre();
  RoomBox box{Point3(c.x() - reach, c.y() - reach, 0.0), Point3(c.x() + reach, c.y() + reach, top)};
  const Eigen::Vector3d n = double(side) * door.wall_normal;
  constexpr double kAlongAxis = 0.985;  // within 10° of an axis
  if (n.x() > kAlongAxis) box.min.x = c.x();
  if (n.x() < -kAlongAxis) box.max.x = c.x();
  if (n.y() > kAlongAxis) box.min.y = c.y();
  if (n.y() < -kAlongAxis) box.max.y = c.y();
  return box;
}

}  // namespace

DoorwayView doorway_view(const DetectedOpening& door, int side, const Eigen::Vector3d& at) {
  const Eigen::Vector3d d = at - door.centre();
  const double across = d.dot(door.wall_normal) * double(side);  // > 0: on the side looked into
  const Eigen::Vector3d along_wall = door.wall_normal.cross(Eigen::Vector3d::UnitZ());
  const double along = d.dot(along_wall) * double(side);
  const double reach = std::hypot(across, along);
  if (reach < door.width / 2) return DoorwayView::kInOpening;
  if (across > 0) return DoorwayView::kBeyond;
  if (std::abs(along) <= std::sin(10.0 * M_PI / 180.0) * reach) return DoorwayView::kStraight;
  return along > 0 ? DoorwayView::kFromOneSide : DoorwayView::kFromTheOther;
}

std::vector<Eigen::Vector3d> Survey::doorway_positions(const DetectedOpening& door) const {
  const double r = map_.tree().leaf_size();
  const Eigen::Vector3d c = door.centre();
  // In the opening, and in front of it on either side: where the robot's cylinder
  // clears the wall's face (the opening's corners lie on one face) and the scanner,
  // looking down no steeper than its lowest elevation, sees the floor just beyond the
  // opening, which the robot must have seen to drive through.
  const double near = params_.robot.radius + r;
  double off = near;
  const double lowest = params_.nbv.limits.elevation_min_deg;
  if (lowest < 0 && lowest > -90)
    off = std::max(off, params_.robot.scanner_height / std::tan(-lowest * M_PI / 180.0) + r);
  const Eigen::Vector3d ahead = off * door.wall_normal;
  std::vector<Eigen::Vector3d> out{c, c + ahead, c - ahead};
  if (off > near) {
    // Where the space in front of the door is shallower than that (a corridor narrower
    // than the distance): nearer, straight in front (the floor beyond is seen from a little
    // past the opening on), and at the full distance obliquely (the floor just beyond the
    // opening is seen, through it at an angle, on one side).
    for (const double share : {0.8, 0.6})
      if (share * off > near) {
        out.push_back(c + share * ahead);
        out.push_back(c - share * ahead);
      }
    const Eigen::Vector3d along = door.wall_normal.cross(Eigen::Vector3d::UnitZ()).normalized();
    for (const double deg : {20.0, 40.0, 60.0})
      for (const double turn : {-1.0, 1.0}) {
        const double a = turn * deg * M_PI / 180.0;
        const Eigen::Vector3d slant = std::cos(a) * door.wall_normal + std::sin(a) * along;
        out.push_back(c + off * slant);
        out.push_back(c - off * slant);
      }
  }
  return out;
}

std::optional<Survey::DoorwayChoice> Survey::plan_doorway_scan(
    const RoomMap& rooms, const std::vector<std::optional<std::size_t>>& status_of,
    const std::vector<std::vector<NbvCandidate>>& in_room, const std::vector<NbvCandidate>& all,
    const NbvParams& nbv) {
  const SemiOcTree& tree = map_.tree();
  const double height = params_.robot.scanner_height, top = map_.ceiling_height();
  const double r = tree.leaf_size();
  const std::vector<DetectedOpening>& openings = map_.openings();
  // Doors with a side where the robot cannot stand yet (nothing seen there, or too
  // little): a linking scan from a doorway position, which sees both sides, nearest
  // first, judged by what it sees beyond the door. A door side is looked through again
  // while the robot still cannot stand beyond it, once from each kind of doorway position
  // (DoorwayView): scans from either side of the door's normal together see the floor
  // just beyond the opening where neither alone does, and then the opening can be stood in.
  auto unexplored = [&](const std::optional<std::size_t>& room) {
    return !room || !status_of[*room] || in_room[*status_of[*room]].empty();
  };
  struct DoorwayPlan {
    std::size_t door;
    int side;  // the unexplored side, along the door's wall normal
    DoorwayView view;
    const NbvCandidate* doorway;
  };
  const auto looked = [&](const Eigen::Vector3d& c, int side, DoorwayView view) {
    return std::any_of(doorway_scans_.begin(), doorway_scans_.end(), [&](const DoorwayScan& d) {
      return d.side == side && d.view == view &&
             std::hypot(d.door.x - c.x(), d.door.y - c.y()) < 2 * r;
    });
  };
  std::vector<DoorwayPlan> plans;
  for (const OpeningLink& link : rooms.links()) {
    const DetectedOpening& o = openings[link.opening];
    if (o.kind != OpeningKind::kDoor) continue;
    const Eigen::Vector3d c = o.centre();
    for (const int side : {1, -1}) {
      if (!unexplored(side > 0 ? link.front : link.back)) continue;
      // Where the robot would stand first beyond the door: inside the survey area?
      const Eigen::Vector3d beyond =
          c + double(side) * (params_.robot.radius + 2 * r) * o.wall_normal;
      if (params_.may_stand && !params_.may_stand(Point3(beyond.x(), beyond.y(), height))) continue;
      // Of each kind, the position farthest from the wall the robot can stand at: it sees
      // through the opening most squarely, and the floor beyond from nearest the opening.
      std::map<DoorwayView, std::pair<double, const NbvCandidate*>> farthest;
      for (const Eigen::Vector3d& p : doorway_positions(o)) {
        const DoorwayView view = doorway_view(o, side, p);
        if (looked(c, side, view)) continue;
        const double depth = std::abs((p - c).dot(o.wall_normal));
        for (const NbvCandidate& cand : all)
          if (std::hypot(cand.position.x - p.x(), cand.position.y - p.y()) < r) {
            auto [at, added] = farthest.try_emplace(view, depth, &cand);
            if (!added && (depth > at->second.first ||
                           (depth == at->second.first && cand.path_m < at->second.second->path_m)))
              at->second = {depth, &cand};
          }
      }
      for (const auto& [view, best] : farthest)
        plans.push_back({link.opening, side, view, best.second});
    }
  }
  std::stable_sort(plans.begin(), plans.end(), [](const DoorwayPlan& a, const DoorwayPlan& b) {
    return a.doorway->path_m < b.doorway->path_m;
  });
  for (const DoorwayPlan& plan : plans) {
    NbvParams beyond = nbv;
    beyond.room = beyond_door(openings[plan.door], plan.side, nbv.limits.max_range, top);
    beyond.see_through_doors = true;
    NbvResult res = best_view_among(tree, {*plan.doorway}, beyond);
    if (!res.best || res.best->score <= 0) continue;
    const Eigen::Vector3d c = openings[plan.door].centre();
    return DoorwayChoice{std::move(res), plan.door, *beyond.room,
                         DoorwayScan{Point3(c.x(), c.y(), height), plan.side, plan.view}};
  }
  return std::nullopt;
}

void Survey::plan_floor(ScanRecord& rec, const NbvParams& nbv, const Point3& robot) {
  const SemiOcTree& tree = map_.tree();
  const double height = params_.robot.scanner_height, top = map_.ceiling_height();
  const double r = tree.leaf_size();
  const RoomMap rooms = segment_rooms(tree, height, 0.0, top, map_.openings());
  // A room is a region the robot's footprint fits in; smaller ones are gaps between
  // furniture, slivers seen past a window frame.
  const double footprint = M_PI * std::pow(std::max(params_.robot.radius, r), 2);
  std::vector<std::optional<std::size_t>> status_of(rooms.rooms().size());
  for (std::size_t i = 0; i < rooms.rooms().size(); ++i) {
    if (rooms.rooms()[i].area_m2 < footprint) continue;
    status_of[i] = rec.rooms.size();
    RoomStatus st;
    st.room = rooms.rooms()[i];
    rec.rooms.push_back(st);
  }
  auto status_near = [&](const Point3& p) -> std::optional<std::size_t> {
    const auto id = rooms.room_near(p, kRoomSeedRadius);
    return id ? status_of[*id] : std::nullopt;
  };
  const std::vector<Point3>& scanners = map_.scanners();
  for (std::size_t i = 0; i < scanners.size(); ++i)
    if (const auto s = status_near(scanners[i])) rec.rooms[*s].scans.push_back(i);
  rec.in_room = status_near(scanners.back());

  // The candidates, once: anywhere the robot can reach, through doors too, and in the
  // doorways it fits through.
  const auto t0 = Clock::now();
  NbvParams with_doorways = nbv;
  const std::vector<DetectedOpening>& openings = map_.openings();
  for (const DetectedOpening& o : openings) {
    if (o.kind != OpeningKind::kDoor || o.width <= 2 * params_.robot.radius + r) continue;
    for (const Eigen::Vector3d& p : doorway_positions(o)) {
      with_doorways.doorways.push_back(Point3(p.x(), p.y(), height));
    }
  }
  std::vector<double> path_m;
  CandidateReport report;
  const std::vector<Point3> positions =
      find_candidates(tree, params_.robot, robot, scanners, with_doorways, &report, &path_m);
  const double seconds_candidates = seconds_since(t0);
  std::vector<NbvCandidate> all;
  std::vector<std::vector<NbvCandidate>> in_room(rec.rooms.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    NbvCandidate c;
    c.position = positions[i];
    c.path_m = path_m[i];
    all.push_back(c);
    if (const auto id = rooms.room_at(positions[i]))
      if (status_of[*id]) in_room[*status_of[*id]].push_back(c);
  }
  auto finish = [&](NbvResult res, const std::optional<std::size_t>& planned) {
    res.candidate_report = report;
    res.seconds_candidates = seconds_candidates;
    rec.nbv = std::move(res);
    rec.planned_room = planned;
  };

  // A room's box: its cells' bounds grown by a leaf (its walls), floor to ceiling.
  auto box_of = [&](const RoomStatus& st) {
    return RoomBox{Point3(st.room.min.x - r, st.room.min.y - r, 0.0),
                   Point3(st.room.max.x + r, st.room.max.y + r, top)};
  };
  // What is known before judging: rooms found complete stay so while they are the same
  // room (bounds within the robot's radius and a leaf of the room found complete: not
  // joined to space seen since, nor split by a door found since); a room without a
  // candidate cannot be stood in.
  const double same_within = params_.robot.radius + r;
  const auto complete_at = [](const Point3& at, const RoomStatus& st) {
    return CompleteRoom{at, st.room.min, st.room.max};
  };
  const auto same = [&](const CompleteRoom& c, const RoomStatus& st) {
    return std::abs(c.min.x - st.room.min.x) <= same_within &&
           std::abs(c.min.y - st.room.min.y) <= same_within &&
           std::abs(c.max.x - st.room.max.x) <= same_within &&
           std::abs(c.max.y - st.room.max.y) <= same_within;
  };
  for (std::size_t i = 0; i < rec.rooms.size(); ++i) {
    RoomStatus& st = rec.rooms[i];
    for (const NbvCandidate& c : in_room[i])
      st.path_m = st.path_m ? std::min(*st.path_m, c.path_m) : c.path_m;
    if (std::any_of(complete_rooms_.begin(), complete_rooms_.end(),
                    [&](const CompleteRoom& c) { return status_near(c.at) == i && same(c, st); })) {
      st.state = RoomState::kComplete;
    } else if (in_room[i].empty()) {
      st.state = RoomState::kUnreachable;
      const Point3 centre(0.5 * (st.room.min.x + st.room.max.x),
                          0.5 * (st.room.min.y + st.room.max.y), height);
      st.why = params_.may_stand && !params_.may_stand(centre)
                   ? "outside the survey area (its centre)"
               : i == rec.in_room
                   ? "no position the robot can reach and stand in, although it stands at its "
                     "edge (the space seen in it, or hidden space next to the robot, narrower "
                     "than the robot's safety cylinder)"
                   : "no position the robot can reach and stand in (its doors, or the space "
                     "seen in it, narrower than the robot's safety cylinder)";
    }
  }

  // The robot's room first, from where it can stand in it (anywhere it can reach, if it
  // stands in no room: in a doorway).
  NbvParams room_nbv = nbv;
  std::vector<Point3> here;
  if (rec.in_room) {
    room_nbv.room = box_of(rec.rooms[*rec.in_room]);
    for (std::size_t i = 0; i < scanners.size(); ++i)
      if (status_near(scanners[i]) == rec.in_room) here.push_back(scanners[i]);
  } else {
    room_nbv.room = room_box(tree, {scanners.back()}, height, 0.0, top);
    here.push_back(scanners.back());
  }
  rec.room = room_nbv.room;
  observer_->stage_done(SurveyStage::kRoomFound, rec);
  // A room the robot stands at the edge of but can stand in nowhere (unreachable) is
  // looked into from wherever it can reach; it is open while that is worth a scan, and
  // never complete: it is judged again once a position in it can be reached.
  const bool stands_in_it = rec.in_room && !in_room[*rec.in_room].empty();
  NbvResult current = best_view_among(tree, stands_in_it ? in_room[*rec.in_room] : all, room_nbv);
  const bool known_complete = rec.in_room && rec.rooms[*rec.in_room].state == RoomState::kComplete;
  const bool open_here =
      !known_complete && current.best && current.stop_percent >= params_.stop_percent;
  if (rec.in_room) {
    RoomStatus& st = rec.rooms[*rec.in_room];
    st.stop_percent = current.best ? std::optional<double>(current.stop_percent) : std::nullopt;
    if (open_here)
      st.state = RoomState::kOpen;
    else if (stands_in_it)
      st.state = RoomState::kComplete;
  }
  if (open_here) return finish(std::move(current), rec.in_room);
  for (const Point3& p : here)
    if (stands_in_it) complete_rooms_.push_back(complete_at(p, rec.rooms[*rec.in_room]));

  // Then the other rooms, nearest by path first: the first open one is planned for,
  // unless a doorway scan into a room the robot cannot stand in yet is nearer by path
  // (that room is open too, and the doorway is where it is reached from).
  std::optional<DoorwayChoice> look = plan_doorway_scan(rooms, status_of, in_room, all, nbv);
  auto take_doorway = [&] {
    doorway_scans_.push_back(look->scan);
    rec.planned_doorway = look->door;
    rec.room = look->beyond;
    finish(std::move(look->nbv), std::nullopt);
  };
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < rec.rooms.size(); ++i)
    if (rec.rooms[i].state == RoomState::kNotJudged) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return *rec.rooms[a].path_m < *rec.rooms[b].path_m;
  });
  for (const std::size_t i : order) {
    RoomStatus& st = rec.rooms[i];
    NbvParams next = nbv;
    next.room = box_of(st);
    NbvResult res = best_view_among(tree, in_room[i], next);
    st.stop_percent = res.best ? std::optional<double>(res.stop_percent) : std::nullopt;
    if (res.best && res.stop_percent >= params_.stop_percent) {
      st.state = RoomState::kOpen;
      if (look && look->nbv.best->path_m < res.best->path_m) return take_doorway();
      rec.room = next.room;
      return finish(std::move(res), i);
    }
    st.state = RoomState::kComplete;
    complete_rooms_.push_back(complete_at(in_room[i].front().position, st));
  }
  // Then the doors with a side where the robot cannot stand yet.
  if (look) return take_doorway();
  // Every room the robot can reach is complete: the robot's room's result ends the survey.
  rec.scope_complete = current.best.has_value();
  finish(std::move(current), rec.in_room);
}

double Survey::predicted_overlap_at(const Point3& position) const {
  return predict_overlap(map_.tree(), position, nbv_params()).share;
}

std::optional<Waypoint> Survey::waypoint_toward(const Point3& from, const Point3& to, double to_m,
                                                double max_path_m,
                                                const std::vector<Point3>& tried) const {
  const NbvParams nbv = nbv_params();
  std::vector<double> from_m, towards_m;
  const std::vector<Point3> stands =
      find_candidates(map_.tree(), params_.robot, from, map_.scanners(), nbv, nullptr, &from_m);
  const std::vector<Point3> seen_from_to =
      find_candidates(map_.tree(), params_.robot, to, map_.scanners(), nbv, nullptr, &towards_m);
  // Both lists hold the same positions in grid order where both ends reach them.
  std::map<std::pair<double, double>, double> path_to;
  for (std::size_t i = 0; i < seen_from_to.size(); ++i)
    path_to.emplace(std::make_pair(seen_from_to[i].x, seen_from_to[i].y), towards_m[i]);
  const double r = map_.tree().leaf_size();
  double nearest_tried = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < stands.size(); ++i)
    for (const Point3& t : tried)
      if (planar_distance(stands[i], t) < r) nearest_tried = std::min(nearest_tried, from_m[i]);
  std::optional<Waypoint> best;
  double best_to = to_m;
  for (std::size_t i = 0; i < stands.size(); ++i) {
    if (from_m[i] > max_path_m || from_m[i] >= nearest_tried) continue;
    const auto t = path_to.find(std::make_pair(stands[i].x, stands[i].y));
    if (t == path_to.end()) continue;
    if (t->second < best_to || (best && t->second == best_to && from_m[i] < best->path_m)) {
      best = Waypoint{stands[i], from_m[i]};
      best_to = t->second;
    }
  }
  return best;
}

std::optional<Survey::Drive> Survey::drive_between(const Point3& from, const Point3& to) const {
  std::vector<double> path_m;
  RouteTree routes;
  const std::vector<Point3> positions = find_candidates(
      map_.tree(), params_.robot, from, map_.scanners(), nbv_params(), nullptr, &path_m, &routes);
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (positions[i].x == to.x && positions[i].y == to.y)
      return Drive{path_m[i], routes.route_to(to)};
  return std::nullopt;
}

SurveyOutcome Survey::run(ScanPlatform& platform, NextScanPolicy& policy) {
  SurveyOutcome out;
  std::optional<Point3> target;         // where the platform was sent (none: the first scan)
  std::optional<double> predicted;      // the overlap predicted there
  std::optional<double> path;           // the robot's path there
  std::vector<Point3> route;            // and its route
  std::vector<Point3> failed_in_a_row;  // where the scans since the last placed one failed
  double failed_path_m = 0;             // the path from the last placed scan to the first
  for (std::size_t i = records_.size(); i < params_.max_scans;) {
    IncomingScan in = platform.scan();
    observer_->scan_taken(i, in);
    try {
      add_scan_telling(std::move(in), std::nullopt, predicted,
                       [&](const Eigen::Isometry3d& pose) { platform.placed(pose); });
    } catch (const RegistrationError& e) {
      platform.rejected();
      RegistrationFailure f;
      f.after_scan = records_.empty() ? 0 : records_.back().index;
      f.position = target.value_or(Point3());
      f.error = e.what();
      f.path_m = path;
      f.route = route;
      if (target) {
        if (failed_in_a_row.empty()) failed_path_m = path.value_or(0.0);
        failed_in_a_row.push_back(*target);
      }
      // Back along the path to the last placed scan: at most half of it, then a quarter...
      std::optional<Waypoint> retry;
      if (target && !records_.empty() && failed_in_a_row.size() <= params_.max_recoveries)
        retry = waypoint_toward(records_.back().scanner(), failed_in_a_row.front(), failed_path_m,
                                std::ldexp(failed_path_m, -int(failed_in_a_row.size())),
                                failed_in_a_row);
      if (retry) f.retry = retry->position;
      out.registration_failures.push_back(f);
      if (!f.retry) {
        observer_->registration_failed(f);
        out.stopped_because = StopReason::kRegistrationFailed;
        out.error = e.what();
        return out;
      }
      // The robot stands at the failed position: its way back there.
      std::optional<Drive> drive = drive_between(*target, *f.retry);
      path = drive ? std::optional<double>(drive->m) : std::nullopt;
      route = drive ? std::move(drive->route) : std::vector<Point3>{};
      out.path_m += path.value_or(0.0);
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
    records_.back().route = route;
    const ScanRecord& rec = records_.back();
    observer_->scan_done(rec, map_);
    if (!rec.nbv.best) {
      out.stopped_because = StopReason::kNoCandidate;
      return out;
    }
    if (rec.scope_complete) {
      out.stopped_because = StopReason::kStopPercentage;
      return out;
    }
    if (i == params_.max_scans) break;
    // The overlap predicted for each candidate a policy asks about, kept for the one chosen.
    const NbvParams nbv = nbv_params();
    std::map<std::pair<double, double>, double> overlap_at;
    auto overlap_of = [&](const NbvCandidate& c) {
      if (c.predicted_overlap) return *c.predicted_overlap;
      const auto key = std::make_pair(c.position.x, c.position.y);
      const auto it = overlap_at.find(key);
      return it != overlap_at.end() ? it->second
                                    : overlap_at[key] = predicted_overlap_at(c.position);
    };
    const RegistrationSafe safe = [&](const NbvCandidate& c) {
      return !nbv.overlap_top || overlap_of(c) >= nbv.min_overlap;
    };
    const NextScanChoice next = policy.choose(rec, map_, safe);
    // The chosen candidate's prediction (the NBV's was made while choosing it) and path.
    const auto chosen = std::find_if(
        rec.nbv.candidates.begin(), rec.nbv.candidates.end(), [&](const NbvCandidate& c) {
          return c.position.x == next.position.x && c.position.y == next.position.y;
        });
    const bool known = chosen != rec.nbv.candidates.end();
    std::optional<Drive> drive = drive_between(rec.scanner(), next.position);
    path = known   ? std::optional<double>(chosen->path_m)
           : drive ? std::optional<double>(drive->m)
                   : std::nullopt;
    route = drive ? std::move(drive->route) : std::vector<Point3>{};
    if (params_.max_path_m && out.path_m + path.value_or(0.0) > *params_.max_path_m) {
      out.stopped_because = StopReason::kMaxPath;
      return out;
    }
    platform.move_to(next.position);
    target = next.position;
    predicted = known ? overlap_of(*chosen) : predicted_overlap_at(next.position);
    out.path_m += path.value_or(0.0);
    observer_->moved(rec, next, policy);
  }
  out.stopped_because = StopReason::kMaxScans;
  return out;
}

}  // namespace semioctree
