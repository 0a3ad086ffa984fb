// The synthetic scanner on the simulated robot as a survey platform (the survey stage's
// ScanPlatform), and the oracle policy that knows the scene. This library joins the two
// sides that otherwise know nothing of each other: the pipeline (semioctree::semioctree)
// and the simulator (semioctree::sim).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "semioctree/sim/coverage.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/robot.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "semioctree/survey.h"

namespace semioctree::sim_platform {

// The scene's scanner's range and elevation limits (position unused, no returns).
ScannerView scanner_limits(const sim::Scene& scene);

// The survey parameters a scene fixes: the scanner's range and elevation limits (map and
// NBV), the robot's radius and the scanner's height.
void apply_scene(const sim::Scene& scene, SurveyParams& params);

// The truth about one scan, known to the simulation only.
struct ScanTruth {
  sim::Pose2 true_pose, reported_pose;  // world frame; reported: odometry
  Eigen::Isometry3d scanner_to_world;   // true
  std::size_t points = 0;
  double scan_seconds = 0;
  std::optional<double> guess_error_m;          // the odometry guess's planar error (not scan 0)
  double pose_error_m = 0, pose_error_deg = 0;  // of the survey's estimate (after placed)
};

class SimulatedPlatform : public ScanPlatform {
 public:
  // Each placed scan's points (scanner frame) and the survey's estimate of its pose carried
  // into the world frame: what a coverage measure counts. Called from placed(); the points
  // are not kept after.
  using PlacedPoints =
      std::function<void(const Cloud& points, const Eigen::Isometry3d& scanner_to_world)>;

  // Scans `scene` with its scanner from its robot's start. `seed`: scanner noise
  // (seed·1000 + scan index) and odometry drift; `on_placed` (may be empty): see above.
  SimulatedPlatform(const sim::Scene& scene, std::uint64_t seed, unsigned threads,
                    PlacedPoints on_placed = {});

  // The scan at the robot's true pose; its reported pose is the survey's estimate of the
  // scan before moved by the odometry of the leg since (odometry drifts: only its
  // increments are trusted), with correction bounds from the robot's odometry noise.
  IncomingScan scan() override;
  void placed(const Eigen::Isometry3d& scanner_to_survey) override;
  // The last scan is forgotten (its truth too); the next one's odometry leg still starts
  // at the last placed scan.
  void rejected() override;
  void move_to(const Point3& target) override;  // survey frame, through the first scan

  const std::vector<ScanTruth>& truths() const { return truths_; }
  const sim::Robot& robot() const { return robot_; }
  const sim::Scene& scene() const { return scene_; }
  const sim::RayCaster& caster() const { return *caster_; }
  unsigned threads() const { return threads_; }
  // Survey frame → world: the first scan's estimate against its true pose.
  const Eigen::Isometry3d& survey_to_world() const { return survey_to_world_; }
  // Whether the scene lets the robot stand at `p` (survey frame, x and y): inside its
  // survey_area polygon, or anywhere without one. For SurveyParams::may_stand.
  bool in_survey_area(const Point3& p) const;
  // SurveyParams::may_stand for this platform (it must outlive the survey): in_survey_area,
  // or empty when the scene has no survey_area.
  std::function<bool(const Point3&)> survey_area_rule() const;
  // The true optical centre of every placed scan.
  const std::vector<Eigen::Vector3d>& optical_centres() const { return optical_centres_; }

 private:
  const sim::Scene& scene_;
  std::uint64_t seed_;
  unsigned threads_;
  PlacedPoints on_placed_;
  std::unique_ptr<sim::RayCaster> caster_;
  sim::Robot robot_;
  std::vector<ScanTruth> truths_;
  // The scan taken and not placed yet: its points are those handed to the survey (one copy).
  std::shared_ptr<const Cloud> last_points_;
  Eigen::Isometry3d last_sensor_to_world_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d survey_to_world_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d previous_estimate_ = Eigen::Isometry3d::Identity();
  sim::Pose2 previous_reported_;
  double previous_distance_ = 0;
  std::vector<Eigen::Vector3d> optical_centres_;
};

// Flags the reference samples that a placed scan's points cover, on `threads` workers (0:
// one per core): the body of a PlacedPoints that measures coverage.
void add_to_coverage(sim::CoverageAccumulator& coverage, const Cloud& points,
                     const Eigen::Isometry3d& scanner_to_world, unsigned threads = 0);

// The yardstick: scans every feasible candidate in the simulator and takes the safe one
// whose points cover the most reference samples not covered yet (greedy, perfect
// knowledge, among the planner's own candidates; the gains in decreasing order, up to the
// first safe candidate). `covered`: what the platform's placed scans have covered so far
// (fed by its PlacedPoints).
class OraclePolicy : public NextScanPolicy {
 public:
  // `progress(scanned, candidates)` now and then, from the survey's thread.
  OraclePolicy(const SimulatedPlatform& platform, const sim::CoverageAccumulator& covered,
               std::uint64_t seed, std::function<void(std::size_t, std::size_t)> progress = {});
  NextScanChoice choose(const ScanRecord& scan, const SurveyMap& map,
                        const RegistrationSafe& safe) override;
  const char* what() const override { return "oracle's choice"; }

 private:
  const SimulatedPlatform& platform_;
  const sim::CoverageAccumulator& covered_;
  std::uint64_t seed_;
  std::function<void(std::size_t, std::size_t)> progress_;
};

}  // namespace semioctree::sim_platform
