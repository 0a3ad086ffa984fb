// The scan loop shared by `semioctree survey` (simulated robot) and
// `semioctree nbv` (real scans): preprocess → register → update → NBV for one
// scan at a time, with a progress line per stage, the per-scan output files
// and the survey.json record (DESIGN.md "Outputs of a survey").
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "semioctree/nbv.h"
#include "semioctree/preprocess.h"
#include "semioctree/registration.h"
#include "semioctree/update.h"

namespace semioctree::cli {

struct SessionParams {
  SurveyMapParams map;
  PreprocessParams preprocess;
  RegistrationParams registration;
  NbvParams nbv;
  RobotGeometry robot;
  double stop_percent = 0.1;
  bool room_only = true;  // NbvParams::room from room_box at every NBV
  std::string out;
};

// The options `survey` and `nbv` share: the grid, the NBV, the stop
// threshold, decimation and threads.
struct PlanningOptions {
  double leaf = 0.05, coarse = 0.8;
  double stop = 0.1;
  int method = 1;
  int level = -1;  // method 2: the level scored (-1: the leaf)
  double candidate_spacing = 0.5;
  std::size_t target_points = 400000;
  unsigned threads = 0;
  bool whole_map = false;  // count targets and Eq 5 over the whole map, not the room
};
void add_planning_options(CLI::App& cmd, PlanningOptions& o);
// Fills `p` from them (the grid is the semioctree, or with `homogeneous` the
// grid of leaf-size voxels; the scanner limits are set by the caller and
// copied to the NBV). Throws std::invalid_argument on a --level the grid lacks.
void apply_planning_options(const PlanningOptions& o, SessionParams& p, bool homogeneous = false);

// One scan as it comes in: points in the scanner frame and the pose the
// scanner's platform reports (odometry, or the pose a user gave).
struct IncomingScan {
  Cloud::Ptr points;
  double x = 0, y = 0, yaw_deg = 0;  // reported planar pose (survey frame)
  bool registered = true;            // refine by ICP against the previous scans (not the first)
  // How far the reported pose can be wrong: a larger ICP correction fails
  // (0: no bound). The simulated robot knows its odometry noise and the leg.
  double max_correction_m = 0, max_correction_deg = 0;
  std::size_t points_raw = 0;  // before NaN removal
};

struct ScanOutcome {
  Eigen::Isometry3d scanner_to_survey = Eigen::Isometry3d::Identity();  // estimated
  Cloud::Ptr registered;  // preprocessed points in the survey frame
  std::optional<NbvCandidate> nbv;
  std::vector<NbvCandidate> candidates;  // every feasible candidate, scored
  double stop_percent = 0;
  nlohmann::json record;  // the scan's entry of survey.json
};

class SurveySession {
 public:
  explicit SurveySession(const SessionParams& params);

  // Runs the stages for one scan, writes scan_NN/ and returns what the caller
  // needs to move on. Throws RegistrationError (with a message saying the map
  // was left as it was) when ICP fails.
  ScanOutcome add_scan(const IncomingScan& scan, const std::optional<Point3>& robot_position = {});

  // survey.json with `stopped_because` and any extra top-level keys.
  void write_survey_json(const std::string& stopped_because, const nlohmann::json& extra) const;

  const SurveyMap& map() const { return map_; }
  std::size_t scans() const { return records_.size(); }
  nlohmann::json& last_record() { return records_.back(); }

 private:
  SessionParams params_;
  SurveyMap map_;
  std::vector<nlohmann::json> records_;
};

// survey.json's "octants" of a map (total, by_level, by_label), and its
// "volume_percent" (Table 1's labels) into `volume_percent_out`.
nlohmann::json octants_json(const SemiOcTree& tree, nlohmann::json& volume_percent_out);

// x, y, z and heading of a scanner pose.
nlohmann::json pose_json(const Eigen::Isometry3d& scanner_to_survey);
double yaw_deg_of(const Eigen::Isometry3d& pose);

// Says so when the leaf is coarser than the robot's ground clearance (obstacles in the
// floor's leaf layer are then driven over, see floor_layer_clearance).
void print_floor_layer_note(const RobotGeometry& robot, double leaf);

// Removes survey.json and the scan_NN/ folders an earlier run left in `dir`
// (nothing else); SurveySession does it when it starts.
void clear_previous_survey(const std::string& dir);

}  // namespace semioctree::cli
