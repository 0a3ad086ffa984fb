// The survey stage (paper 2.3): scan → preprocess → register → update the map → next
// best view → move, repeated until the stop percentage (Eq 5) falls below its threshold,
// no feasible candidate remains, or the scan budget is spent. The stage neither prints
// nor writes files: progress and per-scan records reach a SurveyObserver; the scans come
// from a ScanPlatform (a simulated robot, a person with a scanner); where to scan next is
// a NextScanPolicy's choice. docs/data-flow.md ("The survey loop") tells its rules.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "semioctree/global_registration.h"
#include "semioctree/nbv.h"
#include "semioctree/preprocess.h"
#include "semioctree/registration.h"
#include "semioctree/update.h"

namespace semioctree {

// What the survey plans over (docs/data-flow.md, "Scope").
enum class SurveyScope {
  kRoom,   // the room the scans stand in (room_box): the survey ends when it is complete
  kFloor,  // room by room: the robot's room until it is complete, then the nearest open
           // room by path, through a door; ends when every reachable room is complete
  kMap,    // the whole map as one room (Eq 5 as the paper reads when the grid is the room)
};
const char* to_string(SurveyScope scope);  // "room", "floor", "map"
// The scope named `name`; throws std::invalid_argument naming the accepted ones.
SurveyScope survey_scope_from_string(const std::string& name);

struct SurveyParams {
  SurveyMapParams map;
  PreprocessParams preprocess;
  RegistrationParams registration;
  GlobalAlignParams global_align;  // scans without a pose (ScanPlacement::kNoPose)
  // Its room, grid anchor, overlap_top, min_overlap and progress are set by the survey.
  NbvParams nbv;
  RobotGeometry robot;
  double stop_percent = 0.1;  // Eq 5 threshold, %
  SurveyScope scope = SurveyScope::kFloor;
  // Where the robot may stand (x, y of the scanner; the survey area a user gives).
  // Empty: wherever it can reach.
  std::function<bool(const Point3&)> may_stand;
  std::size_t max_scans = 10;  // Survey::run's scan budget (at least 1)
  // Survey::run's path budget, m: the survey ends before a move that would take the
  // robot's path beyond it. None: no budget.
  std::optional<double> max_path_m;
  // The predicted overlap a candidate's scan needs with the map (NbvParams::min_overlap;
  // docs/nbv.md). None: the share registration itself needs, registration.min_overlap.
  std::optional<double> min_overlap;
  // Survey::run: failed registrations in a row recovered from by a scan nearer the last
  // placed one (Survey::waypoint_toward); 0: the first failure ends the survey.
  std::size_t max_recoveries = 3;
};

// What the reported pose of a scan is worth. The first scan is always placed by its
// pose (the origin without one): it defines the survey frame.
enum class ScanPlacement {
  kRefine,  // a guess (odometry): refined by ICP against the scans before
  kExact,   // taken as it is (a pose surveyed or given by the user)
  kNoPose,  // none: global alignment against the scans before, then ICP (x, y, yaw unused)
};

// How a scan was placed (ScanRecord::placed_by).
// kPoseGlobalAndIcp: ICP from the reported pose failed, and the global alignment found a
// placement within what the platform's pose can be wrong by (IncomingScan::max_correction_*).
enum class PlacedBy { kPose, kPoseAndIcp, kGlobalAndIcp, kPoseGlobalAndIcp };
// "pose", "pose+icp", "global+icp", "pose+global+icp"
const char* to_string(PlacedBy placed_by);

// One scan as the platform delivers it: points in the scanner frame and the planar pose
// the platform reports (odometry, or the pose a user gave), survey frame.
struct IncomingScan {
  Cloud::Ptr points;
  double x = 0, y = 0, yaw_deg = 0;
  ScanPlacement placement = ScanPlacement::kRefine;
  // How far the reported pose can be wrong: a larger ICP correction is a false match
  // (0: no bound).
  double max_correction_m = 0, max_correction_deg = 0;
  std::size_t points_raw = 0;  // before invalid points were dropped (0: points->size())
  // Taken from the robot of SurveyParams::robot: nothing but the robot stood within its
  // safety cylinder, so directions without returns that the cylinder holds up to the
  // minimum range are open (ReturnDirections::open_within). false: a tripod or unknown.
  bool from_robot = true;
};

// A room of the floor (SurveyScope::kFloor) as one scan's planning left it.
enum class RoomState {
  kComplete,     // its Eq 5 is below the stop percentage
  kOpen,         // not complete: the next scan is planned for it
  kUnreachable,  // the robot can stand nowhere in it (RoomStatus::why)
  kNotJudged,    // not looked at: the robot's room was still open
};
const char* to_string(RoomState state);  // "complete", "open", "unreachable", "not_judged"

struct RoomStatus {
  Room room;  // cells, area, bounds, the openings on its border
  RoomState state = RoomState::kNotJudged;
  std::optional<double> stop_percent;  // Eq 5 in its box from its best candidate, if judged
  std::optional<double> path_m;        // the robot's path to its nearest candidate
  std::vector<std::size_t> scans;      // indices of the scans that stood in it
  std::string why;                     // kUnreachable: why
};

// What the survey did with one scan; filled stage by stage (SurveyObserver::stage_done).
struct ScanRecord {
  std::size_t index = 0;
  Eigen::Isometry3d scanner_to_survey = Eigen::Isometry3d::Identity();  // estimated
  std::size_t points_raw = 0, points_kept = 0, points_outside_limits = 0;
  double ceiling_height = 0, tilt_alpha_deg = 0, tilt_beta_deg = 0;  // preprocessing
  bool ceiling_found = false;  // else levelled by the floor alone (PreprocessResult)
  RoomHeightFrom height_from = RoomHeightFrom::kCeiling;
  PlacedBy placed_by = PlacedBy::kPose;
  struct Registration {
    RegistrationResult icp;
    double scanner_shift_m = 0;  // how far ICP moved the scanner (from the pose or the guess)
    std::optional<GlobalAlignResult> global;  // the guess of a scan without a pose
    // Why ICP from the reported pose failed, when the global alignment recovered the
    // scan (PlacedBy::kPoseGlobalAndIcp); empty otherwise.
    std::string pose_icp_failure;
  };
  std::optional<Registration> registration;  // none for the first or a posed scan
  ScanUpdateReport update;
  SurveyScope scope = SurveyScope::kRoom;
  std::optional<RoomBox> room;  // where targets and Eq 5 were counted (none: whole map)
  // kFloor: the rooms of the map at this scan (segment_rooms, those the robot's footprint
  // fits in), the one the scan stands in and the one the NBV was planned for.
  std::vector<RoomStatus> rooms;
  std::optional<std::size_t> in_room, planned_room;  // indices into `rooms`
  // kFloor: the door the NBV stands in to look into a room not seen yet (an index into
  // the map's openings), when no room was open.
  std::optional<std::size_t> planned_doorway;
  // The scope is done: Eq 5 from the NBV is below the stop percentage (kFloor: in every
  // room the robot can reach, and no door is left to look through).
  bool scope_complete = false;
  NbvResult nbv;  // candidates, their scores, the best one, Eq 5
  // Survey::run: the overlap with the map predicted for this scan's position when it was
  // chosen (predict_overlap, as the NBV predicts it), to set beside registration's
  // overlap; none for the first scan.
  std::optional<double> predicted_overlap;
  // Survey::run: the robot's path to this scan's position from where it stood (the scan
  // before, or a scan that could not be registered), over the cells its safety cylinder
  // clears (NbvCandidate::path_m); none for the first scan.
  std::optional<double> path_m;
  // Survey::run: that path itself (RouteTree::route_to: the robot's cell, its turns, the
  // scan's cell); empty for the first scan.
  std::vector<Point3> route;
  // Wall seconds of the stages; `returns`: the directions of the scan's returns
  // (return_directions, read from the scan before its decimation).
  struct Seconds {
    double preprocess = 0, registration = 0, returns = 0, occupancy = 0, openings = 0,
           occlusion = 0, nbv = 0, total = 0;
  } seconds;

  Point3 scanner() const;  // the optical centre, survey frame
  // Eq 5 from the NBV; none without a feasible candidate.
  std::optional<double> stop_percent() const;
};

enum class SurveyStage { kPreprocessed, kRegistered, kMapped, kRoomFound, kPlanned };

// Why Survey::run ended. kRegistrationFailed leaves the map of the scans before intact.
// kStopPercentage: with SurveyScope::kFloor, every room the robot can reach is complete.
enum class StopReason { kStopPercentage, kMaxScans, kMaxPath, kNoCandidate, kRegistrationFailed };
const char* to_string(StopReason reason);  // "stop_percentage", "max_scans", "max_path", ...

// Where to scan next, and what the policy predicted the scan adds (if it knows).
struct NextScanChoice {
  Point3 position;  // survey frame, a feasible candidate
  std::optional<double> predicted_gain_percent;
};

// Whether a scan at a candidate could be registered: the overlap with the map predicted
// for it (NbvCandidate::predicted_overlap, or predict_overlap as the NBV predicts it) is at
// least the survey's minimum (NbvParams::min_overlap). The NBV's own best passed it.
using RegistrationSafe = std::function<bool(const NbvCandidate&)>;

// Chooses the next scan position among the feasible, scored candidates.
class NextScanPolicy {
 public:
  virtual ~NextScanPolicy() = default;
  // `scan.nbv.candidates` is not empty when this is called; at least one of them is
  // `safe` (the NBV's best). A policy chooses among the safe ones, so that policies
  // compared differ in their choice, not in how often their scans fail to register.
  virtual NextScanChoice choose(const ScanRecord& scan, const SurveyMap& map,
                                const RegistrationSafe& safe) = 0;
  virtual const char* what() const = 0;  // a noun for messages: "NBV", ...
};

// The paper's policy: the best-scoring candidate (the NBV).
class BestScorePolicy : public NextScanPolicy {
 public:
  NextScanChoice choose(const ScanRecord& scan, const SurveyMap& map,
                        const RegistrationSafe& safe) override;
  const char* what() const override { return "NBV"; }
};

// The baseline: a safe candidate drawn uniformly (mt19937_64 seeded with `seed`): the
// candidates in a random order, the first safe one.
class RandomCandidatePolicy : public NextScanPolicy {
 public:
  explicit RandomCandidatePolicy(std::uint64_t seed) : rng_(seed) {}
  NextScanChoice choose(const ScanRecord& scan, const SurveyMap& map,
                        const RegistrationSafe& safe) override;
  const char* what() const override { return "random candidate"; }

 private:
  std::mt19937_64 rng_;
};

// A scan Survey::run could not register, and where it scanned again.
struct RegistrationFailure {
  std::size_t after_scan = 0;  // index of the last placed scan before it
  Point3 position;             // where the failed scan was asked for (survey frame)
  std::string error;
  std::optional<Point3> retry;   // the recovery position; none: the survey ended
  std::optional<double> path_m;  // the robot's path to `position` (as ScanRecord::path_m)
  std::vector<Point3> route;     // and that path (as ScanRecord::route)
};

// Where the scans come from and how the scanner moves.
class ScanPlatform {
 public:
  virtual ~ScanPlatform() = default;
  // A scan at the current position.
  virtual IncomingScan scan() = 0;
  // The survey placed the last scan at this pose (survey frame): Survey::run calls it as
  // soon as the scan is placed, before the map is updated with it.
  virtual void placed(const Eigen::Isometry3d& scanner_to_survey) { (void)scanner_to_survey; }
  // The survey could not place the last scan: it is dropped, and the odometry of the
  // leg runs on from the last placed scan.
  virtual void rejected() {}
  // Moves the scanner to `target` (survey frame; its z is ignored).
  virtual void move_to(const Point3& target) = 0;
};

// Progress and records. Every call comes from the thread running the survey, except
// candidates_scored (from scoring threads: make it thread-safe).
class SurveyObserver {
 public:
  virtual ~SurveyObserver() = default;
  virtual void scan_taken(std::size_t index, const IncomingScan& scan) { (void)index, (void)scan; }
  virtual void stage_done(SurveyStage stage, const ScanRecord& scan) { (void)stage, (void)scan; }
  virtual void candidates_scored(std::size_t done, std::size_t total) { (void)done, (void)total; }
  // Survey::run: the scan is mapped and placed on the platform.
  virtual void scan_done(const ScanRecord& scan, const SurveyMap& map) { (void)scan, (void)map; }
  // The map given to scan_done is about to change (the next scan's update) or to go (the
  // Survey's destructor): an observer still reading it on a thread of its own must be
  // done with it when this returns. What it throws ends the scan as an error would
  // (the destructor ignores it).
  virtual void map_changing() {}
  // Survey::run: the platform moved to `choice`, chosen by `policy`.
  virtual void moved(const ScanRecord& scan, const NextScanChoice& choice,
                     const NextScanPolicy& policy) {
    (void)scan, (void)choice, (void)policy;
  }
  // Survey::run: a scan could not be registered (and, with `failure.retry`, the platform
  // moved there to scan again).
  virtual void registration_failed(const RegistrationFailure& failure) { (void)failure; }
};

struct SurveyOutcome {
  StopReason stopped_because = StopReason::kMaxScans;
  std::string error;                                       // kRegistrationFailed: why
  std::vector<RegistrationFailure> registration_failures;  // recovered from, or the last
  double path_m = 0;  // the robot's path over the survey (to failed scans and retries too)
};

// Where a doorway position (Survey::doorway_positions) stands for a look through `door`
// into its side `side` (±1 along its wall normal): within half the door's width of its
// centre (in the opening); on the side looked into; within 10° of its normal on the near
// side; or off the normal to one side or the other (along the wall, seen from `side`).
enum class DoorwayView { kInOpening, kBeyond, kStraight, kFromOneSide, kFromTheOther };
DoorwayView doorway_view(const DetectedOpening& door, int side, const Eigen::Vector3d& at);

// A stop on the robot's way (Survey::waypoint_toward).
struct Waypoint {
  Point3 position;    // a position the robot can stand at (scanner height)
  double path_m = 0;  // the robot's path to it
};

class Survey {
 public:
  // Throws std::invalid_argument for max_scans < 1.
  // `observer` (if any) must outlive the Survey.
  explicit Survey(const SurveyParams& params, SurveyObserver* observer = nullptr);
  ~Survey();  // tells the observer the map goes (map_changing)
  Survey(const Survey&) = delete;
  Survey& operator=(const Survey&) = delete;

  // One scan through preprocess → register → update → NBV, reporting each stage.
  // `robot_position`: where the robot stands (default: under the scanner).
  // `predicted_overlap`: the overlap predicted for where the scan was taken
  // (predict_overlap); a placement sharing less than half of it with the map has slid to
  // a wrong fit (docs/registration.md, "A placement that slid"): from the reported pose
  // the global alignment is tried instead, and if that one is no better the scan fails.
  // Throws RegistrationError (the map is left as it was) when ICP or the global alignment
  // fails (no placement, or an ambiguous one) or a scan finds another floor,
  // PreprocessError when the scan cannot be levelled.
  // The scan's points are let go once their directions are read: a caller that hands the
  // scan over (std::move) holds them no longer than that.
  const ScanRecord& add_scan(IncomingScan scan,
                             const std::optional<Point3>& robot_position = std::nullopt,
                             std::optional<double> predicted_overlap = std::nullopt);

  // The loop: scans from `platform` until the stop percentage (kFloor: in every room
  // the robot can reach), no candidate, the scan budget or the path budget ends it; moves to
  // `policy`'s choice in between. A scan that cannot be registered is dropped
  // (ScanPlatform::rejected) and taken again at the waypoint_toward it from the last placed
  // scan at most half the path there, then a quarter, ... up to SurveyParams::max_recoveries
  // times in a row; then the survey ends (kRegistrationFailed with the error). It does not
  // throw for a failed registration.
  SurveyOutcome run(ScanPlatform& platform, NextScanPolicy& policy);

  // A stop on the robot's way from `from` towards `to`, `to_m` away by path: of the
  // positions it can stand at (find_candidates from `from`, as the NBV finds them), those
  // at most `max_path_m` from `from` by path, and nearer it than every position of `tried`
  // that is one of them, the one nearest `to` by path (ties: nearer `from`), if it is
  // nearer `to` than `to_m`. Survey::run sends the robot back there after a failed
  // registration.
  std::optional<Waypoint> waypoint_toward(const Point3& from, const Point3& to, double to_m,
                                          double max_path_m,
                                          const std::vector<Point3>& tried = {}) const;

  const SurveyMap& map() const { return map_; }
  const std::vector<ScanRecord>& records() const { return records_; }
  const SurveyParams& params() const { return params_; }

 private:
  // `placed` (a scan placed by its reported pose `place`) aligned globally to the merged
  // cloud, kept only within the pose's bounds (the scanner's shift goes to
  // `scanner_shift_m`); else RegistrationError with both reasons.
  GlobalAlignResult recover_by_global_alignment(const Cloud& placed, const Eigen::Isometry3d& place,
                                                const IncomingScan& in, const SurfaceFacing& facing,
                                                const std::string& pose_failure,
                                                double* scanner_shift_m) const;

  // add_scan, calling `placed` with the scan's pose (survey frame) as soon as it is placed,
  // before its points are read for their directions and the map is updated (Survey::run
  // tells the platform then, which lets it free its copy of the points).
  const ScanRecord& add_scan_telling(IncomingScan scan, const std::optional<Point3>& robot_position,
                                     std::optional<double> predicted_overlap,
                                     const std::function<void(const Eigen::Isometry3d&)>& placed);

  // The NBV's parameters for the map as it stands: the candidate grid's anchor, where
  // candidates may stand, the overlap rule.
  NbvParams nbv_params() const;
  // Stages 6-7 of SurveyScope::kFloor: fills rec.rooms, rec.in_room, rec.planned_room,
  // rec.room and rec.nbv (docs/data-flow.md, "Scope").
  void plan_floor(ScanRecord& rec, const NbvParams& nbv, const Point3& robot);

  // A doorway scan: the door's centre, the side looked into, and from where.
  struct DoorwayScan {
    Point3 door;
    int side = 1;
    DoorwayView view = DoorwayView::kStraight;
  };
  // A doorway scan planned (plan_floor): its NBV result, the door looked through (an
  // index into the map's openings), what lies beyond it, and the scan to record if it is
  // taken.
  struct DoorwayChoice {
    NbvResult nbv;
    std::size_t door = 0;
    RoomBox beyond;
    DoorwayScan scan;
  };
  // The nearest doorway scan that looks through a door into a side the robot cannot stand
  // in yet (docs/nbv.md, "Looking through a door again"); `rooms`, the index of each of
  // its rooms in the record's rooms (`status_of`), the candidates in each of those and
  // all candidates as plan_floor found them.
  std::optional<DoorwayChoice> plan_doorway_scan(
      const RoomMap& rooms, const std::vector<std::optional<std::size_t>>& status_of,
      const std::vector<std::vector<NbvCandidate>>& in_room, const std::vector<NbvCandidate>& all,
      const NbvParams& nbv);

  // Where a linking scan may stand at `door`: in the opening, and in front of it on
  // either side where the scanner sees the floor just beyond the opening: straight in
  // front, and up to 60° off the wall's normal (NbvParams::doorways).
  std::vector<Eigen::Vector3d> doorway_positions(const DetectedOpening& door) const;

  // The overlap a scan at `position` is predicted to have with the map (as the NBV's
  // candidates are judged).
  double predicted_overlap_at(const Point3& position) const;
  // The robot's path from `from` to `to` (a candidate of the last scan): its length (m)
  // and route (RouteTree::route_to); none if `to` is no candidate from there.
  struct Drive {
    double m = 0;
    std::vector<Point3> route;
  };
  std::optional<Drive> drive_between(const Point3& from, const Point3& to) const;

  SurveyParams params_;
  SurveyObserver* observer_;
  SurveyObserver silent_;
  SurveyMap map_;
  std::vector<ScanRecord> records_;
  // kFloor: the rooms found complete (a room holding one's point, with about its bounds,
  // stays complete).
  struct CompleteRoom {
    Point3 at;        // a point in it
    Point3 min, max;  // its bounds then (Room::min, max)
  };
  std::vector<CompleteRoom> complete_rooms_;
  // kFloor: the doorway scans planned (each door side is looked through once from each
  // kind of position).
  std::vector<DoorwayScan> doorway_scans_;
};

// Heading of a pose (its x axis in the horizontal plane), degrees.
double yaw_deg_of(const Eigen::Isometry3d& pose);

}  // namespace semioctree
