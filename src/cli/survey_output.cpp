#include "survey_output.h"

#include <malloc.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <stdexcept>

#include "semioctree/figures.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/outputs.h"
#include "semioctree/report.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

using nlohmann::json;

json octants_json(const SemiOcTree& tree, json& volume_percent_out) {
  const OctantStatistics st = tree.statistics();
  json by_level = json::array(), by_label = json::object();
  for (unsigned l = 0; l <= tree.leaf_level(); ++l) by_level.push_back(st.at_level(l));
  for (int l = 1; l < kLabelCount; ++l)
    by_label[std::string(label_name(Label(l)))] = st.with_label(Label(l));
  json pct = json::object();
  for (Label l : {Label::kEmpty, Label::kOccupied, Label::kOccluded, Label::kDoor, Label::kWindow,
                  Label::kOut})
    pct[std::string(label_name(l))] = volume_percent(st, l);
  volume_percent_out = pct;
  return {{"total", st.total()}, {"by_level", by_level}, {"by_label", by_label}};
}

json pose_json(const Eigen::Isometry3d& p) {
  const Eigen::Vector3d t = p.translation();
  return {{"x", t.x()}, {"y", t.y()}, {"z", t.z()}, {"yaw_deg", yaw_deg_of(p)}};
}

json route_json(const std::vector<Point3>& route) {
  json out = json::array();
  for (const Point3& p : route)
    out.push_back({std::round(p.x * 1000.0) / 1000.0, std::round(p.y * 1000.0) / 1000.0});
  return out;
}

json rooms_json(const std::vector<RoomStatus>& rooms) {
  json out = json::array();
  for (std::size_t i = 0; i < rooms.size(); ++i) {
    const RoomStatus& st = rooms[i];
    const Room& room = st.room;
    json o = {{"id", i},
              {"state", to_string(st.state)},
              {"area_m2", room.area_m2},
              {"min", {room.min.x, room.min.y, room.min.z}},
              {"max", {room.max.x, room.max.y, room.max.z}},
              {"openings", room.openings},
              {"scans", st.scans},
              {"stop_percent", st.stop_percent ? json(*st.stop_percent) : json(nullptr)},
              {"path_m", st.path_m ? json(*st.path_m) : json(nullptr)}};
    if (!st.why.empty()) o["why"] = st.why;
    out.push_back(o);
  }
  return out;
}

void print_floor_layer_note(const RobotGeometry& robot, double leaf) {
  if (floor_layer_clearance(robot, leaf) > robot.ground_clearance)
    std::printf(
        "note: leaves of %.3f m are coarser than the robot's ground clearance (%.3f m): the "
        "safety cylinder drives over whatever lies in the floor's leaf layer\n",
        leaf, robot.ground_clearance);
}

std::vector<std::string> survey_files_written() {
  std::vector<std::string> files = {"survey.json", "coverage_missed.ply", "scan_[0-9][0-9]/"};
  for (const std::string& f : survey_report_files()) files.push_back(f);
  return files;
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
    const std::vector<std::string> report = survey_report_files();
    const bool report_file = std::find(report.begin(), report.end(), name) != report.end();
    if (scan_dir || report_file || name == "survey.json" || name == "coverage_missed.ply") {
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

SurveyOutput::SurveyOutput(std::string dir, const SurveyParams& params)
    : dir_(std::move(dir)), params_(params) {
  clear_previous_survey(dir_);
  print_floor_layer_note(params_.robot, params_.map.grid.leaf);
}

void SurveyOutput::stage_done(SurveyStage stage, const ScanRecord& s) {
  switch (stage) {
    case SurveyStage::kPreprocessed:
      std::printf(
          "  preprocess: %zu → %zu points (%zu outside the scanner's limits dropped), %s, tilt "
          "α %.2f° β %.2f° [%.2f s]\n",
          s.points_raw, s.points_kept, s.points_outside_limits,
          describe_room_height(s.ceiling_found, s.height_from, s.ceiling_height).c_str(),
          s.tilt_alpha_deg, s.tilt_beta_deg, s.seconds.preprocess);
      break;
    case SurveyStage::kRegistered: {
      const RegistrationResult& r = s.registration->icp;
      if (!s.registration->pose_icp_failure.empty())
        std::printf("  ICP from the reported pose failed (%s); recovered by a global alignment\n",
                    s.registration->pose_icp_failure.c_str());
      if (const auto& g = s.registration->global)
        std::printf(
            "  global alignment: %zu yaws of %.2f°, %zu distinct placements, %zu screened by "
            "ICP; chosen overlap %.0f %% (runner-up %.0f %%) [%.2f s]\n",
            g->yaw_steps, g->yaw_step_deg, g->candidates, g->screened.size(),
            100 * g->chosen_overlap, 100 * g->runner_up_overlap, g->seconds);
      std::printf(
          "  register: ICP moved the scanner %.3f m, %.2f°; fitness %.2e m², overlap %.0f %% "
          "[%.2f s]\n",
          s.registration->scanner_shift_m, r.rotation_deg, r.fitness, 100 * r.overlap,
          s.seconds.registration);
      break;
    }
    case SurveyStage::kMapped: {
      const ScanUpdateReport& up = s.update;
      std::printf(
          "  map: directions of the returns [%.2f s]; %zu new coarse voxels, %zu occupied leaves "
          "[%.2f s]; %zu openings [%.2f s]; occlusion %zu octants tested, %zu split, %zu segments "
          "[%.2f s]\n",
          s.seconds.returns, up.new_coarse_voxels, up.occupied_leaves, up.seconds_occupancy,
          up.openings_found, up.seconds_openings,
          up.retest.octants_tested + up.new_space.octants_tested,
          up.retest.octants_split + up.new_space.octants_split,
          up.retest.segments + up.new_space.segments, up.seconds_occlusion);
      progress_ = std::make_unique<CountProgress>(stdout, "  nbv: scored", "candidates");
      break;
    }
    case SurveyStage::kRoomFound:
      if (s.room)
        std::printf(
            "  room: x %.2f..%.2f, y %.2f..%.2f, z %.2f..%.2f m (targets and Eq 5 inside)\n",
            s.room->min.x, s.room->max.x, s.room->min.y, s.room->max.y, s.room->min.z,
            s.room->max.z);
      else
        std::printf(
            "  room: no scanner stands in free space: targets and Eq 5 over the whole map\n");
      break;
    case SurveyStage::kPlanned: {
      if (progress_) progress_->finish();
      const NbvResult& nbv = s.nbv;
      if (s.scope == SurveyScope::kFloor) {
        std::size_t count[4] = {0, 0, 0, 0};
        for (const RoomStatus& room : s.rooms) ++count[int(room.state)];
        std::printf("  rooms: %zu (%zu complete, %zu open, %zu unreachable, %zu not judged)",
                    s.rooms.size(), count[int(RoomState::kComplete)], count[int(RoomState::kOpen)],
                    count[int(RoomState::kUnreachable)], count[int(RoomState::kNotJudged)]);
        if (s.in_room) std::printf("; standing in room %zu", *s.in_room);
        if (s.planned_room && s.planned_room != s.in_room)
          std::printf("; next: room %zu, %.1f m away", *s.planned_room,
                      s.rooms[*s.planned_room].path_m.value_or(0.0));
        if (s.planned_doorway && nbv.best)
          std::printf("; next: a doorway of door %zu, to look through it", *s.planned_doorway);
        std::printf("\n");
      }
      if (nbv.best) {
        std::printf(
            "  nbv: %zu feasible candidates, %zu occluded targets; best (%.3f, %.3f) score "
            "%.1f, %.2f m away by path, stop %.3f %% [%.2f s; candidates %.2f s, the plan's "
            "targets and scores %.2f s, its Eq 5 %.2f s]\n",
            nbv.candidate_report.feasible, nbv.scoring.targets, nbv.best->position.x,
            nbv.best->position.y, nbv.best->score, nbv.best->path_m, nbv.stop_percent,
            s.seconds.nbv, nbv.seconds_candidates, nbv.seconds_scoring, nbv.seconds_stop);
        if (nbv.best_overlap)
          std::printf("  nbv: predicted overlap %.0f %% (%.0f %% of the rays)%s [%.2f s]\n",
                      100 * nbv.best_overlap->share, 100 * nbv.best_overlap->unweighted_share,
                      nbv.low_overlap ? (", after " + std::to_string(nbv.low_overlap) +
                                         " better-scored candidates predicted too low")
                                            .c_str()
                                      : "",
                      nbv.seconds_overlap);
      } else
        std::printf(
            "  nbv: no feasible candidate (%zu grid points, %zu blocked, %zu unreachable, %zu "
            "already scanned from, %zu predicted to overlap the map too little) [%.2f s]\n",
            nbv.candidate_report.grid_points, nbv.candidate_report.cylinder_blocked,
            nbv.candidate_report.unreachable, nbv.candidate_report.already_scanned, nbv.low_overlap,
            s.seconds.nbv);
      break;
    }
  }
  std::fflush(stdout);
}

void SurveyOutput::candidates_scored(std::size_t done, std::size_t total) {
  if (progress_) progress_->update(done, total);
}

void SurveyOutput::scan_done(const ScanRecord& s, const SurveyMap& map) {
  char name[16];
  std::snprintf(name, sizeof name, "scan_%02zu", s.index);
  const std::string dir = (std::filesystem::path(dir_) / name).string();
  const std::optional<NbvCandidate>& best = s.nbv.best;
  SliceOptions slice;
  slice.height = params_.robot.scanner_height;
  slice.scans = map.scanners();
  if (best) slice.nbv = best->position;
  if (!s.route.empty()) routes_.push_back(s.route);
  slice.routes = routes_;
  for (std::size_t i = 0; i < s.rooms.size(); ++i) {
    const Room& room = s.rooms[i].room;
    slice.rooms.push_back(
        {room.outline, room.inner, "R" + std::to_string(i) + " " + to_string(s.rooms[i].state)});
  }
  for (const DetectedOpening& op : map.openings())
    slice.openings.push_back({op.kind == OpeningKind::kDoor,
                              Point3(op.corners[0].x(), op.corners[0].y(), op.corners[0].z()),
                              Point3(op.corners[1].x(), op.corners[1].y(), op.corners[1].z())});
  slice.title = std::string(name) + (best ? ": scans and next best view" : ": scans");
  // scan_NN/ on a thread of its own, beside the next scan's simulation, preprocessing and
  // registration: the map stays as it is until the next scan's update, which waits for it
  // (map_changing). The files are written from the map with a few bytes a node beside it.
  map_changing();  // a write still running is finished first
  writing_.index = s.index;
  writing_.dir = dir;
  writing_.seconds = std::async(std::launch::async, [&map, dir, slice = std::move(slice)] {
    const auto t0 = Clock::now();
    write_map_files(map.tree(), dir, slice);
    write_cloud_ply(map.merged_cloud(), (std::filesystem::path(dir) / "cloud.ply").string());
    // What this thread freed stays with its own malloc arena, which the survey's thread
    // does not take from: give it back to the system.
    malloc_trim(0);
    return seconds_since(t0);
  });

  json r;
  r["index"] = s.index;
  r["pose"] = pose_json(s.scanner_to_survey);
  r["placed_by"] = to_string(s.placed_by);
  r["points_raw"] = s.points_raw;
  r["points_kept"] = s.points_kept;
  r["points_outside_limits"] = s.points_outside_limits;
  r["ceiling_found"] = s.ceiling_found;
  r["ceiling_height"] = s.ceiling_height;
  r["ceiling_height_from"] = to_string(s.height_from);
  json volume;
  r["octants"] = octants_json(map.tree(), volume);
  r["volume_percent"] = volume;
  // Eq 5 is measured from the NBV: without one there is nothing to report.
  r["stop_percent"] = best ? json(s.nbv.stop_percent) : json(nullptr);
  r["nbv"] = best ? json{{"x", best->position.x},
                         {"y", best->position.y},
                         {"z", best->position.z},
                         {"score", best->score}}
                  : json(nullptr);
  if (best && s.nbv.best_overlap) {
    r["nbv"]["predicted_overlap"] = s.nbv.best_overlap->share;
    r["nbv"]["predicted_overlap_unweighted"] = s.nbv.best_overlap->unweighted_share;
  }
  r["candidates"] = s.nbv.candidate_report.feasible;
  r["candidates_low_overlap"] = s.nbv.low_overlap;
  r["predicted_overlap"] = s.predicted_overlap ? json(*s.predicted_overlap) : json(nullptr);
  r["path_m"] = s.path_m ? json(*s.path_m) : json(nullptr);
  r["route"] = route_json(s.route);
  if (best) {
    r["nbv"]["path_m"] = best->path_m;
    r["nbv"]["value"] = best->value;
  }
  r["occluded_targets"] = s.nbv.scoring.targets;
  r["scope"] = to_string(s.scope);
  if (s.scope == SurveyScope::kFloor) {
    r["rooms"] = rooms_json(s.rooms);
    r["in_room"] = s.in_room ? json(*s.in_room) : json(nullptr);
    r["planned_room"] = s.planned_room ? json(*s.planned_room) : json(nullptr);
    r["planned_doorway"] = s.planned_doorway ? json(*s.planned_doorway) : json(nullptr);
  }
  if (s.room)  // where targets and Eq 5 were counted (null: the whole map)
    r["room"] = {{"min", {s.room->min.x, s.room->min.y, s.room->min.z}},
                 {"max", {s.room->max.x, s.room->max.y, s.room->max.z}}};
  else
    r["room"] = nullptr;
  if (s.registration) {
    const RegistrationResult& icp = s.registration->icp;
    r["registration"] = {{"fitness", icp.fitness},
                         {"overlap", icp.overlap},
                         {"converged", icp.converged},
                         {"correction_m", s.registration->scanner_shift_m},
                         {"correction_deg", icp.rotation_deg},
                         {"iterations", icp.iterations}};
    if (!s.registration->pose_icp_failure.empty())
      r["registration"]["pose_icp_failure"] = s.registration->pose_icp_failure;
    if (const auto& g = s.registration->global) {
      json screened = json::array();
      for (const GlobalHypothesis& h : g->screened)
        screened.push_back({{"x", h.x},
                            {"y", h.y},
                            {"yaw_deg", h.yaw_deg},
                            {"votes", h.votes},
                            {"overlap", h.overlap}});
      r["registration"]["global"] = {{"yaw_steps", g->yaw_steps},
                                     {"yaw_step_deg", g->yaw_step_deg},
                                     {"source_cells", g->source_cells},
                                     {"target_cells", g->target_cells},
                                     {"candidates", g->candidates},
                                     {"screened", screened},
                                     {"chosen_overlap", g->chosen_overlap},
                                     {"runner_up_overlap", g->runner_up_overlap},
                                     {"seconds_search", g->seconds_search},
                                     {"seconds_screen", g->seconds_screen},
                                     {"verified", g->verified},
                                     {"seconds_verify", g->seconds_verify},
                                     {"seconds", g->seconds}};
    }
  } else {
    r["registration"] = nullptr;
  }
  r["seconds"] = {{"preprocess", s.seconds.preprocess},
                  {"register", s.seconds.registration},
                  {"returns", s.seconds.returns},
                  {"occupancy", s.seconds.occupancy},
                  {"openings", s.seconds.openings},
                  {"occlusion", s.seconds.occlusion},
                  {"nbv", s.seconds.nbv},
                  {"write", nullptr},  // when written (map_changing)
                  {"total", s.seconds.total}};
  r["peak_rss_mib"] = peak_resident_mib();  // of the whole run so far
  if (records_.size() <= s.index) records_.resize(s.index + 1);
  records_[s.index] = r;
}

void SurveyOutput::map_changing() {
  if (!writing_.seconds.valid()) return;
  const double seconds = writing_.seconds.get();
  records_.at(writing_.index)["seconds"]["write"] = seconds;
  std::printf("  wrote %s/ [%.2f s, beside the survey]\n", writing_.dir.c_str(), seconds);
  std::fflush(stdout);
}

void SurveyOutput::registration_failed(const RegistrationFailure& f) {
  json r = {{"after_scan", f.after_scan},
            {"position", {f.position.x, f.position.y}},
            {"error", f.error},
            {"retry", f.retry ? json{f.retry->x, f.retry->y} : json(nullptr)},
            {"path_m", f.path_m ? json(*f.path_m) : json(nullptr)},
            {"route", route_json(f.route)}};
  failures_.push_back(r);
  if (!f.route.empty()) routes_.push_back(f.route);
  if (f.retry)
    std::printf(
        "  registration failed: %s\n  the scan is dropped; scanning again at (%.3f, %.3f), "
        "nearer scan %zu\n",
        f.error.c_str(), f.retry->x, f.retry->y, f.after_scan);
  std::fflush(stdout);
}

void SurveyOutput::write_survey_json(const std::string& stopped_because, const json& extra,
                                     const SurveyMap* map) {
  map_changing();  // the last scan_NN/ written
  json openings = json::array();
  if (map)
    for (const DetectedOpening& op : map->openings()) {
      json corners = json::array();
      for (const auto& c : op.corners) corners.push_back({c.x(), c.y(), c.z()});
      openings.push_back({{"kind", to_string(op.kind)},
                          {"corners", corners},
                          {"width", op.width},
                          {"height", op.height}});
    }
  // The robot's planned path over the whole survey: to every scan, failed ones too.
  double path_m = 0;
  for (const json& r : records_)
    if (r["path_m"].is_number()) path_m += r["path_m"].get<double>();
  for (const json& f : failures_)
    if (f["path_m"].is_number()) path_m += f["path_m"].get<double>();
  json j = {{"format", "semioctree-survey"},
            {"version", 1},
            {"leaf", params_.map.grid.leaf},
            {"coarse", params_.map.grid.coarse},
            {"stop_threshold_percent", params_.stop_percent},
            {"method", params_.nbv.method},
            {"travel_weight", params_.nbv.travel_weight},
            {"platform",
             {{"robot_radius", params_.robot.radius},
              {"scanner_height", params_.robot.scanner_height},
              {"elevation_min_deg", params_.map.limits.elevation_min_deg},
              {"elevation_max_deg", params_.map.limits.elevation_max_deg},
              {"min_range", params_.map.limits.min_range},
              {"max_range", params_.map.limits.max_range}}},
            {"stopped_because", stopped_because},
            // Only the stop percentage says the room is done; the other reasons leave
            // occluded space that the NBV (if any) would still reveal.
            {"complete", stopped_because == "stop_percentage"},
            {"scans", records_},
            {"registration_failures", failures_},
            {"path_m", path_m},
            {"openings", openings},
            {"peak_rss_mib", peak_resident_mib()}};
  // The floor's rooms as the last scan left them (openings: indices into "openings").
  if (!records_.empty() && records_.back().contains("rooms")) {
    j["scope"] = records_.back()["scope"];
    j["rooms"] = records_.back()["rooms"];
  } else if (!records_.empty()) {
    j["scope"] = records_.back()["scope"];
  }
  for (const auto& [k, v] : extra.items()) j[k] = v;
  std::filesystem::create_directories(dir_);
  write_file_atomically((std::filesystem::path(dir_) / "survey.json").string(),
                        [&](std::ostream& os) { os << j.dump(2) << "\n"; });
  write_survey_report(dir_);
  std::printf("wrote %s/report.html (open it in any browser)\n", dir_.c_str());
}

}  // namespace semioctree::cli
