// What `survey` and `nbv` print and write while the survey stage runs: a progress line
// per stage, scan_NN/ (the map files, slice.png, cloud.ply) per scan, and survey.json
// (docs/outputs.md). An observer of the stage: the stage itself neither prints nor writes.
#pragma once

#include <future>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "progress_line.h"
#include "semioctree/survey.h"

namespace semioctree::cli {

class SurveyOutput : public SurveyObserver {
 public:
  // Removes what an earlier survey left in `dir` (survey.json, scan_NN/,
  // coverage_missed.ply; nothing else) and says when the leaf is coarser than the
  // robot's ground clearance.
  SurveyOutput(std::string dir, const SurveyParams& params);

  void stage_done(SurveyStage stage, const ScanRecord& scan) override;
  void candidates_scored(std::size_t done, std::size_t total) override;
  // Keeps the scan's survey.json record and writes scan_NN/ on a thread of its own beside
  // the next scan's stages up to its update (map_changing); a write that fails there
  // throws from map_changing, or from write_survey_json.
  void scan_done(const ScanRecord& scan, const SurveyMap& map) override;
  // Waits for scan_NN/ to be written and says so.
  void map_changing() override;
  // Says so and keeps it for survey.json's "registration_failures".
  void registration_failed(const RegistrationFailure& failure) override;

  // The record of scan `index` (after scan_done), for keys a command adds.
  nlohmann::json& record(std::size_t index) { return records_.at(index); }
  // survey.json with `stopped_because` and any extra top-level keys, then report.html
  // from it (after the last scan_NN/ is written).
  void write_survey_json(const std::string& stopped_because, const nlohmann::json& extra,
                         const SurveyMap* map);
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  SurveyParams params_;
  std::unique_ptr<CountProgress> progress_;  // one per NBV, while candidates are scored
  std::vector<nlohmann::json> records_;
  std::vector<std::vector<Point3>> routes_;  // the robot's drives so far, for the slices
  nlohmann::json failures_ = nlohmann::json::array();
  // The scan_NN/ being written: its scan and folder, and the seconds it took (the future
  // holds the write's error, if any).
  struct PendingWrite {
    std::size_t index = 0;
    std::string dir;
    std::future<double> seconds;
  };
  PendingWrite writing_;
};

// survey.json's "octants" of a map (total, by_level, by_label), and its
// "volume_percent" (Table 1's labels) into `volume_percent_out`.
nlohmann::json octants_json(const SemiOcTree& tree, nlohmann::json& volume_percent_out);

// x, y, z and heading of a scanner pose.
nlohmann::json pose_json(const Eigen::Isometry3d& scanner_to_survey);
// A route (ScanRecord::route) as [[x, y], ...], to the millimetre.
nlohmann::json route_json(const std::vector<Point3>& route);
// A floor's rooms (ScanRecord::rooms): id, state, area, bounds, openings, scans, Eq 5, path.
nlohmann::json rooms_json(const std::vector<RoomStatus>& rooms);

// Says so when the leaf is coarser than the robot's ground clearance (obstacles in the
// floor's leaf layer are then driven over, see floor_layer_clearance).
void print_floor_layer_note(const RobotGeometry& robot, double leaf);

// Removes survey.json, coverage_missed.ply, the report (survey_report_files) and the
// scan_NN/ folders an earlier run left in `dir` (nothing else).
void clear_previous_survey(const std::string& dir);
// What a survey writes or replaces in its directory (as OutputDir::written).
std::vector<std::string> survey_files_written();

}  // namespace semioctree::cli
