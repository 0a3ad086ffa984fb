// `semioctree map-nbv --map FILE --scanner X,Y,Z... --out DIR`: the next best view
// for a map made elsewhere — an OctoMap occupancy map (.bt, or an OcTree .ot from
// octomap_server or any OctoMap tool) or one of our SemiOcTree .ot files — without
// our point-cloud pipeline (docs/semioctree.md, "drop-in for OctoMap users").
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cloud_input.h"
#include "commands.h"
#include "option_checks.h"
#include "planning_options.h"
#include "progress_line.h"
#include "semioctree/figures.h"
#include "semioctree/nbv.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/octomap_ext/import.h"
#include "semioctree/openings.h"
#include "semioctree/outputs.h"
#include "semioctree/scan_io.h"
#include "semioctree/timing.h"
#include "survey_output.h"

namespace semioctree::cli {

namespace {

struct MapNbvOptions {
  std::string map;
  std::vector<std::string> scanners;
  std::string out;
  double coarse = -1;  // < 0: the map's resolution · 2^k nearest kDefaultCoarse
  std::string unobserved = "classify";
  double stop = 0.1;
  int method = 1;
  double candidate_spacing = 0.5;
  double robot_radius = 0.5;
  double scanner_height = -1;  // < 0: the last scanner's z (the floor is z = 0)
  bool skip_openings = false;
  double ceiling = -1;            // < 0: map_ceiling_height
  double floor_z = std::nan("");  // NaN: find_occupancy_floor
  int speck_leaves = 2;
  unsigned threads = 0;
  ScannerView limits;
};

constexpr double kDefaultCoarse = 0.8;  // m, the coarse size of our own surveys

nlohmann::json point_json(const Point3& p) {
  return {{"x", p.x}, {"y", p.y}, {"z", p.z}};
}

// The coarse size for an OctoMap map: the given one if it is the resolution times a
// power of two (else refused, naming the nearest valid sizes), or the one nearest 0.8 m.
double coarse_for(double res, double given) {
  if (given < 0) {
    const double c = nearest_coarse_size(res, kDefaultCoarse);
    std::printf(
        "coarse voxels: %.3f m, the map's resolution times a power of two nearest %.1f m "
        "(a tie goes to the larger)\n",
        c, kDefaultCoarse);
    return c;
  }
  try {
    SemiOcTree::leaf_level_for(res, given);
  } catch (const std::invalid_argument&) {
    const double k = std::floor(std::log2(given / res));
    char near[128];
    std::snprintf(near, sizeof near, "%g or %g", res * std::pow(2.0, k),
                  res * std::pow(2.0, k + 1));
    throw std::invalid_argument("--coarse " + std::to_string(given) +
                                " is not the map's resolution (" + std::to_string(res) +
                                " m) times a power of two: the nearest are " + near);
  }
  return given;
}

// The leaf layers to move an OctoMap map up by so that its floor lies at z = 0: from
// --floor-z, or the floor found in its occupied leaves (find_occupancy_floor).
int floor_shift_for(const octomap::OcTree& map, double floor_z) {
  const double res = map.getResolution();
  if (std::isfinite(floor_z)) {
    const int shift = -int(std::lround(floor_z / res));
    std::printf("floor: z = %.3f m (--floor-z): the map is moved up by %d leaves (%.3f m)\n",
                floor_z, shift, shift * res);
    return shift;
  }
  const std::optional<OccupancyFloor> f = find_occupancy_floor(map);
  if (!f) {
    std::printf("floor: no occupied leaves, taken at z = 0\n");
    return 0;
  }
  std::printf(
      "floor: z = %.3f m, found in the map (the lowest layer of leaves holding a quarter as many "
      "occupied leaves as the fullest: %zu); %s\n",
      f->z, f->leaves,
      f->shift_layers ? ("the map is moved up by " + std::to_string(f->shift_layers) +
                         " leaves, positions are reported in its own frame (--floor-z to give it)")
                            .c_str()
                      : "at z = 0 already (--floor-z to give it)");
  return f->shift_layers;
}

// The directions each scanner got returns in, read from the rays the map carved. A
// scanner whose rays the map does not hold (its leaf is not free, or under half of its
// directions reach an occupied leaf: a map of points without free space, or one too
// sparse to follow a ray through) is taken to have got returns everywhere, as before.
constexpr double kMinDirectionsReached = 0.5;
std::vector<std::shared_ptr<const ReturnDirections>> returns_from_map(
    const octomap::OcTree& map, const std::vector<Point3>& scanners, const MapNbvOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::shared_ptr<const ReturnDirections>> out;
  std::size_t used = 0;
  std::string shares;  // per scanner: its rays that reach a surface
  for (std::size_t i = 0; i < scanners.size(); ++i) {
    MapReturnsReport rep;
    auto r = return_directions_in_map(map, scanners[i], o.limits, o.threads, &rep);
    const double reached =
        rep.bins_tested ? double(rep.bins_reached) / double(rep.bins_tested) : 0.0;
    const std::string percent = std::to_string(std::lround(100 * reached)) + " %";
    shares += (i ? ", " : "") + percent;
    if (!rep.origin_free || reached < kMinDirectionsReached) {
      const std::string why =
          rep.origin_free
              ? "only " + percent + " of its rays reach an occupied leaf through free space"
              : "the map does not hold its position as free space";
      std::printf(
          "  scanner %zu: %s, so the directions it got no returns in are not known (a surface "
          "nearer than its minimum range may look seen through)\n",
          i + 1, why.c_str());
      out.push_back(nullptr);
      continue;
    }
    ++used;
    out.push_back(std::move(r));
  }
  std::printf(
      "directions with returns, from the rays the map carved: %zu of %zu scanner(s) (rays that "
      "reach an occupied leaf: %s) [%.2f s]\n",
      used, scanners.size(), shares.c_str(), seconds_since(t0));
  return out;
}

// An OctoMap map holds no doors or windows: find them as `classify` does, in
// its occupied leaves, then make the free space seen through them out.
std::optional<std::vector<DetectedOpening>> find_openings_in_map(
    SemiOcTree& tree, const octomap::OcTree& map, const MapNbvOptions& o,
    const std::vector<Point3>& scanners,
    const std::vector<std::shared_ptr<const ReturnDirections>>& returns) {
  if (o.skip_openings) return std::nullopt;
  const auto t0 = std::chrono::steady_clock::now();
  const std::optional<double> ceiling =
      o.ceiling > 0 ? std::optional<double>(o.ceiling) : map_ceiling_height(tree);
  if (!ceiling) {
    std::printf(
        "doors and windows: not looked for, no ceiling found. That needs occupied leaves at the "
        "floor, z = 0 (is the map levelled there?), and a layer above 2 m with at least a quarter "
        "as many; give --ceiling if the floor is there\n");
    return std::nullopt;
  }
  OpeningsReport rep;
  std::vector<DetectedOpening> found = detect_openings_in_map(tree, *ceiling, scanners, {}, &rep);
  // Seen through is not open: the map must hold the free space its rays carved through it.
  std::vector<DetectedOpening> kept, not_carved;
  std::vector<double> shares;
  for (const DetectedOpening& d : found) {
    const double share = share_carved_behind(d, map, scanners);
    (2 * share >= 1 ? kept : not_carved).push_back(d);
    if (2 * share < 1) shares.push_back(share);
  }
  found = std::move(kept);
  label_openings(tree, found);
  std::printf(
      "doors and windows (ceiling %.2f m%s): %zu walls, %zu candidates, %zu confirmed, %zu "
      "rejected as occlusion shadows [%.2f s]\n",
      *ceiling, o.ceiling > 0 ? "" : ", found in the map", rep.walls.size(), rep.candidates,
      found.size(), rep.rejected.size(), seconds_since(t0));
  for (const DetectedOpening& d : found)
    std::printf("  %-6s %.2f x %.2f m, sill %.2f m, line of sight %.0f %%\n", to_string(d.kind),
                d.width, d.height, d.sill, 100 * d.los_fraction);
  for (std::size_t i = 0; i < not_carved.size(); ++i)
    std::printf(
        "  not an opening: %s %.2f x %.2f m, sill %.2f m at (%.2f, %.2f): the map holds free space "
        "behind only %.0f %% of it (under half: a shadow or a gap in the wall's surface)\n",
        to_string(not_carved[i].kind), not_carved[i].width, not_carved[i].height,
        not_carved[i].sill, not_carved[i].corners[0].x(), not_carved[i].corners[0].y(),
        100 * shares[i]);
  if (!found.empty()) {
    OcclusionParams op;
    op.scope = OcclusionScope::kFreeThroughOpenings;
    op.threads = o.threads;
    const OcclusionReport occ =
        study_occlusion(tree, scanner_views(scanners, o.limits, returns), op);
    std::printf("  free space seen through them is out of the room: %zu octants\n", occ.out);
  }
  return found;
}

void run_map_nbv(const MapNbvOptions& o) {
  const auto t_start = std::chrono::steady_clock::now();
  check_scanner_limits(o.limits);
  std::vector<std::string> written = map_files_written();
  written.insert(written.end(), {"openings.json", "nbv.json"});
  check_outputs_spare_inputs({{"--map", o.map}}, {}, {{{"--out", o.out}, written}});
  std::vector<Point3> scanners;
  for (const std::string& s : o.scanners) {
    const Eigen::Vector3d p = parse_pose(s).position();
    scanners.emplace_back(p.x(), p.y(), p.z());
  }
  // The map: a SemiOcTree as it is, an OctoMap occupancy map imported (its floor moved
  // to z = 0 by `lift`: positions given and reported are in the map's own frame).
  TreeFile file = read_tree_file(o.map);
  double lift = 0;  // m
  if (auto* occupancy = dynamic_cast<octomap::OcTree*>(file.tree.get());
      occupancy && !dynamic_cast<SemiOcTree*>(file.tree.get())) {
    const int layers = floor_shift_for(*occupancy, o.floor_z);
    if (layers != 0) {
      lift = layers * occupancy->getResolution();
      file.tree = shifted_by_layers(*occupancy, layers);
    }
  }
  for (Point3& s : scanners) s.z += lift;
  const Point3 robot = scanners.back();
  const double height = o.scanner_height > 0 ? o.scanner_height : robot.z;
  if (!(height > 0))
    throw std::invalid_argument(
        "--scanner: the last scanner's z (" + std::to_string(robot.z - lift) +
        ") is not above the map's floor (z = " + std::to_string(-lift) +
        "); give its position in the map's frame, or --floor-z or --scanner-height");
  std::unique_ptr<SemiOcTree> tree;
  std::optional<std::vector<DetectedOpening>> openings;          // looked for: an OctoMap map
  std::vector<std::shared_ptr<const ReturnDirections>> returns;  // per scanner; none: any
  bool imported = false;                                         // an OctoMap map
  if (auto* semi = dynamic_cast<SemiOcTree*>(file.tree.get())) {
    file.tree.release();
    tree.reset(semi);
    std::printf("read %s: SemiOcTree, leaf %.3f m, coarse %.3f m, %zu octants\n", o.map.c_str(),
                tree->leaf_size(), tree->coarse_size(), std::size_t(tree->statistics().total()));
  } else if (auto* occupancy = dynamic_cast<octomap::OcTree*>(file.tree.get())) {
    const auto t0 = std::chrono::steady_clock::now();
    const double res = occupancy->getResolution();
    const double coarse = coarse_for(res, o.coarse);
    imported = true;
    OccupancyImportReport rep;
    const Label unobserved = o.unobserved == "occluded" ? Label::kOccluded : Label::kUnknown;
    try {
      tree = from_occupancy_octree(*occupancy, coarse, unobserved, &rep);
    } catch (const std::length_error& e) {
      throw std::runtime_error(o.map + ": " + e.what());
    }
    std::printf(
        "read %s: OctoMap %s, resolution %.3f m, %zu leaf nodes → SemiOcTree of %zu coarse "
        "voxels (%zu occupied leaves) [%.2f s]\n",
        o.map.c_str(), file.binary ? "occupancy map (.bt)" : file.type.c_str(), res, rep.map_leaves,
        rep.coarse_voxels, rep.occupied_leaves, seconds_since(t0));
    returns = returns_from_map(*occupancy, scanners, o);
    if (unobserved == Label::kUnknown) {
      // Space the map does not hold: seen from a scanner (then empty: nothing returned
      // there) or hidden (occluded), as the occlusion study decides.
      const auto t1 = std::chrono::steady_clock::now();
      const std::vector<ScannerView> views = scanner_views(scanners, o.limits, returns);
      OcclusionParams op;
      op.scope = OcclusionScope::kUnknown;
      op.threads = o.threads;
      const OcclusionReport occ = study_occlusion(*tree, views, op);
      std::printf(
          "classified the unobserved space from %zu scanner position(s): %zu empty, %zu "
          "occluded, %zu out [%.2f s]\n",
          views.size(), occ.empty, occ.occluded, occ.out, seconds_since(t1));
    }
    openings = find_openings_in_map(*tree, *occupancy, o, scanners, returns);
  } else {
    throw std::invalid_argument(o.map + ": a " + file.type +
                                " holds no occupancy (give a .bt, an OcTree .ot or a SemiOcTree "
                                ".ot)");
  }
  if (!tree->find_octant(robot))
    throw std::invalid_argument(
        "--scanner: the robot's position (last --scanner) is outside "
        "the map");

  RobotGeometry geometry;
  geometry.radius = o.robot_radius;
  geometry.scanner_height = height;
  print_floor_layer_note(geometry, tree->leaf_size());
  NbvParams params;
  params.method = o.method;
  params.candidate_spacing = o.candidate_spacing;
  params.threads = o.threads;
  params.limits = o.limits;
  params.grid_anchor = scanners.front();  // the first scan position, as `survey` does
  if (imported) params.enclosed_speck_leaves = o.speck_leaves;  // its carving may be sparse
  const auto t2 = std::chrono::steady_clock::now();
  CountProgress progress(stdout, "nbv: scored", "candidates");
  params.progress = progress.callback();
  const NbvResult r =
      next_best_view(*tree, geometry, Point3(robot.x, robot.y, 0.0), scanners, params);
  progress.finish();
  std::printf("nbv: %zu feasible candidates, %zu occluded targets [%.2f s]\n", r.candidates.size(),
              r.scoring.targets, seconds_since(t2));
  if (params.enclosed_speck_leaves > 0)
    std::printf(
        "  unobserved specks enclosed in free space (at most %d leaves a side), not obstacles for "
        "the safety cylinder: %zu leaves\n",
        params.enclosed_speck_leaves, r.candidate_report.specks_freed);
  // Positions out in the map's own frame (its floor where it was).
  auto in_map_frame = [lift](Point3 p) { return p.z -= lift, p; };

  std::filesystem::create_directories(o.out);
  if (openings) {
    std::vector<DetectedOpening> framed = *openings;
    for (DetectedOpening& d : framed)
      for (Eigen::Vector3d& c : d.corners) c.z() -= lift;
    write_openings_json(framed, (std::filesystem::path(o.out) / "openings.json").string());
  }
  SliceOptions slice;
  slice.height = height;
  slice.scans = scanners;
  if (r.best) slice.nbv = r.best->position;
  slice.title = std::filesystem::path(o.map).filename().string();
  write_map_files(*tree, o.out, slice);

  nlohmann::json volume;
  const nlohmann::json octants = octants_json(*tree, volume);
  nlohmann::json scanner_list = nlohmann::json::array();
  for (const Point3& s : scanners) scanner_list.push_back(point_json(in_map_frame(s)));
  const Point3 nbv = r.best ? in_map_frame(r.best->position) : Point3();
  const bool complete = r.best && r.stop_percent < o.stop;
  nlohmann::json j = {
      {"format", "semioctree-map-nbv"},
      {"version", 1},
      {"map", o.map},
      {"leaf", tree->leaf_size()},
      {"coarse", tree->coarse_size()},
      {"method", o.method},
      {"scanners", scanner_list},
      {"candidates", r.candidates.size()},
      {"openings", openings ? nlohmann::json(openings->size()) : nlohmann::json(nullptr)},
      {"nbv",
       r.best ? nlohmann::json{{"x", nbv.x}, {"y", nbv.y}, {"z", nbv.z}, {"score", r.best->score}}
              : nlohmann::json(nullptr)},
      {"floor_z", -lift},
      {"map_files_lift", lift},
      {"specks_freed", r.candidate_report.specks_freed},
      {"stop_percent", r.best ? nlohmann::json(r.stop_percent) : nlohmann::json(nullptr)},
      {"stop_threshold_percent", o.stop},
      {"complete", complete},
      {"octants", octants},
      {"volume_percent", volume},
      {"seconds_total", seconds_since(t_start)}};
  const std::string json_path = (std::filesystem::path(o.out) / "nbv.json").string();
  write_file_atomically(json_path, [&](std::ostream& os) { os << j.dump(2) << "\n"; });
  if (r.best)
    std::printf("next best view: (%.3f, %.3f, %.3f), score %.1f; stop percentage %.3f %% (%s)\n",
                nbv.x, nbv.y, nbv.z, r.best->score, r.stop_percent,
                complete ? "below the threshold: the map is complete" : "above the threshold");
  else  // the robot is in the map: a scanner outside it was refused above
    std::printf(
        "no feasible next best view: of %zu grid points, %zu are not empty space at scanner "
        "height, %zu have an obstacle in their safety cylinder (radius %.2f m) and %zu cannot be "
        "reached from the robot at (%.3f, %.3f)\n",
        r.candidate_report.grid_points, r.candidate_report.not_empty,
        r.candidate_report.cylinder_blocked, geometry.radius, r.candidate_report.unreachable,
        robot.x, robot.y);
  if (lift != 0)
    std::printf("the map files are in the map's frame moved up by %.3f m (its floor at z = 0)\n",
                lift);
  std::printf("wrote %s and the map files in %s\n", json_path.c_str(), o.out.c_str());
}

}  // namespace

void add_map_nbv_command(CLI::App& app) {
  auto o = std::make_shared<MapNbvOptions>();
  auto* cmd = app.add_subcommand(
      "map-nbv",
      "Next best view for a map made elsewhere: an OctoMap occupancy map (.bt, or an OcTree .ot "
      "from octomap_server or any OctoMap tool) or a SemiOcTree .ot. An OctoMap map becomes a "
      "semioctree of the same resolution (its leaf); the space it does not hold is classified "
      "from the scanner positions (seen → empty, hidden → occluded), or all taken as occluded "
      "(--unobserved occluded). Seen means in a direction the scanner got returns in: one "
      "whose ray, through the map's free space, reaches an occupied leaf (a surface nearer than "
      "the minimum range leaves a hole in the map but hides what is behind it); a map without "
      "free space around a scanner cannot tell, and every direction counts. Its doors and windows "
      "are found as `classify` finds them, with its occupied leaves for points (the ceiling: its "
      "densest layer of occupied leaves "
      "above 2 m, or --ceiling), and the space seen through them is out of the room. The "
      "map's frame must be levelled (z up); its floor is found (or --floor-z) and moved to "
      "z = 0 by whole leaves, positions given and reported stay in the map's frame. "
      "Writes nbv.json (the NBV, its score and the stop percentage), semioctree.ot, "
      "labels_color.ot, occupancy.bt and slice.png, and openings.json when doors and windows "
      "were looked for.");
  cmd->add_option("--map", o->map, "the map: .bt, OcTree .ot or SemiOcTree .ot")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--scanner", o->scanners,
                  "optical centre X,Y,Z of a scan that made the map, in its frame (repeat); the "
                  "robot stands at the last")
      ->required();
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--coarse", o->coarse,
                  "coarse voxel size L for an OctoMap map: its resolution times a power of two, "
                  "m (default: the one nearest 0.8 m; of two equally near, the larger)")
      ->check(finite_positive());
  cmd->add_option("--floor-z", o->floor_z,
                  "OctoMap map: the floor's height in the map's frame, m (default: found, the "
                  "lowest layer of leaves holding at least a quarter as many occupied leaves as "
                  "the fullest layer). The map is moved by whole leaves to put it at z = 0; "
                  "positions given and reported stay in the map's frame")
      ->check(CLI::Range(-1e4, 1e4));
  cmd->add_option("--speck-leaves", o->speck_leaves,
                  "OctoMap map: unknown or occluded specks enclosed in free space (a component "
                  "fitting in a cube of this many leaves a side, every face neighbour free) do "
                  "not block the safety cylinder; they stay unknown in the outputs. A solid "
                  "smaller than that could hide in one (docs/nbv.md). 0: off")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  cmd->add_option("--unobserved", o->unobserved,
                  "space an OctoMap map does not hold: classify (from the --scanner positions) "
                  "or occluded (all of it)")
      ->check(CLI::IsMember({"classify", "occluded"}))
      ->capture_default_str();
  cmd->add_option("--stop", o->stop, "stop percentage threshold (Eq 5), %")
      ->check(finite_in(0, 100))
      ->capture_default_str();
  cmd->add_option("--method", o->method,
                  "NBV scoring: 1 = occluded volume, all levels (paper), 3 = area of the "
                  "occlusion frontier facing the position (surface, ours)")
      ->check(CLI::IsMember({1, 3}))
      ->capture_default_str();
  cmd->add_option(
         "--candidate-spacing", o->candidate_spacing,
         "spacing of the NBV candidate grid at scanner height (a grid through the first scan "
         "position), m")
      ->check(finite_positive(10))
      ->capture_default_str();
  cmd->add_option("--robot-radius", o->robot_radius, "safety cylinder radius, m (0.05 to 5)")
      ->check(finite_in(0.05, 5))
      ->capture_default_str();
  cmd->add_flag("--no-openings", o->skip_openings,
                "OctoMap map: do not look for doors and windows (what was seen through them then "
                "counts as the room; a SemiOcTree .ot keeps its own labels either way)");
  cmd->add_option("--ceiling", o->ceiling,
                  "OctoMap map: ceiling height above the floor for finding doors and windows, m "
                  "(default: the densest layer of occupied leaves above 2 m)")
      ->check(finite_positive(100));
  cmd->add_option("--scanner-height", o->scanner_height,
                  "scanner optical centre above the floor, m (default: the last --scanner's z)")
      ->check(finite_positive(100));
  cmd->add_option("--threads", o->threads, "worker threads (0: one per core; at most 256)")
      ->check(thread_count())
      ->capture_default_str();
  add_scanner_limit_options(*cmd, o->limits);
  cmd->callback([o] { run_map_nbv(*o); });
}

}  // namespace semioctree::cli
