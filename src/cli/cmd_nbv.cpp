// `semioctree nbv --cloud FILE... [--pose X,Y,Z,YAW ...] [--global-align auto|on|off]
// --out DIR`: one map update and next best view for real scans. Each scan is placed by
// its --pose, or by the pose its file carries (PTX header, PCD/PLY viewpoint); otherwise
// the first scan is at the origin and the others are placed by global alignment, then
// ICP, against the scans before (docs/registration.md). Writes what a survey writes
// (survey.json, scan_NN/).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "cloud_input.h"
#include "commands.h"
#include "option_checks.h"
#include "planning_options.h"
#include "semioctree/scan_io.h"
#include "semioctree/survey.h"
#include "semioctree/timing.h"
#include "survey_output.h"

namespace semioctree::cli {

namespace {

struct NbvOptions {
  std::vector<std::string> clouds;
  std::vector<std::string> poses;
  std::string global_align = "auto";
  std::string out;
  PlanningOptions plan;
  double robot_radius = 0.5;
  bool scanned_by_robot = false;  // ReturnDirections::open_within with the robot's body
  double scanner_height = -1;     // < 0: the first scan's optical centre above the floor
  ScannerView limits;
};

// The map takes a scan's position and heading only; preprocessing levels the
// scan on its floor, so a tilt in its pose is dropped (said, not silent).
void warn_if_tilted(const Scan& s) {
  const Eigen::Vector3d up = s.pose.scanner_to_survey.linear() * Eigen::Vector3d::UnitZ();
  const double tilt_deg = std::acos(std::clamp(up.z(), -1.0, 1.0)) * 180.0 / M_PI;
  if (tilt_deg > 0.5)
    std::printf(
        "  note: the pose of %s is tilted by %.1f°; only its position and heading are "
        "used (the scan is levelled on its floor)\n",
        s.source.c_str(), tilt_deg);
}

void run_nbv(const NbvOptions& o) {
  const auto t_start = Clock::now();
  if (!o.poses.empty() && o.poses.size() != o.clouds.size())
    throw std::invalid_argument("give one --pose per --cloud file (" +
                                std::to_string(o.clouds.size()) + " files, " +
                                std::to_string(o.poses.size()) + " poses)");
  if (o.global_align == "on" && !o.poses.empty())
    throw std::invalid_argument(
        "--global-align on places every scan after the first without its pose: give no --pose");
  check_scanner_limits(o.limits);
  {
    std::vector<NamedPath> inputs;
    for (const std::string& f : o.clouds) inputs.push_back({"--cloud", f});
    check_outputs_spare_inputs(inputs, {}, {{{"--out", o.out}, survey_files_written()}});
  }
  SurveyParams p;
  p.map.limits = o.limits;
  apply_planning_options(o.plan, p);
  p.robot.radius = o.robot_radius;
  // Read everything first: a bad file fails before any work is done.
  std::vector<Scan> scans;
  for (std::size_t i = 0; i < o.clouds.size(); ++i) {
    for (Scan& s : read_scans(o.clouds[i])) {
      if (!o.poses.empty()) s.pose = parse_pose(o.poses[i]);
      check_scan_usable(s, &o.limits);
      std::printf("read %s: %zu points (%zu invalid dropped)\n", s.source.c_str(), s.points->size(),
                  s.invalid_dropped);
      scans.push_back(std::move(s));
    }
  }
  std::unique_ptr<SurveyOutput> output;
  std::unique_ptr<Survey> survey;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Scan& s = scans[i];
    // Placed by --pose or the file's pose (PTX header, PCD/PLY viewpoint); the first
    // scan without one at the origin; the others without one (or all after the first
    // with --global-align on) by global alignment then ICP, or with --global-align off
    // by ICP from the origin.
    const bool has_pose = !o.poses.empty() || s.pose_from_file;
    const bool global =
        i > 0 && (o.global_align == "on" || (o.global_align == "auto" && !has_pose));
    const bool posed = !global && (has_pose || i == 0);
    const char* how = global  ? (has_pose ? "its pose ignored (--global-align on): placed by "
                                            "global alignment, then ICP"
                                          : "no pose: placed by global alignment, then ICP")
                      : posed ? (has_pose ? "placed by its pose" : "no pose: at the origin")
                              : "no pose: ICP from the origin (--global-align off)";
    std::printf("scan %zu: %s (%s)\n", i, s.source.c_str(), how);
    if (!survey) {
      // The robot's scanner height: the first scan's optical centre above its floor.
      if (o.scanner_height > 0) {
        p.robot.scanner_height = o.scanner_height;
      } else {
        const PreprocessResult pre =
            preprocess(*within_limits(s.points, p.map.limits), p.preprocess);
        p.robot.scanner_height = pre.transform.translation().z();
        std::printf("  scanner height above the floor: %.2f m\n", p.robot.scanner_height);
      }
      output = std::make_unique<SurveyOutput>(o.out, p);
      survey = std::make_unique<Survey>(p, output.get());
    }
    if (posed && has_pose) warn_if_tilted(s);
    IncomingScan in;
    in.points = s.points;
    in.points_raw = s.points->size() + s.invalid_dropped;
    in.x = posed ? s.pose.position().x() : 0.0;
    in.y = posed ? s.pose.position().y() : 0.0;
    in.yaw_deg = posed ? s.pose.yaw_deg() : 0.0;
    in.placement = global  ? ScanPlacement::kNoPose
                   : posed ? ScanPlacement::kExact
                           : ScanPlacement::kRefine;
    in.from_robot = o.scanned_by_robot;
    try {
      output->scan_done(survey->add_scan(in), survey->map());
    } catch (const RegistrationError& e) {
      // As the survey does: the map of the scans before is written, with the reason.
      const std::string error = std::string(e.what()) + " in " + o.out;
      nlohmann::json extra = {{"inputs", o.clouds}, {"error", error}};
      output->write_survey_json("registration_failed", extra, &survey->map());
      throw RegistrationError(error);
    }
  }
  const ScanRecord& last = survey->records().back();
  std::string why = "stop_percentage";
  if (!last.nbv.best)
    why = "no_candidate";
  else if (last.nbv.stop_percent >= o.plan.stop)
    why = "max_scans";  // the scans given are all there is; more are needed
  nlohmann::json extra;
  extra["inputs"] = o.clouds;
  extra["seconds_total"] = seconds_since(t_start);
  output->write_survey_json(why, extra, &survey->map());
  if (last.nbv.best)
    std::printf(
        "next best view: (%.3f, %.3f, %.3f), score %.1f; stop percentage %.3f %% (%s %.3f "
        "%%)\n",
        last.nbv.best->position.x, last.nbv.best->position.y, last.nbv.best->position.z,
        last.nbv.best->score, last.nbv.stop_percent,
        last.nbv.stop_percent < o.plan.stop ? "below the threshold" : "threshold", o.plan.stop);
  else
    std::printf("no feasible next best view\n");
  std::printf("wrote %s/survey.json and scan_NN/\n", o.out.c_str());
}

}  // namespace

void add_nbv_command(CLI::App& app) {
  auto o = std::make_shared<NbvOptions>();
  auto* cmd = app.add_subcommand(
      "nbv",
      "One map update and next best view for real scans: preprocess each scan, place it by its "
      "pose (--pose, or the pose its file carries: a PTX header, a PCD/PLY viewpoint), or else "
      "(the first scan at the origin) place it against the scans before by global alignment "
      "and ICP, build the semioctree "
      "(occupancy, doors and windows, occlusion), score the candidate positions and report the "
      "next best view and the stop percentage. Returns outside the scanner's limits (--min-range, "
      "--elevation-min: on a robot, the lowest elevation that clears its body) are dropped: they "
      "are the scanner's mount and the robot. Writes survey.json, report.html and scan_NN/ as "
      "`survey` does.");
  cmd->add_option("--cloud", o->clouds,
                  "scan file: .pcd, .ply, .xyz/.txt or .ptx (repeat for several scans)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--pose", o->poses,
                  "scanner pose X,Y,Z[,YAW_DEG] of each --cloud in the survey frame (default: "
                  "the pose the file carries (PTX header, PCD/PLY viewpoint); without one, the "
                  "first scan at the origin and the others placed by --global-align)");
  cmd->add_option("--global-align", o->global_align,
                  "scans after the first: auto = those without a pose are placed by global "
                  "alignment (a search over x, y and heading of the walls' outline, then ICP; "
                  "refused when no placement overlaps enough or two fit alike, e.g. a "
                  "symmetric empty room); on = every one is, its pose ignored (not with "
                  "--pose); off = those without a pose are refined by ICP from the origin "
                  "(scans taken close to the first, facing the same way)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out,
                  "output directory (a survey.json and scan_NN/ folders of an earlier run "
                  "there are replaced)")
      ->required();
  add_planning_options(*cmd, o->plan);
  cmd->add_option("--robot-radius", o->robot_radius, "safety cylinder radius, m (0.05 to 5)")
      ->check(finite_in(0.05, 5))
      ->capture_default_str();
  cmd->add_option("--scanner-height", o->scanner_height,
                  "scanner optical centre above the floor, m (default: from the first scan)")
      ->check(finite_positive(100));
  cmd->add_flag("--scanned-by-robot", o->scanned_by_robot,
                "the scans were taken from the robot of --robot-radius and --scanner-height: "
                "nothing but the robot stood within its radius, so a direction without returns "
                "that its body holds up to --min-range met nothing within range (space seen, "
                "not hidden). Without it (a tripod, or not known) a direction without returns "
                "stays hidden unless the hole in the returns it lies in has all its edge returns "
                "at least twice --min-range away (a window, a door: docs/occlusion.md)");
  add_scanner_limit_options(*cmd, o->limits);
  cmd->callback([o] { run_nbv(*o); });
}

}  // namespace semioctree::cli
