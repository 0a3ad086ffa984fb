#include "survey_session.h"

#include <pcl/common/transforms.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "option_checks.h"
#include "progress_line.h"
#include "semioctree/figures.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/outputs.h"

namespace semioctree::cli {

using nlohmann::json;

namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

json octants_json(const SemiOcTree& tree, json& volume_percent_out) {
  const OctantStatistics st = tree.statistics();
  json by_level = json::array(), by_label = json::object();
  for (unsigned l = 0; l <= tree.coarse_level(); ++l) by_level.push_back(st.at_level(l));
  for (int l = 1; l < kLabelCount; ++l)
    by_label[std::string(label_name(Label(l)))] = st.with_label(Label(l));
  json pct = json::object();
  for (Label l : {Label::kEmpty, Label::kOccupied, Label::kOccluded, Label::kDoor, Label::kWindow,
                  Label::kOut})
    pct[std::string(label_name(l))] = volume_percent(st, l);
  volume_percent_out = pct;
  return {{"total", st.total()}, {"by_level", by_level}, {"by_label", by_label}};
}

double yaw_deg_of(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x = pose.rotation() * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) * 180.0 / M_PI;
}

json pose_json(const Eigen::Isometry3d& p) {
  const Eigen::Vector3d t = p.translation();
  return {{"x", t.x()}, {"y", t.y()}, {"z", t.z()}, {"yaw_deg", yaw_deg_of(p)}};
}

void add_planning_options(CLI::App& cmd, PlanningOptions& o) {
  cmd.add_option("--leaf", o.leaf, "leaf (finest octant) size r, m")
      ->check(finite_positive())
      ->capture_default_str();
  cmd.add_option("--coarse", o.coarse, "coarse voxel size L = r*2^k, m")
      ->check(finite_positive())
      ->capture_default_str();
  cmd.add_option("--stop", o.stop, "stop percentage threshold (Eq 5), %")
      ->check(finite_in(0, 100))
      ->capture_default_str();
  cmd.add_option(
         "--method", o.method,
         "NBV scoring: 1 = occluded volume, all levels (paper), 2 = one level (--level), 3 = "
         "area of the occlusion frontier facing the position (surface, ours)")
      ->check(CLI::IsMember({1, 2, 3}))
      ->capture_default_str();
  cmd.add_option("--level", o.level,
                 "method 2: the octree level scored, 0 = coarse voxels ... k = leaf (default: the "
                 "leaf)")
      ->check(whole_in(0, 16));
  cmd.add_option(
         "--candidate-spacing", o.candidate_spacing,
         "spacing of the NBV candidate grid at scanner height (a grid through the first scan "
         "position), m")
      ->check(finite_positive(10))
      ->capture_default_str();
  cmd.add_option("--target-points", o.target_points,
                 "decimate each scan to about this many points (paper: 400 000; 0: keep all; "
                 "else at least 1000)")
      ->check(zero_or_whole_in(1000, 1000000000))
      ->capture_default_str();
  cmd.add_flag("--whole-map", o.whole_map,
               "count occluded space as NBV targets and in the stop percentage over the whole "
               "map, as Eq 5 reads when the grid is the room; default: only inside the room the "
               "scans stand in (its walls, floor and ceiling), so that space behind the walls or "
               "seen out of a window does not count");
  cmd.add_option("--threads", o.threads, "worker threads (0: one per core; at most 256)")
      ->check(thread_count())
      ->capture_default_str();
}

void apply_planning_options(const PlanningOptions& o, SessionParams& p, bool homogeneous) {
  // L = r·2^k, or a clear error (the homogeneous grid's region snaps to L too);
  // the homogeneous grid has one level.
  const unsigned semioctree_k = SemiOcTree::coarse_level_for(o.leaf, o.coarse);
  const unsigned k = homogeneous ? 0 : semioctree_k;
  if (o.level > int(k))
    throw std::invalid_argument("--level " + std::to_string(o.level) +
                                " is finer than the leaf: the grid has levels 0 (coarse voxels) "
                                "to " +
                                std::to_string(k) + " (leaf)");
  if (o.level >= 0 && o.method != 2)
    throw std::invalid_argument("--level applies to --method 2 only");
  // The homogeneous grid spans the same coarse-aligned region as the semioctree.
  p.map.grid = homogeneous ? DiscretizeParams{o.leaf, o.leaf, o.coarse}
                           : DiscretizeParams{o.leaf, o.coarse, 0.0};
  p.map.threads = o.threads;
  p.preprocess.target_points = o.target_points;
  p.nbv.method = o.method;
  if (o.level >= 0) p.nbv.level = unsigned(o.level);
  p.nbv.candidate_spacing = o.candidate_spacing;
  p.nbv.threads = o.threads;
  p.nbv.limits = p.map.limits;
  p.stop_percent = o.stop;
  p.room_only = !o.whole_map;
}

SurveySession::SurveySession(const SessionParams& params) : params_(params), map_(params.map) {
  clear_previous_survey(params_.out);
  print_floor_layer_note(params_.robot, params_.map.grid.leaf);
}

void print_floor_layer_note(const RobotGeometry& robot, double leaf) {
  if (floor_layer_clearance(robot, leaf) > robot.ground_clearance)
    std::printf(
        "note: leaves of %.3f m are coarser than the robot's ground clearance (%.3f m): the "
        "safety cylinder drives over whatever lies in the floor's leaf layer\n",
        leaf, robot.ground_clearance);
}

void clear_previous_survey(const std::string& dir) {
  // A survey.json and scan_NN/ folders left by an earlier run would sit beside
  // the new ones (a 3-scan run over a 5-scan one keeps scan_03, scan_04) and
  // read as part of it. Only what a survey writes is removed.
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::size_t removed = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const bool scan_dir = name.size() == 7 && name.compare(0, 5, "scan_") == 0 &&
                          std::isdigit(static_cast<unsigned char>(name[5])) &&
                          std::isdigit(static_cast<unsigned char>(name[6])) && e.is_directory(ec);
    if (scan_dir || name == "survey.json" || name == "coverage_missed.ply") {
      fs::remove_all(e.path(), ec);
      if (ec)
        throw std::runtime_error(e.path().string() +
                                 ": cannot remove the previous run's output: " + ec.message());
      ++removed;
    }
  }
  if (removed)
    std::printf("replacing the previous survey in %s (%zu files and scan folders removed)\n",
                dir.c_str(), removed);
}

ScanOutcome SurveySession::add_scan(const IncomingScan& in,
                                    const std::optional<Point3>& robot_position) {
  const std::size_t index = records_.size();
  const auto t_total = std::chrono::steady_clock::now();
  ScanOutcome out;
  json seconds;

  // Stage 1: drop the returns outside the scanner's limits (its mount, the
  // robot), level this scan in its own frame, then place it by the reported pose.
  auto t0 = std::chrono::steady_clock::now();
  std::size_t outside = 0;
  const Cloud::Ptr seen = within_limits(*in.points, params_.map.limits, &outside);
  const PreprocessResult pre = preprocess(*seen, params_.preprocess);
  seconds["preprocess"] = since(t0);
  std::printf(
      "  preprocess: %zu → %zu points (%zu outside the scanner's limits dropped), ceiling %.2f m, "
      "tilt α %.2f° β %.2f° [%.2f s]\n",
      in.points->size(), pre.output_points, outside, pre.ceiling_height, pre.alpha_deg,
      pre.beta_deg, seconds["preprocess"].get<double>());
  std::fflush(stdout);
  const Eigen::Isometry3d place = planar_pose(in.x, in.y, in.yaw_deg);
  Cloud::Ptr guess(new Cloud);
  pcl::transformPointCloud(*pre.cloud, *guess, (place).matrix().cast<float>());

  // Stage 2: ICP against the merged cloud of the previous scans.
  t0 = std::chrono::steady_clock::now();
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  json registration = nullptr;
  double scanner_shift = 0;
  if (index > 0 && in.registered) {
    RegistrationResult r;
    try {
      r = register_scan(*guess, map_.merged_cloud(), params_.registration);
      // How far the correction moves the scanner (the translation of the
      // correction itself is about the survey origin, far away).
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
      scanner_shift = shift;
    } catch (const RegistrationError& e) {
      throw RegistrationError("scan " + std::to_string(index) + " could not be registered (" +
                              e.what() + "); the map of the previous scans is kept in " +
                              params_.out);
    }
    correction = r.correction;
    registration = {{"fitness", r.fitness},
                    {"overlap", r.overlap},
                    {"converged", r.converged},
                    {"correction_m", scanner_shift},
                    {"correction_deg", r.rotation_deg},
                    {"iterations", r.iterations}};
    std::printf(
        "  register: ICP moved the scanner %.3f m, %.2f°; fitness %.2e m², overlap %.0f %% "
        "[%.2f s]\n",
        scanner_shift, r.rotation_deg, r.fitness, 100 * r.overlap, since(t0));
  }
  seconds["register"] = since(t0);
  out.scanner_to_survey = correction * place * pre.transform;
  out.registered.reset(new Cloud);
  pcl::transformPointCloud(*guess, *out.registered, correction.matrix().cast<float>());
  const Eigen::Vector3d o = out.scanner_to_survey.translation();
  // One floor for the whole survey: a scan levelled onto another plane (the
  // ground outside a window, a table) would shift the map up or down.
  if (!map_.empty() && std::abs(o.z() - map_.scanners().front().z) > 0.1) {
    char m[200];
    std::snprintf(m, sizeof m,
                  "scan %zu: its floor was found %.2f m from the first scan's (scanner at %.2f m "
                  "above it instead of %.2f m); the map of the previous scans is kept",
                  index, o.z() - map_.scanners().front().z, o.z(), map_.scanners().front().z);
    throw RegistrationError(m);
  }
  const Point3 scanner(o.x(), o.y(), o.z());

  // Stages 3-5 (8 for later scans): occupancy, openings, occlusion.
  const ScanUpdateReport up =
      map_.add_scan(*out.registered, scanner, pre.ceiling_height,
                    return_directions(*seen, out.scanner_to_survey.linear()));
  seconds["occupancy"] = up.seconds_occupancy;
  seconds["openings"] = up.seconds_openings;
  seconds["occlusion"] = up.seconds_occlusion;
  std::printf(
      "  map: %zu new coarse voxels, %zu occupied leaves [%.2f s]; %zu openings [%.2f s]; "
      "occlusion %zu octants tested, %zu split, %zu segments [%.2f s]\n",
      up.new_coarse_voxels, up.occupied_leaves, up.seconds_occupancy, up.openings_found,
      up.seconds_openings, up.retest.octants_tested + up.new_space.octants_tested,
      up.retest.octants_split + up.new_space.octants_split,
      up.retest.segments + up.new_space.segments, up.seconds_occlusion);
  std::fflush(stdout);

  // Stages 6-7: next best view and stop percentage.
  t0 = std::chrono::steady_clock::now();
  const Point3 robot = robot_position.value_or(scanner);
  NbvParams nbv_params = params_.nbv;
  nbv_params.grid_anchor = map_.scanners().front();  // see NbvParams::grid_anchor
  if (params_.room_only) {
    nbv_params.room = room_box(map_.tree(), map_.scanners(), params_.robot.scanner_height, 0.0,
                               map_.ceiling_height());
    if (nbv_params.room) {
      const RoomBox& b = *nbv_params.room;
      std::printf("  room: x %.2f..%.2f, y %.2f..%.2f, z %.2f..%.2f m (targets and Eq 5 inside)\n",
                  b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z);
    } else {
      std::printf("  room: no scanner stands in free space: targets and Eq 5 over the whole map\n");
    }
  }
  CountProgress progress(stdout, "  nbv: scored", "candidates");
  nbv_params.progress = progress.callback();
  const NbvResult nbv =
      next_best_view(map_.tree(), params_.robot, robot, map_.scanners(), nbv_params);
  progress.finish();
  seconds["nbv"] = since(t0);
  out.nbv = nbv.best;
  out.candidates = nbv.candidates;
  out.stop_percent = nbv.stop_percent;
  if (nbv.best)
    std::printf(
        "  nbv: %zu feasible candidates, %zu occluded targets; best (%.3f, %.3f) score "
        "%.1f, stop %.3f %% [%.2f s]\n",
        nbv.candidate_report.feasible, nbv.scoring.targets, nbv.best->position.x,
        nbv.best->position.y, nbv.best->score, nbv.stop_percent, seconds["nbv"].get<double>());
  else
    std::printf(
        "  nbv: no feasible candidate (%zu grid points, %zu blocked, %zu unreachable) "
        "[%.2f s]\n",
        nbv.candidate_report.grid_points, nbv.candidate_report.cylinder_blocked,
        nbv.candidate_report.unreachable, seconds["nbv"].get<double>());
  std::fflush(stdout);

  // Outputs of this scan.
  t0 = std::chrono::steady_clock::now();
  char name[16];
  std::snprintf(name, sizeof name, "scan_%02zu", index);
  const std::string dir = (std::filesystem::path(params_.out) / name).string();
  SliceOptions slice;
  slice.height = params_.robot.scanner_height;
  slice.scans = map_.scanners();
  if (nbv.best) slice.nbv = nbv.best->position;
  slice.title = std::string(name) + (nbv.best ? ": scans and next best view" : ": scans");
  write_map_files(map_.tree(), dir, slice);
  write_cloud_ply(map_.merged_cloud(), (std::filesystem::path(dir) / "cloud.ply").string());
  seconds["write"] = since(t0);
  seconds["total"] = since(t_total);
  std::printf("  wrote %s/ [%.2f s]\n", dir.c_str(), seconds["write"].get<double>());
  std::fflush(stdout);

  json r;
  r["index"] = index;
  r["pose"] = pose_json(out.scanner_to_survey);
  r["points_raw"] = in.points_raw ? in.points_raw : in.points->size();
  r["points_kept"] = pre.output_points;
  r["points_outside_limits"] = outside;
  json volume;
  r["octants"] = octants_json(map_.tree(), volume);
  r["volume_percent"] = volume;
  // Eq 5 is measured from the NBV: without one there is nothing to report.
  r["stop_percent"] = nbv.best ? json(nbv.stop_percent) : json(nullptr);
  r["nbv"] = nbv.best ? json{{"x", nbv.best->position.x},
                             {"y", nbv.best->position.y},
                             {"z", nbv.best->position.z},
                             {"score", nbv.best->score}}
                      : json(nullptr);
  r["candidates"] = nbv.candidate_report.feasible;
  r["occluded_targets"] = nbv.scoring.targets;
  if (nbv_params.room)  // where targets and Eq 5 were counted (null: the whole map)
    r["room"] = {{"min", {nbv_params.room->min.x, nbv_params.room->min.y, nbv_params.room->min.z}},
                 {"max", {nbv_params.room->max.x, nbv_params.room->max.y, nbv_params.room->max.z}}};
  else
    r["room"] = nullptr;
  r["registration"] = registration;
  r["seconds"] = seconds;
  records_.push_back(r);
  out.record = r;
  return out;
}

void SurveySession::write_survey_json(const std::string& stopped_because, const json& extra) const {
  json openings = json::array();
  for (const DetectedOpening& op : map_.openings()) {
    json corners = json::array();
    for (const auto& c : op.corners) corners.push_back({c.x(), c.y(), c.z()});
    openings.push_back({{"kind", to_string(op.kind)},
                        {"corners", corners},
                        {"width", op.width},
                        {"height", op.height}});
  }
  json j = {{"format", "semioctree-survey"},
            {"version", 1},
            {"leaf", params_.map.grid.leaf},
            {"coarse", params_.map.grid.coarse},
            {"stop_threshold_percent", params_.stop_percent},
            {"method", params_.nbv.method},
            {"stopped_because", stopped_because},
            // Only the stop percentage says the room is done; the other reasons leave
            // occluded space that the NBV (if any) would still reveal.
            {"complete", stopped_because == "stop_percentage"},
            {"scans", records_},
            {"openings", openings}};
  for (const auto& [k, v] : extra.items()) j[k] = v;
  std::filesystem::create_directories(params_.out);
  write_file_atomically((std::filesystem::path(params_.out) / "survey.json").string(),
                        [&](std::ostream& os) { os << j.dump(2) << "\n"; });
}

}  // namespace semioctree::cli
