// Benchmark: one Next-Best-View evaluation (candidates, Eq 3 scores with
// method 1, stop percentage; method 3 for comparison) on the lab after the
// first scan at 0.05 m, in one run, three ways:
//  * semioctree: the SemiOcTree (0.8 m coarse voxels), every feasible
//    candidate scored (the production path);
//  * homogeneous: the same code on the homogeneous grid (coarse = leaf =
//    0.05 m, i.e. discretize(..., {0.05, 0.05, 0.8})) built from the same cloud
//    through the same stages;
//  * octomap_castRay: the semioctree's candidates and targets scored the way an
//    OctoMap user would: castRay on an octomap::OcTree holding the same map
//    (to_occupancy_octree: occupied leaves occupied, empty/out/door/window free,
//    occluded absent and ignored as unknown) decides whether the line is
//    blocked; for lines that are not, computeRayKeys + OctoMap's search() on
//    the SemiOcTree used as a plain OctoMap tree (a 16-level descent per key)
//    gives the labels along the line, to count the occluded octants crossed
//    (consecutive keys in the same node are one octant) and to zero lines
//    through a door or window.
// The last two would take minutes on every candidate, so they score a fixed,
// deterministic subset (every j-th candidate of their list) and the time is
// scaled to the full candidate count; the JSON says so. Prints JSON.
//
//   bench_nbv [--subset N] [--threads T] [--no-homogeneous]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <thread>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/nbv.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/export.h"
#include "semioctree/openings.h"
#include "semioctree/preprocess.h"
#include "src/parallel_for.h"
#include "src/scanner_limits.h"
#include "support/bench_common.h"
#include "support/lab_scan.h"

using namespace semioctree;

namespace {

std::unique_ptr<SemiOcTree> classified_map(const PreprocessResult& pre, const Point3& origin,
                                           double coarse, double* seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  auto tree = discretize(*pre.cloud, pre.ceiling_height, {0.05, coarse, 0.8});
  const auto openings = detect_openings(*pre.cloud, pre.ceiling_height, *tree, {origin});
  label_openings(*tree, openings);
  study_occlusion(*tree, {ScannerView{origin}});
  tree->compact();
  *seconds = bench::seconds_since(t0);
  return tree;
}

// Every j-th element, `count` of them at most.
std::vector<Point3> subset(const std::vector<Point3>& all, std::size_t count) {
  std::vector<Point3> out;
  if (all.empty() || count == 0) return out;
  const std::size_t step = std::max<std::size_t>(1, (all.size() + count - 1) / count);
  for (std::size_t i = step / 2; i < all.size() && out.size() < count; i += step)
    out.push_back(all[i]);
  return out;
}

struct CastRayScorer {
  const SemiOcTree& labels;
  const octomap::OcTree& occupancy;
  std::vector<Point3> targets;
  std::vector<double> weights;
  ScannerView limits;

  double score(const Point3& a, octomap::KeyRay& ray, std::size_t& cast) const {
    const detail::ScannerLimits in_limits(limits);  // the scorer's own test of the limits
    const octomap::point3d origin{float(a.x), float(a.y), float(a.z)};
    double sum = 0;
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const Point3& b = targets[i];
      if (!in_limits.in_view(a, b)) continue;
      const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
      const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
      ++cast;
      const octomap::point3d dir{float(dx), float(dy), float(dz)};
      octomap::point3d hit;
      if (occupancy.castRay(origin, dir, hit, true, range)) continue;  // blocked
      const octomap::point3d end{float(b.x), float(b.y), float(b.z)};
      if (!labels.computeRayKeys(origin, end, ray)) continue;
      const SemiOcTreeNode* last = nullptr;
      std::uint32_t occluded = 0;
      bool through_opening = false;
      for (const octomap::OcTreeKey& k : ray) {
        const SemiOcTreeNode* node = labels.search(k);
        if (node == last) continue;
        last = node;
        const Label l = node ? node->label() : Label::kUnknown;
        if (l == Label::kDoor || l == Label::kWindow) {
          through_opening = true;
          break;
        }
        occluded += l == Label::kOccluded;
      }
      if (through_opening) continue;
      // computeRayKeys leaves out the end cell: add the target's octant unless
      // the ray's last key already lies in it.
      octomap::OcTreeKey ek;
      labels.coordToKeyChecked(end, ek);
      const bool target_counted = last && labels.search(ek) == last;
      const std::uint32_t n = target_counted ? occluded - 1 : occluded;
      sum += weights[i] / (1.0 + double(n));
    }
    return sum;
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: one Next-Best-View evaluation (method 1; methods 2 and 3 for comparison) on "
      "the lab after the first scan at 0.05 m: on the semioctree, on the homogeneous grid and "
      "with OctoMap castRay scoring, in one run. Prints JSON on stdout, progress on stderr."};
  std::size_t subset_size = 16;
  unsigned threads = 0;  // 0: automatic
  app.add_option("--subset", subset_size,
                 "number of candidates scored by the slow baselines (homogeneous grid, OctoMap "
                 "castRay) and by method 2, every j-th of the list; their time is scaled to all "
                 "candidates")
      ->check(CLI::Range(1LL, std::numeric_limits<long long>::max(), "POSITIVE"))
      ->capture_default_str();
  app.add_option("--threads", threads,
                 "scoring threads (default: automatic, one per core for the semioctree and "
                 "homogeneous scoring and at most 8 for the OctoMap castRay baseline)")
      ->check(CLI::Range(1u, std::numeric_limits<unsigned>::max(), "POSITIVE"));
  bool no_homogeneous = false;
  app.add_flag("--no-homogeneous", no_homogeneous,
               "skip the homogeneous-grid baseline (its map takes minutes to build; its JSON "
               "fields are then those of an empty map); default: off");
  CLI11_PARSE(app, argc, argv);
  const bool with_homogeneous = !no_homogeneous;
  const unsigned used_threads = detail::thread_count(threads);  // as the scorer counts them
  const testing::LabScan lab = testing::scan_lab();
  PreprocessParams pp;
  pp.target_points = 400000;
  const PreprocessResult pre = preprocess(lab.world, pp);
  const Eigen::Vector3d o = pre.transform * lab.origin;
  const Point3 origin(o.x(), o.y(), o.z());
  RobotGeometry robot;
  robot.scanner_height = origin.z;
  NbvParams params;
  params.threads = threads;

  std::fprintf(stderr, "building the semioctree map ...\n");
  double semi_build = 0, homo_build = 0;
  const auto semi = classified_map(pre, origin, 0.8, &semi_build);
  std::fprintf(stderr, "semioctree NBV ...\n");
  const NbvResult s = next_best_view(*semi, robot, origin, {origin}, params);
  std::vector<Point3> semi_positions;
  for (const NbvCandidate& c : s.candidates) semi_positions.push_back(c.position);
  const std::vector<Point3> semi_sub = subset(semi_positions, subset_size);
  // Our scores of the subset, for the agreement with castRay.
  auto t_sub = std::chrono::steady_clock::now();
  ScoringStats semi_sub_stats;
  const std::vector<double> semi_sub_scores =
      score_positions(*semi, semi_sub, params, &semi_sub_stats);
  const double semi_sub_s = bench::seconds_since(t_sub);
  // Method 2 on the same subset, at level 2 (0.2 m cells).
  NbvParams m2 = params;
  m2.method = 2;
  m2.level = 2;
  ScoringStats m2_stats;
  t_sub = std::chrono::steady_clock::now();
  const std::vector<double> m2_scores = score_positions(*semi, semi_sub, m2, &m2_stats);
  const double m2_sub_s = bench::seconds_since(t_sub);
  // Method 3 (frontier surface) on all candidates, against method 1's scoring.
  // What the survey runs: method 1 counted inside the room (NbvParams::room).
  NbvParams in_room = params;
  in_room.room = room_box(*semi, {origin}, origin.z, 0.0, pre.ceiling_height);
  const NbvResult sr = next_best_view(*semi, robot, origin, {origin}, in_room);
  const double room_total = sr.seconds_candidates + sr.seconds_scoring + sr.seconds_stop;
  NbvParams m3 = params;
  m3.method = 3;
  ScoringStats m3_stats;
  t_sub = std::chrono::steady_clock::now();
  score_positions(*semi, semi_positions, m3, &m3_stats);
  const double m3_s = bench::seconds_since(t_sub);
  std::size_t m2_best = 0, m1_best = 0;
  for (std::size_t i = 0; i < semi_sub.size(); ++i) {
    if (m2_scores[i] > m2_scores[m2_best]) m2_best = i;
    if (semi_sub_scores[i] > semi_sub_scores[m1_best]) m1_best = i;
  }

  std::fprintf(stderr, "building the homogeneous map ...\n");
  const auto homo = with_homogeneous ? classified_map(pre, origin, 0.05, &homo_build)
                                     : std::make_unique<SemiOcTree>(0.05);
  std::fprintf(stderr, "homogeneous NBV (subset) ...\n");
  auto t0 = std::chrono::steady_clock::now();
  CandidateReport homo_rep;
  const std::vector<Point3> homo_positions =
      find_candidates(*homo, robot, origin, {origin}, params, &homo_rep);
  const double homo_candidates_s = bench::seconds_since(t0);
  const std::vector<Point3> homo_sub = subset(homo_positions, subset_size);
  t0 = std::chrono::steady_clock::now();
  ScoringStats homo_stats;
  score_positions(*homo, homo_sub, params, &homo_stats);
  const std::size_t homo_targets = homo_stats.targets, homo_segments = homo_stats.segments;
  const double homo_sub_s = bench::seconds_since(t0);
  const double homo_scoring_s =
      homo_sub.empty() ? 0 : homo_sub_s * double(homo_positions.size()) / double(homo_sub.size());

  std::fprintf(stderr, "OctoMap castRay scoring (subset) ...\n");
  t0 = std::chrono::steady_clock::now();
  const auto occupancy = to_occupancy_octree(*semi);
  const double octo_build_s = bench::seconds_since(t0);
  CastRayScorer scorer{*semi, *occupancy, {}, {}, params.limits};
  semi->for_each_octant([&](const Octant& oc) {
    if (oc.label() != Label::kOccluded) return;
    scorer.targets.push_back(oc.center);
    scorer.weights.push_back(double(std::uint64_t(1) << (3 * (semi->leaf_level() - oc.level))));
  });
  std::vector<double> octo_scores(semi_sub.size(), 0);
  std::atomic<std::size_t> next{0}, octo_cast{0};
  t0 = std::chrono::steady_clock::now();
  {
    auto work = [&] {
      octomap::KeyRay ray;
      std::size_t cast = 0;
      for (std::size_t i; (i = next.fetch_add(1)) < semi_sub.size();)
        octo_scores[i] = scorer.score(semi_sub[i], ray, cast);
      octo_cast += cast;
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < used_threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
  }
  const double octo_sub_s = bench::seconds_since(t0);
  const double octo_scoring_s =
      semi_sub.empty() ? 0 : octo_sub_s * double(semi_positions.size()) / double(semi_sub.size());
  double max_rel = 0, mean_rel = 0;
  for (std::size_t i = 0; i < semi_sub.size(); ++i) {
    const double d = std::fabs(octo_scores[i] - semi_sub_scores[i]) /
                     std::max(1.0, std::fabs(semi_sub_scores[i]));
    max_rel = std::max(max_rel, d);
    mean_rel += d / double(semi_sub.size());
  }
  std::size_t rank_ours = 0, rank_octo = 0;
  for (std::size_t i = 0; i < semi_sub.size(); ++i) {
    if (semi_sub_scores[i] > semi_sub_scores[rank_ours]) rank_ours = i;
    if (octo_scores[i] > octo_scores[rank_octo]) rank_octo = i;
  }

  const double semi_total = s.seconds_candidates + s.seconds_scoring + s.seconds_stop;
  const double homo_total = homo_candidates_s + homo_scoring_s;  // stop percentage left out
  std::printf(
      "{\n  \"benchmark\": \"one NBV evaluation (method 1) on the lab after the first scan, 0.05 m "
      "leaf\",\n"
      "  \"threads\": %u, \"points\": %zu,\n"
      "  \"semioctree\": {\"coarse\": 0.8, \"octants\": %llu, \"map_seconds\": %.3f,\n"
      "    \"grid_points\": %zu, \"not_empty\": %zu, \"cylinder_blocked\": %zu, \"unreachable\": "
      "%zu, "
      "\"blind_octants_freed\": %zu, \"robot_in_map\": %s,\n"
      "    \"candidates\": %zu, \"occluded_targets\": %zu, \"segments\": %zu, "
      "\"segments_blocked_by_cache\": %zu, \"segments_visible\": %zu,\n"
      "    \"seconds_candidates\": %.4f, \"seconds_scoring\": %.4f, \"seconds_stop\": %.4f, "
      "\"seconds_total\": %.4f, \"cpu_seconds_scoring\": %.3f,\n"
      "    \"best\": {\"x\": %.3f, \"y\": %.3f, \"z\": %.3f, \"score\": %.2f}, \"stop_percent\": "
      "%.4f},\n"
      "  \"homogeneous\": {\"coarse\": 0.05, \"octants\": %llu, \"map_seconds\": %.3f,\n"
      "    \"candidates\": %zu, \"occluded_targets\": %zu, \"scored_candidates\": %zu, "
      "\"scored_segments\": %zu,\n"
      "    \"seconds_candidates\": %.4f, \"seconds_scoring_subset\": %.4f, "
      "\"seconds_scoring_scaled\": %.3f, \"seconds_total_scaled\": %.3f,\n"
      "    \"cpu_seconds_scoring_subset\": %.3f, \"semioctree_cpu_seconds_own_subset\": %.3f,\n"
      "    \"note\": \"scoring timed on a fixed subset of its candidates and scaled to all; stop "
      "percentage not included\"},\n"
      "  \"octomap_castRay\": {\"octree_build_seconds\": %.3f, \"scored_candidates\": %zu, "
      "\"segments\": %zu,\n"
      "    \"seconds_scoring_subset\": %.4f, \"seconds_scoring_scaled\": %.3f,\n"
      "    \"semioctree_seconds_same_subset\": %.4f,\n"
      "    \"score_max_relative_difference\": %.4f, \"score_mean_relative_difference\": %.5f,\n"
      "    \"same_best_in_subset\": %s,\n"
      "    \"note\": \"the semioctree's candidates and occluded targets; castRay on "
      "to_occupancy_octree decides blocked, computeRayKeys + search on the SemiOcTree gives the "
      "labels; subset scaled to all candidates\"},\n"
      "  \"semioctree_method2_level2\": {\"cell\": 0.2, \"targets\": %zu, \"scored_candidates\": "
      "%zu, "
      "\"segments\": %zu, \"seconds_scoring_subset\": %.4f, \"seconds_scoring_scaled\": %.3f, "
      "\"same_best_as_method1_in_subset\": %s},\n"
      "  \"semioctree_method3\": {\"targets\": %zu, \"candidates\": %zu, \"seconds_scoring\": "
      "%.4f, \"scoring_speedup_vs_method1\": %.2f},\n"
      "  \"semioctree_room\": {\"found\": %s, \"min\": [%.2f, %.2f, %.2f], \"max\": [%.2f, %.2f, "
      "%.2f], \"occluded_targets\": %zu, \"seconds_total\": %.4f, \"best\": {\"x\": %.3f, "
      "\"y\": %.3f}, \"stop_percent\": %.4f, \"speedup_vs_whole_map\": %.2f,\n"
      "    \"note\": \"the survey's NBV: targets and Eq 5 inside room_box\"},\n"
      "  \"scoring_speedup_vs_homogeneous\": %.2f,\n"
      "  \"scoring_speedup_vs_octomap_castRay\": %.2f,\n"
      "  \"total_speedup_vs_homogeneous\": %.2f\n}\n",
      used_threads, pre.cloud->size(), static_cast<unsigned long long>(semi->statistics().total()),
      semi_build, s.candidate_report.grid_points, s.candidate_report.not_empty,
      s.candidate_report.cylinder_blocked, s.candidate_report.unreachable,
      s.candidate_report.blind_octants_freed, s.candidate_report.robot_in_map ? "true" : "false",
      s.candidates.size(), s.scoring.targets, s.scoring.segments, s.scoring.blocked_by_cache,
      s.scoring.visible, s.seconds_candidates, s.seconds_scoring, s.seconds_stop, semi_total,
      s.scoring.cpu_seconds, s.best ? s.best->position.x : 0.0, s.best ? s.best->position.y : 0.0,
      s.best ? s.best->position.z : 0.0, s.best ? s.best->score : 0.0, s.stop_percent,
      static_cast<unsigned long long>(homo->statistics().total()), homo_build,
      homo_positions.size(), homo_targets, homo_sub.size(), homo_segments, homo_candidates_s,
      homo_sub_s, homo_scoring_s, homo_total, homo_stats.cpu_seconds, semi_sub_stats.cpu_seconds,
      octo_build_s, semi_sub.size(), octo_cast.load(), octo_sub_s, octo_scoring_s, semi_sub_s,
      max_rel, mean_rel, rank_ours == rank_octo ? "true" : "false", m2_stats.targets,
      semi_sub.size(), m2_stats.segments, m2_sub_s,
      semi_sub.empty() ? 0.0 : m2_sub_s * double(semi_positions.size()) / double(semi_sub.size()),
      m2_best == m1_best ? "true" : "false", m3_stats.targets, semi_positions.size(), m3_s,
      s.seconds_scoring / std::max(1e-9, m3_s), in_room.room ? "true" : "false",
      in_room.room ? in_room.room->min.x : 0.0, in_room.room ? in_room.room->min.y : 0.0,
      in_room.room ? in_room.room->min.z : 0.0, in_room.room ? in_room.room->max.x : 0.0,
      in_room.room ? in_room.room->max.y : 0.0, in_room.room ? in_room.room->max.z : 0.0,
      sr.scoring.targets, room_total, sr.best ? sr.best->position.x : 0.0,
      sr.best ? sr.best->position.y : 0.0, sr.stop_percent, semi_total / std::max(1e-9, room_total),
      homo_scoring_s / std::max(1e-9, s.seconds_scoring),
      octo_scoring_s / std::max(1e-9, s.seconds_scoring), homo_total / std::max(1e-9, semi_total));
  return 0;
}
