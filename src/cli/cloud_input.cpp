#include "cloud_input.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "option_checks.h"
#include "semioctree/outputs.h"
#include "semioctree/scan_io.h"
#include "semioctree/update.h"
#ifdef SEMIOCTREE_HAVE_SIM
#include "semioctree/timing.h"
#include "sim_input.h"
#endif

namespace semioctree::cli {

void check_scan_usable(const Scan& scan, const ScannerView* limits) {
  std::size_t outside = 0;
  const Cloud::Ptr kept = limits ? within_limits(scan.points, *limits, &outside) : scan.points;
  if (kept->empty()) {
    char range[160];
    std::snprintf(range, sizeof range,
                  "%g to %g m, elevation %g to %g degrees; --min-range, --max-range, "
                  "--elevation-min, --elevation-max",
                  limits->min_range, limits->max_range, limits->elevation_min_deg,
                  limits->elevation_max_deg);
    throw std::invalid_argument(scan.source + ": no points within the scanner's range limits (" +
                                range + "): all " + std::to_string(outside) + " lie outside them");
  }
  Eigen::AlignedBox3f box;
  for (const pcl::PointXYZ& p : *kept) box.extend(p.getVector3fMap());
  if (box.diagonal().norm() < 1e-3f)
    throw std::invalid_argument(scan.source + ": all " + std::to_string(kept->size()) +
                                " points lie within 1 mm of each other: nothing to map");
}

PreparedCloud prepare_clouds(const CloudInput& in, const PreprocessParams& params,
                             const ScannerView* limits) {
  if (in.files.empty()) throw std::invalid_argument("no --cloud file given");
  if (!in.poses.empty() && in.poses.size() != in.files.size())
    throw std::invalid_argument("give one --pose per --cloud file (" +
                                std::to_string(in.files.size()) + " files, " +
                                std::to_string(in.poses.size()) + " poses)");
  if (!in.pose_file.empty() && in.files.size() != 1)
    throw std::invalid_argument("--pose-file applies to a single --cloud file");
  PreparedCloud out;
  Cloud merged;
  std::vector<Eigen::Vector3d> origins;
  std::vector<std::pair<Cloud::Ptr, Eigen::Matrix3d>> returns;  // scanner frame, rotation
  for (std::size_t i = 0; i < in.files.size(); ++i) {
    const auto t0 = Clock::now();
    std::vector<Scan> scans = read_scans(in.files[i]);
    for (Scan& s : scans) {
      if (!in.poses.empty())
        s.pose = parse_pose(in.poses[i]);
      else if (!in.pose_file.empty())
        s.pose = read_pose_json(in.pose_file);
      check_scan_usable(s, limits);
      std::size_t outside = 0;
      if (limits) s.points = within_limits(s.points, *limits, &outside);
      out.outside_limits += outside;
      const Cloud::Ptr world = to_survey_frame(s);
      merged += *world;
      origins.push_back(s.pose.position());
      returns.emplace_back(s.points, s.pose.scanner_to_survey.linear());
      out.raw_points += s.points->size() + s.invalid_dropped + outside;
      out.invalid_dropped += s.invalid_dropped;
      std::printf(
          "read %s: %zu points (%zu invalid, %zu outside the scanner's limits dropped), scanner "
          "at (%.2f, %.2f, %.2f) [%.2f s]\n",
          s.source.c_str(), s.points->size(), s.invalid_dropped, outside, s.pose.position().x(),
          s.pose.position().y(), s.pose.position().z(), seconds_since(t0));
    }
  }
  std::fflush(stdout);
  const auto t0 = Clock::now();
  out.pre = preprocess(merged, params);
  for (const auto& o : origins) {
    const Eigen::Vector3d p = out.pre.transform * o;
    out.scanners.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto& [points, rotation] : returns)
    out.returns.push_back(return_directions(
        *points, out.pre.transform.linear() * rotation,
        returns_options(limits ? *limits : ScannerView(), !out.pre.ceiling_found)));
  const auto& r = out.pre;
  char ceiling[64] = "";
  if (r.ceiling_found)
    std::snprintf(ceiling, sizeof ceiling, " (ceiling σ %.1f mm, %zu removed)",
                  1000 * r.ceiling.sigma, r.ceiling.removed);
  std::printf(
      "preprocess: alpha %.3f°, beta %.3f°; floor σ %.1f mm (%zu removed), %s%s; %zu → %zu "
      "points%s [%.2f s]\n",
      r.alpha_deg, r.beta_deg, 1000 * r.floor.sigma, r.floor.removed,
      describe_room_height(r.ceiling_found, r.height_from, r.ceiling_height).c_str(), ceiling,
      r.input_points, r.output_points,
      r.decimation_spacing > 0
          ? (" (decimated at " + std::to_string(r.decimation_spacing).substr(0, 6) + " m)").c_str()
          : "",
      seconds_since(t0));
  std::fflush(stdout);
  return out;
}

void add_scan_source_options(CLI::App& cmd, ScanSource& src, const std::string& pose_help) {
  auto* cloud_opt =
      cmd.add_option("--cloud", src.input.files,
                     "point cloud: .pcd, .ply, .xyz/.txt or .ptx (repeat for several)")
          ->check(CLI::ExistingFile);
  cmd.add_option("--pose", src.input.poses, pose_help);
  cmd.add_option("--pose-file", src.input.pose_file,
                 "JSON pose {\"x\",\"y\",\"z\",\"yaw_deg\"} for a single --cloud")
      ->check(CLI::ExistingFile);
#ifdef SEMIOCTREE_HAVE_SIM
  cmd.add_option("--scene", src.scene,
                 "scene file: scan it from the robot's start with the synthetic scanner")
      ->check(CLI::ExistingFile)
      ->excludes(cloud_opt);
  cmd.add_option("--seed", src.seed, "scanner noise seed (with --scene)")
      ->check(seed_value())
      ->capture_default_str();
#else
  (void)cloud_opt;
#endif
  auto& p = src.pre;
  cmd.add_option(
         "--target-points", p.target_points,
         "decimate to about this many points (distance filter; the paper keeps ~400000; 0: off; "
         "else at least 1000)")
      ->check(zero_or_whole_in(1000, 1000000000))
      ->capture_default_str();
  cmd.add_option("--min-spacing", p.min_spacing,
                 "decimate to this minimum point spacing in metres (0: off)")
      ->check(finite_in(0, 10))
      ->capture_default_str();
  cmd.add_option(
         "--sigma-factor", p.sigma_factor,
         "remove points within this many standard deviations of the floor and ceiling peaks")
      ->check(finite_in(0, 100))
      ->capture_default_str();
}

void check_scanner_limits(const ScannerView& v) {
  if (!(v.min_range < v.max_range))
    throw std::invalid_argument("--min-range (" + std::to_string(v.min_range) +
                                ") must be below --max-range (" + std::to_string(v.max_range) +
                                ")");
  if (!(v.elevation_min_deg < v.elevation_max_deg))
    throw std::invalid_argument("--elevation-min (" + std::to_string(v.elevation_min_deg) +
                                ") must be below --elevation-max (" +
                                std::to_string(v.elevation_max_deg) + ")");
}

PreparedCloud prepare(const ScanSource& src, const std::string& command,
                      const ScannerView* limits) {
  if (limits) check_scanner_limits(*limits);
  if (src.input.files.empty() && src.scene.empty())
    throw std::invalid_argument(command + ": give --cloud FILE or --scene FILE");
#ifdef SEMIOCTREE_HAVE_SIM
  if (!src.scene.empty()) return scan_scene_at_start(src.scene, src.seed, src.pre);
#endif
  return prepare_clouds(src.input, src.pre, limits);
}

void add_scanner_limit_options(CLI::App& cmd, ScannerView& limits) {
  cmd.add_option("--max-range", limits.max_range, "scanner maximum range, m")
      ->check(finite_positive(100000))
      ->capture_default_str();
  cmd.add_option("--min-range", limits.min_range, "scanner minimum range, m (below --max-range)")
      ->check(finite_in(0, 100000))
      ->capture_default_str();
  cmd.add_option("--elevation-min", limits.elevation_min_deg,
                 "scanner lowest elevation, degrees (-90 to 90, below --elevation-max)")
      ->check(finite_in(-90, 90))
      ->capture_default_str();
  cmd.add_option("--elevation-max", limits.elevation_max_deg, "scanner highest elevation, degrees")
      ->check(finite_in(-90, 90))
      ->capture_default_str();
}

void add_grid_options(CLI::App& cmd, DiscretizeParams& grid) {
  cmd.add_option("--leaf", grid.leaf, "leaf (finest octant) size r in metres")
      ->check(finite_positive())
      ->capture_default_str();
  cmd.add_option("--coarse", grid.coarse,
                 "coarse voxel size L in metres; must be r*2^k (L = r gives the homogeneous grid)")
      ->check(finite_positive())
      ->capture_default_str();
}

std::string source_name(const ScanSource& src) {
  return std::filesystem::path(src.scene.empty() ? src.input.files.front() : src.scene)
      .filename()
      .string();
}

std::vector<NamedPath> source_paths(const ScanSource& src) {
  std::vector<NamedPath> out;
  for (const std::string& f : src.input.files) out.push_back({"--cloud", f});
  out.push_back({"--pose-file", src.input.pose_file});
  out.push_back({"--scene", src.scene});
  return out;
}

std::vector<std::string> map_files_written() {
  const MapFiles names;
  return {names.semioctree, names.color, names.occupancy, names.slice, "stats.json"};
}

bool has_extension(const std::string& path, const std::string& ext) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e == ext;
}

}  // namespace semioctree::cli
