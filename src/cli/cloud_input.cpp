#include "cloud_input.h"

#include <chrono>
#include <cstdio>

#include "semioctree/scan_io.h"

namespace semioctree::cli {

PreparedCloud prepare_clouds(const CloudInput& in, const PreprocessParams& params) {
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
  for (std::size_t i = 0; i < in.files.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Scan> scans = read_scans(in.files[i]);
    for (Scan& s : scans) {
      if (!in.poses.empty())
        s.pose = parse_pose(in.poses[i]);
      else if (!in.pose_file.empty())
        s.pose = read_pose_json(in.pose_file);
      const Cloud::Ptr world = to_survey_frame(s);
      merged += *world;
      origins.push_back(s.pose.position());
      out.raw_points += s.points->size() + s.invalid_dropped;
      out.invalid_dropped += s.invalid_dropped;
      std::printf(
          "read %s: %zu points (%zu invalid dropped), scanner at (%.2f, %.2f, %.2f) [%.2f s]\n",
          s.source.c_str(), s.points->size(), s.invalid_dropped, s.pose.position().x(),
          s.pose.position().y(), s.pose.position().z(),
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
  }
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  out.pre = preprocess(merged, params);
  for (const auto& o : origins) {
    const Eigen::Vector3d p = out.pre.transform * o;
    out.scanners.emplace_back(p.x(), p.y(), p.z());
  }
  const auto& r = out.pre;
  std::printf(
      "preprocess: alpha %.3f°, beta %.3f°; floor σ %.1f mm (%zu removed), ceiling at %.3f m σ "
      "%.1f mm "
      "(%zu removed); %zu → %zu points%s [%.2f s]\n",
      r.alpha_deg, r.beta_deg, 1000 * r.floor.sigma, r.floor.removed, r.ceiling_height,
      1000 * r.ceiling.sigma, r.ceiling.removed, r.input_points, r.output_points,
      r.decimation_spacing > 0
          ? (" (decimated at " + std::to_string(r.decimation_spacing).substr(0, 6) + " m)").c_str()
          : "",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  std::fflush(stdout);
  return out;
}

void add_preprocess_options(CLI::App& cmd, PreprocessParams& p) {
  cmd.add_option(
         "--target-points", p.target_points,
         "decimate to about this many points (distance filter; the paper keeps ~400000; 0: off)")
      ->capture_default_str();
  cmd.add_option("--min-spacing", p.min_spacing,
                 "decimate to this minimum point spacing in metres (0: off)")
      ->capture_default_str();
  cmd.add_option(
         "--sigma-factor", p.sigma_factor,
         "remove points within this many standard deviations of the floor and ceiling peaks")
      ->capture_default_str();
}

}  // namespace semioctree::cli
