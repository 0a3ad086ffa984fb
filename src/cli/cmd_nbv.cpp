// `semioctree nbv --cloud FILE... [--pose X,Y,Z,YAW ...] --out DIR`: one map
// update and next best view for real scans. With poses, each scan is placed by
// its pose; without, the first scan is at the origin and the others are
// registered to it by ICP. Writes what a survey writes (survey.json, scan_NN/).
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "commands.h"
#include "semioctree/scan_io.h"
#include "survey_session.h"

namespace semioctree::cli {

namespace {

struct NbvOptions {
  std::vector<std::string> clouds;
  std::vector<std::string> poses;
  std::string out;
  double leaf = 0.05, coarse = 0.8;
  double stop = 0.1;
  int method = 1;
  int level = -1;  // method 2: the level scored (-1: the leaf)
  double robot_radius = 0.5;
  double scanner_height = -1;  // < 0: the first scan's optical centre above the floor
  std::size_t target_points = 400000;
  double candidate_spacing = 0.5;
  ScannerView limits;
  unsigned threads = 0;
};

void run_nbv(const NbvOptions& o) {
  const auto t_start = std::chrono::steady_clock::now();
  if (!o.poses.empty() && o.poses.size() != o.clouds.size())
    throw std::invalid_argument("give one --pose per --cloud file (" +
                                std::to_string(o.clouds.size()) + " files, " +
                                std::to_string(o.poses.size()) + " poses)");
  SemiOcTree::coarse_level_for(o.leaf, o.coarse);
  // Read everything first: a bad file fails before any work is done.
  std::vector<Scan> scans;
  for (std::size_t i = 0; i < o.clouds.size(); ++i) {
    for (Scan& s : read_scans(o.clouds[i])) {
      if (!o.poses.empty()) s.pose = parse_pose(o.poses[i]);
      std::printf("read %s: %zu points (%zu invalid dropped)\n", s.source.c_str(), s.points->size(),
                  s.invalid_dropped);
      scans.push_back(std::move(s));
    }
  }
  const bool posed =
      !o.poses.empty() || scans.size() == 1 || o.clouds.size() == 1;  // PTX files carry their poses
  SessionParams p;
  p.out = o.out;
  p.map.grid = {o.leaf, o.coarse, 0.0};
  p.map.limits = o.limits;
  p.map.threads = o.threads;
  p.preprocess.target_points = o.target_points;
  p.nbv.method = o.method;
  if (o.level >= 0) p.nbv.level = unsigned(o.level);
  p.nbv.candidate_spacing = o.candidate_spacing;
  p.nbv.threads = o.threads;
  p.nbv.limits = o.limits;
  p.robot.radius = o.robot_radius;
  p.stop_percent = o.stop;
  std::unique_ptr<SurveySession> session;
  ScanOutcome last;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Scan& s = scans[i];
    std::printf("scan %zu: %s\n", i, s.source.c_str());
    if (!session) {
      // The robot's scanner height: the first scan's optical centre above its floor.
      if (o.scanner_height > 0) {
        p.robot.scanner_height = o.scanner_height;
      } else {
        const PreprocessResult pre = preprocess(*s.points, p.preprocess);
        p.robot.scanner_height = pre.transform.translation().z();
        std::printf("  scanner height above the floor: %.2f m\n", p.robot.scanner_height);
      }
      session = std::make_unique<SurveySession>(p);
    }
    IncomingScan in;
    in.points = s.points;
    in.points_raw = s.points->size() + s.invalid_dropped;
    in.x = posed ? s.pose.position().x() : 0.0;
    in.y = posed ? s.pose.position().y() : 0.0;
    in.yaw_deg = posed ? s.pose.yaw_deg() : 0.0;
    in.registered = !posed;
    last = session->add_scan(in);
  }
  std::string why = "stop_percentage";
  if (!last.nbv)
    why = "no_candidate";
  else if (last.stop_percent >= o.stop)
    why = "max_scans";  // the scans given are all there is; more are needed
  nlohmann::json extra;
  extra["inputs"] = o.clouds;
  extra["seconds_total"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  session->write_survey_json(why, extra);
  if (last.nbv)
    std::printf(
        "next best view: (%.2f, %.2f, %.2f), score %.1f; stop percentage %.3f %% (%s %.3f "
        "%%)\n",
        last.nbv->position.x, last.nbv->position.y, last.nbv->position.z, last.nbv->score,
        last.stop_percent, last.stop_percent < o.stop ? "below the threshold" : "threshold",
        o.stop);
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
      "pose (or register it to the first by ICP when no --pose is given), build the semioctree "
      "(occupancy, doors and windows, occlusion), score the candidate positions and report the "
      "next best view and the stop percentage. Writes survey.json and scan_NN/ as `survey` does.");
  cmd->add_option("--cloud", o->clouds,
                  "scan file: .pcd, .ply, .xyz/.txt or .ptx (repeat for several scans)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--pose", o->poses,
                  "scanner pose X,Y,Z[,YAW_DEG] of each --cloud in the survey frame (default: "
                  "the first at the origin, the others registered by ICP; PTX files carry theirs)");
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--leaf", o->leaf, "leaf (finest octant) size r, m")->capture_default_str();
  cmd->add_option("--coarse", o->coarse, "coarse voxel size L = r*2^k, m")->capture_default_str();
  cmd->add_option("--stop", o->stop, "stop percentage threshold (Eq 5), %")->capture_default_str();
  cmd->add_option("--method", o->method,
                  "NBV scoring: 1 = all levels weighted by volume, 2 = one level (--level)")
      ->check(CLI::IsMember({1, 2}))
      ->capture_default_str();
  cmd->add_option("--level", o->level,
                  "method 2: the octree level scored, 0 = coarse voxels ... k = leaf (default: the "
                  "leaf)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--robot-radius", o->robot_radius, "safety cylinder radius, m")
      ->capture_default_str();
  cmd->add_option("--scanner-height", o->scanner_height,
                  "scanner optical centre above the floor, m (default: from the first scan)");
  cmd->add_option("--target-points", o->target_points,
                  "decimate each scan to about this many points")
      ->capture_default_str();
  cmd->add_option("--candidate-spacing", o->candidate_spacing,
                  "spacing of the NBV candidate grid, m")
      ->capture_default_str();
  cmd->add_option("--max-range", o->limits.max_range, "scanner maximum range, m")
      ->capture_default_str();
  cmd->add_option("--min-range", o->limits.min_range, "scanner minimum range, m")
      ->capture_default_str();
  cmd->add_option("--elevation-min", o->limits.elevation_min_deg,
                  "scanner lowest elevation, degrees")
      ->capture_default_str();
  cmd->add_option("--elevation-max", o->limits.elevation_max_deg,
                  "scanner highest elevation, degrees")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0: one per core)")
      ->capture_default_str();
  cmd->callback([o] { run_nbv(*o); });
}

}  // namespace semioctree::cli
