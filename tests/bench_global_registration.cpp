// Registration without a pose (global alignment, then ICP) over lab scan pairs 2-4 m
// and 30-180° apart, and over the real scan against a moved, thinned, noisy copy of
// itself. Prints JSON: per pair the outcome, pose error and seconds; the success rate
// (placed within 2 cm and 0.3°), the pairs refused (ambiguous or not placed), the pairs
// placed wrongly, the largest and mean errors of the registered ones, wall and CPU seconds,
// and the largest ratio of a refined runner-up's overlap to the chosen one's.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>
#include <string>

#include "semioctree/global_registration.h"
#include "semioctree/preprocess.h"
#include "semioctree/scan_io.h"
#include "support/bench_common.h"
#include "support/unposed_pairs.h"

namespace st = semioctree::testing;
using semioctree::Cloud;

namespace {

constexpr double kMaxTranslation = 0.02, kMaxYawDeg = 0.3;

semioctree::GlobalAlignParams global_params;

nlohmann::json run_pair(const Cloud& target, const st::LabPair& pair) {
  nlohmann::json j;
  j["distance_m"] = pair.distance_m;
  j["turn_deg"] = pair.turn_deg;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  try {
    const semioctree::GlobalAlignResult r =
        semioctree::global_align(*pair.source_cloud, target, {}, global_params);
    const st::PlanarError e = st::planar_error(r.transform, pair.truth, pair.source_scanner);
    j["outcome"] = e.translation_m <= kMaxTranslation && std::fabs(e.yaw_deg) <= kMaxYawDeg
                       ? "placed"
                       : "wrong";
    j["error_m"] = e.translation_m;
    j["error_yaw_deg"] = e.yaw_deg;
    j["yaw_steps"] = r.yaw_steps;
    j["candidates"] = r.candidates;
    j["screened"] = r.screened.size();
    j["chosen_overlap"] = r.chosen_overlap;
    j["chosen_rank"] = r.screened[r.chosen].rank;
    j["chosen_votes"] = r.screened[r.chosen].votes;
    j["runner_up_overlap"] = r.runner_up_overlap;
    j["runner_up_refined_overlap"] = r.runner_up_refined_overlap;
    j["overlap"] = r.icp.overlap;
    j["fitness"] = r.icp.fitness;
    j["seconds_search"] = r.seconds_search;
    j["seconds_screen"] = r.seconds_screen;
    j["seconds_verify"] = r.seconds_verify;
    j["verified"] = r.verified;
    j["seconds_icp"] = r.icp.seconds;
  } catch (const semioctree::RegistrationError& e) {
    j["outcome"] =
        std::string(e.what()).find("ambiguous") != std::string::npos ? "ambiguous" : "refused";
    j["error"] = e.what();
  }
  j["seconds"] = semioctree::bench::seconds_since(t0);
  j["cpu_seconds"] = double(std::clock() - cpu0) / CLOCKS_PER_SEC;  // all threads
  return j;
}

nlohmann::json summary(const nlohmann::json& pairs) {
  std::size_t placed = 0, refused = 0, wrong = 0;
  double max_t = 0, max_yaw = 0, sum_t = 0, sum_yaw = 0, sum_s = 0, max_s = 0, sum_cpu = 0,
         max_cpu = 0, max_ratio = 0;
  for (const auto& p : pairs) {
    const std::string o = p["outcome"];
    sum_s += p["seconds"].get<double>();
    max_s = std::max(max_s, p["seconds"].get<double>());
    sum_cpu += p["cpu_seconds"].get<double>();
    max_cpu = std::max(max_cpu, p["cpu_seconds"].get<double>());
    if (p.contains("runner_up_refined_overlap"))
      max_ratio = std::max(
          max_ratio, p["runner_up_refined_overlap"].get<double>() / p["overlap"].get<double>());
    if (o == "refused" || o == "ambiguous") {
      ++refused;
      continue;
    }
    (o == "placed" ? placed : wrong)++;
    const double t = p["error_m"], yaw = std::fabs(p["error_yaw_deg"].get<double>());
    max_t = std::max(max_t, t), max_yaw = std::max(max_yaw, yaw);
    sum_t += t, sum_yaw += yaw;
  }
  const double n = double(pairs.size()), registered = double(placed + wrong);
  return {{"pairs", pairs.size()},
          {"placed", placed},
          {"refused", refused},
          {"wrong", wrong},
          {"success_rate", n > 0 ? double(placed) / n : 0.0},
          {"max_error_m", max_t},
          {"mean_error_m", registered > 0 ? sum_t / registered : 0.0},
          {"max_error_yaw_deg", max_yaw},
          {"mean_error_yaw_deg", registered > 0 ? sum_yaw / registered : 0.0},
          {"mean_seconds", n > 0 ? sum_s / n : 0.0},
          {"max_seconds", max_s},
          {"mean_cpu_seconds", n > 0 ? sum_cpu / n : 0.0},
          {"max_cpu_seconds", max_cpu},
          {"max_runner_up_ratio", max_ratio}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Registration without a pose: lab scan pairs 2-4 m and 30-180° apart, and the real scan "
      "against a moved copy of itself; prints JSON"};
  double grid = 1.2, scan_step = st::kTestStepDeg, noise = 0.005;
  std::size_t pairs = 48;
  app.add_option("--grid", grid, "spacing of the lab scan positions, m")->capture_default_str();
  app.add_option("--pairs", pairs, "lab pairs (at most)")->capture_default_str();
  app.add_option("--scan-step", scan_step, "scanner step, degrees")->capture_default_str();
  app.add_option("--noise", noise, "noise on the real scan's copy, m (σ per coordinate)")
      ->capture_default_str();
  app.add_option("--ambiguity-ratio", global_params.ambiguity_ratio,
                 "GlobalAlignParams::ambiguity_ratio")
      ->capture_default_str();
  app.add_option("--hypotheses", global_params.hypotheses, "GlobalAlignParams::hypotheses")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  nlohmann::json out;
  const auto t_scan = std::chrono::steady_clock::now();
  const std::vector<st::LabPosition> positions = st::lab_positions(grid, scan_step);
  out["lab"]["positions"] = positions.size();
  out["lab"]["seconds_scanning"] = semioctree::bench::seconds_since(t_scan);
  nlohmann::json lab = nlohmann::json::array();
  for (const st::LabPair& p : st::lab_pairs(positions, pairs)) {
    nlohmann::json j = run_pair(*positions[p.target].levelled, p);
    j["target"] = {positions[p.target].pose.x, positions[p.target].pose.y};
    j["source"] = {positions[p.source].pose.x, positions[p.source].pose.y};
    std::fprintf(stderr, "lab pair %zu: %s\n", lab.size(), j.dump().c_str());
    lab.push_back(j);
  }
  out["lab"]["pairs"] = lab;
  out["lab"]["summary"] = summary(lab);

  const auto scans =
      semioctree::read_scans(std::string(SEMIOCTREE_SOURCE_DIR) + "/tests/data/room_scan1.pcd");
  const semioctree::PreprocessResult pre = semioctree::preprocess(*scans.front().points);
  const Eigen::Vector3d scanner = pre.transform * Eigen::Vector3d::Zero();
  // Moved 2 m and turned 40° about the scanner.
  const Eigen::Isometry3d moved = Eigen::Translation3d(scanner + Eigen::Vector3d(1.2, -1.6, 0)) *
                                  semioctree::planar_pose(0, 0, 40.0) *
                                  Eigen::Translation3d(-scanner);
  const st::LabPair copy = st::moved_copy(*pre.cloud, scanner, moved, 0.2, noise, 7);
  out["real_copy"] = run_pair(*pre.cloud, copy);
  out["real_copy"]["noise_m"] = noise;
  out["real_copy"]["points"] = pre.cloud->size();
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
