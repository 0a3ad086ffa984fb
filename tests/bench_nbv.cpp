// Benchmark: one Next-Best-View evaluation (candidates, Eq 3 scores with method 1, stop
// percentage; methods 2 and 3 and the room-restricted NBV for comparison) on the lab after
// the first scan at 0.05 m, in one run, with 1 thread and with all threads, three ways:
//  * semioctree: the SemiOcTree (0.8 m coarse voxels), every feasible candidate scored
//    (the production path);
//  * semioctree_k0: the same code on the SemiOcTree with k = 0 (coarse = leaf = 0.05 m,
//    i.e. discretize(..., {0.05, 0.05, 0.8})) built from the same cloud through the same
//    stages, scoring the semioctree's candidates against its own occluded targets;
//  * octomap_castRay: the semioctree's candidates and targets scored the way an OctoMap
//    user would: castRay on an octomap::OcTree holding the same map
//    (to_occupancy_octree: occupied leaves occupied, empty/out/door/window free, occluded
//    absent and ignored as unknown) decides whether the line is blocked; for lines that
//    are not, computeRayKeys + OctoMap's search() on the SemiOcTree used as a plain OctoMap
//    tree (a 16-level descent per key) gives the labels along the line, to count the
//    occluded octants crossed (consecutive keys in the same node are one octant) and to
//    zero lines through a door or window. castRay is const: the candidates are split over
//    the threads, one OcTree read by all.
// The two baselines would take minutes on every candidate, so they score a fixed,
// deterministic subset (every j-th candidate) and the semioctree scores that same subset:
// the headline ratios are those of the subset, both sides timed on it with the same
// threads. The semioctree's full run is printed beside them, never a ratio scaled to it.
// Prints JSON on stdout, progress on stderr.
//
//   bench_nbv [--subset N] [--no-homogeneous]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semioctree/nbv.h"
#include "semioctree/octomap_ext/export.h"
#include "src/parallel_for.h"
#include "src/scanner_limits.h"
#include "support/bench_common.h"
#include "support/lab_map.h"

using namespace semioctree;
using json = nlohmann::ordered_json;  // fields in the order written

namespace {

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
      "Benchmark: one Next-Best-View evaluation (method 1; methods 2 and 3 and the room's NBV "
      "for comparison) on the lab after the first scan at 0.05 m: on the semioctree, on the "
      "SemiOcTree with k = 0 and with OctoMap castRay scoring, with 1 thread and with all "
      "threads, in one run. Prints JSON on stdout, progress on stderr."};
  std::size_t subset_size = 16;
  app.add_option("--subset", subset_size,
                 "number of candidates (every j-th of the semioctree's list) scored by both "
                 "sides of the baselines' ratios (k = 0 grid, OctoMap castRay) and by method 2; "
                 "the headline ratios are those of this subset")
      ->check(CLI::Range(1LL, std::numeric_limits<long long>::max(), "POSITIVE"))
      ->capture_default_str();
  bool no_homogeneous = false;
  app.add_flag("--no-homogeneous", no_homogeneous,
               "skip the k = 0 baseline (its map takes minutes to build; its JSON fields and "
               "ratio are then null); default: off");
  CLI11_PARSE(app, argc, argv);
  const bool with_homogeneous = !no_homogeneous;
  std::fprintf(stderr, "scanning the lab ...\n");
  const testing::PreprocessedLab lab = testing::preprocessed_lab();
  const PreprocessResult& pre = lab.pre;
  const Point3& origin = lab.origin;
  RobotGeometry robot;
  robot.scanner_height = origin.z;

  std::fprintf(stderr, "building the semioctree map ...\n");
  double semi_build = 0, homo_build = 0;
  const auto semi = testing::classified_lab_map(lab, 0.8, 0, &semi_build);
  std::fprintf(stderr, "building the k = 0 map ...\n");
  const auto homo = with_homogeneous ? testing::classified_lab_map(lab, 0.05, 0, &homo_build)
                                     : std::make_unique<SemiOcTree>(0.05);
  std::fprintf(stderr, "the OctoMap tree and the targets ...\n");
  auto t0 = std::chrono::steady_clock::now();
  const auto occupancy = to_occupancy_octree(*semi);
  const double octo_build_s = bench::seconds_since(t0);
  CastRayScorer scorer{*semi, *occupancy, {}, {}, NbvParams{}.limits};
  semi->for_each_octant([&](const Octant& oc) {
    if (oc.label() != Label::kOccluded) return;
    scorer.targets.push_back(oc.center);
    scorer.weights.push_back(double(std::uint64_t(1) << (3 * (semi->leaf_level() - oc.level))));
  });

  json runs = json::array();
  bench::SideSeconds semi_sub_s, homo_sub_s, octo_sub_s, semi_full_s;
  json semi_json, octo_agreement, m2_json, homo_json;
  for (unsigned threads : bench::thread_counts()) {
    NbvParams params;
    params.threads = threads;
    json run;
    run["threads"] = threads;
    std::fprintf(stderr, "%u thread(s): semioctree NBV ...\n", threads);
    const NbvResult s = next_best_view(*semi, robot, origin, {origin}, params);
    const double semi_total = s.seconds_candidates + s.seconds_scoring + s.seconds_stop;
    std::vector<Point3> semi_positions;
    for (const NbvCandidate& c : s.candidates) semi_positions.push_back(c.position);
    const std::vector<Point3> semi_sub = subset(semi_positions, subset_size);
    run["semioctree_full_run"] = {
        {"candidates", s.candidates.size()},    {"seconds_candidates", s.seconds_candidates},
        {"seconds_scoring", s.seconds_scoring}, {"seconds_stop", s.seconds_stop},
        {"seconds_total", semi_total},          {"cpu_seconds_scoring", s.scoring.cpu_seconds}};
    // The subset, scored by the semioctree: one side of the headline ratios.
    t0 = std::chrono::steady_clock::now();
    ScoringStats semi_sub_stats;
    const std::vector<double> semi_sub_scores =
        score_positions(*semi, semi_sub, params, &semi_sub_stats);
    const double semi_sub_seconds = bench::seconds_since(t0);
    run["semioctree_subset_seconds"] = semi_sub_seconds;
    // Method 2 on the same subset, at level 2 (0.2 m cells).
    NbvParams m2 = params;
    m2.method = 2;
    m2.level = 2;
    ScoringStats m2_stats;
    t0 = std::chrono::steady_clock::now();
    const std::vector<double> m2_scores = score_positions(*semi, semi_sub, m2, &m2_stats);
    const double m2_sub_s = bench::seconds_since(t0);
    std::size_t m2_best = 0, m1_best = 0;
    for (std::size_t i = 0; i < semi_sub.size(); ++i) {
      if (m2_scores[i] > m2_scores[m2_best]) m2_best = i;
      if (semi_sub_scores[i] > semi_sub_scores[m1_best]) m1_best = i;
    }
    run["semioctree_method2_level2_subset_seconds"] = m2_sub_s;
    // Method 3 (frontier surface) on all candidates, against method 1's scoring of them.
    NbvParams m3 = params;
    m3.method = 3;
    ScoringStats m3_stats;
    t0 = std::chrono::steady_clock::now();
    score_positions(*semi, semi_positions, m3, &m3_stats);
    const double m3_s = bench::seconds_since(t0);
    run["semioctree_method3"] = {
        {"seconds_scoring", m3_s},
        {"scoring_speedup_vs_method1", s.seconds_scoring / std::max(1e-9, m3_s)}};
    // What the survey runs: method 1 counted inside the room (NbvParams::room).
    NbvParams in_room = params;
    in_room.room = room_box(*semi, {origin}, origin.z, 0.0, pre.ceiling_height);
    const NbvResult sr = next_best_view(*semi, robot, origin, {origin}, in_room);
    const double room_total = sr.seconds_candidates + sr.seconds_scoring + sr.seconds_stop;
    run["semioctree_room"] = {{"seconds_total", room_total},
                              {"speedup_vs_whole_map", semi_total / std::max(1e-9, room_total)}};

    // The k = 0 map: the same subset of positions against its own occluded targets.
    json homo_run = nullptr;
    double homo_sub_seconds = 0;
    if (with_homogeneous) {
      std::fprintf(stderr, "%u thread(s): k = 0 candidates and subset scoring ...\n", threads);
      t0 = std::chrono::steady_clock::now();
      CandidateReport homo_rep;
      const std::vector<Point3> homo_positions =
          find_candidates(*homo, robot, origin, {origin}, params, &homo_rep);
      const double homo_candidates_s = bench::seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      ScoringStats homo_stats;
      score_positions(*homo, semi_sub, params, &homo_stats);
      homo_sub_seconds = bench::seconds_since(t0);
      homo_run = {{"candidates", homo_positions.size()},
                  {"seconds_candidates", homo_candidates_s},
                  {"candidates_speedup", homo_candidates_s / std::max(1e-9, s.seconds_candidates)},
                  {"subset_seconds", homo_sub_seconds}};
      homo_json = {{"coarse", 0.05},
                   {"octants", homo->statistics().total()},
                   {"map_seconds", homo_build},
                   {"candidates", homo_positions.size()},
                   {"occluded_targets", homo_stats.targets},
                   {"subset_segments", homo_stats.segments},
                   {"note",
                    "scores the semioctree's subset of candidates against its own occluded "
                    "targets (the same space in leaf-sized octants); its own candidates are "
                    "found and timed in full"}};
    }
    run["semioctree_k0"] = homo_run;

    std::fprintf(stderr, "%u thread(s): OctoMap castRay scoring of the subset ...\n", threads);
    std::vector<double> octo_scores(semi_sub.size(), 0);
    std::vector<std::size_t> cast_of(semi_sub.size(), 0);
    t0 = std::chrono::steady_clock::now();
    {
      std::vector<octomap::KeyRay> rays(threads);
      detail::parallel_for(semi_sub.size(), threads, 1, [&](std::size_t i, unsigned worker) {
        octo_scores[i] = scorer.score(semi_sub[i], rays[worker], cast_of[i]);
      });
    }
    const double octo_sub_seconds = bench::seconds_since(t0);
    run["octomap_castRay_subset_seconds"] = octo_sub_seconds;
    runs.push_back(run);
    (threads == 1 ? semi_sub_s.one_thread : semi_sub_s.all_threads) = semi_sub_seconds;
    (threads == 1 ? homo_sub_s.one_thread : homo_sub_s.all_threads) = homo_sub_seconds;
    (threads == 1 ? octo_sub_s.one_thread : octo_sub_s.all_threads) = octo_sub_seconds;
    (threads == 1 ? semi_full_s.one_thread : semi_full_s.all_threads) = s.seconds_scoring;

    // What the runs found (the same for every thread count).
    double max_rel = 0, mean_rel = 0;
    std::size_t cast = 0, rank_ours = 0, rank_octo = 0;
    for (std::size_t i = 0; i < semi_sub.size(); ++i) {
      const double d = std::fabs(octo_scores[i] - semi_sub_scores[i]) /
                       std::max(1.0, std::fabs(semi_sub_scores[i]));
      max_rel = std::max(max_rel, d);
      mean_rel += d / double(semi_sub.size());
      cast += cast_of[i];
      if (semi_sub_scores[i] > semi_sub_scores[rank_ours]) rank_ours = i;
      if (octo_scores[i] > octo_scores[rank_octo]) rank_octo = i;
    }
    octo_agreement = {{"octree_build_seconds", octo_build_s},
                      {"scored_candidates", semi_sub.size()},
                      {"segments", cast},
                      {"score_max_relative_difference", max_rel},
                      {"score_mean_relative_difference", mean_rel},
                      {"same_best_in_subset", rank_ours == rank_octo},
                      {"note",
                       "the semioctree's candidates and occluded targets; castRay on "
                       "to_occupancy_octree decides blocked, computeRayKeys + search on the "
                       "SemiOcTree gives the labels; candidates split over the threads"}};
    m2_json = {{"cell", 0.2},
               {"targets", m2_stats.targets},
               {"scored_candidates", semi_sub.size()},
               {"segments", m2_stats.segments},
               {"same_best_as_method1_in_subset", m2_best == m1_best}};
    semi_json = {
        {"coarse", 0.8},
        {"octants", semi->statistics().total()},
        {"map_seconds", semi_build},
        {"grid_points", s.candidate_report.grid_points},
        {"not_empty", s.candidate_report.not_empty},
        {"cylinder_blocked", s.candidate_report.cylinder_blocked},
        {"unreachable", s.candidate_report.unreachable},
        {"blind_octants_freed", s.candidate_report.blind_octants_freed},
        {"robot_in_map", s.candidate_report.robot_in_map},
        {"candidates", s.candidates.size()},
        {"subset_candidates", semi_sub.size()},
        {"occluded_targets", s.scoring.targets},
        {"segments", s.scoring.segments},
        {"segments_blocked_by_cache", s.scoring.blocked_by_cache},
        {"segments_blocked_by_walls", s.scoring.blocked_by_walls},
        {"segments_visible", s.scoring.visible},
        {"subset_segments", semi_sub_stats.segments},
        {"best",
         {{"x", s.best ? s.best->position.x : 0.0},
          {"y", s.best ? s.best->position.y : 0.0},
          {"z", s.best ? s.best->position.z : 0.0},
          {"score", s.best ? s.best->score : 0.0}}},
        {"stop_percent", s.stop_percent},
        {"method3_targets", m3_stats.targets},
        {"room",
         {{"found", bool(in_room.room)},
          {"min", in_room.room ? json{in_room.room->min.x, in_room.room->min.y, in_room.room->min.z}
                               : json(nullptr)},
          {"max", in_room.room ? json{in_room.room->max.x, in_room.room->max.y, in_room.room->max.z}
                               : json(nullptr)},
          {"occluded_targets", sr.scoring.targets},
          {"best",
           {{"x", sr.best ? sr.best->position.x : 0.0},
            {"y", sr.best ? sr.best->position.y : 0.0}}},
          {"stop_percent", sr.stop_percent},
          {"note", "the survey's NBV: targets and Eq 5 inside room_box"}}}};
  }
  if (bench::all_threads() == 1) {
    semi_sub_s.all_threads = semi_sub_s.one_thread;
    homo_sub_s.all_threads = homo_sub_s.one_thread;
    octo_sub_s.all_threads = octo_sub_s.one_thread;
    semi_full_s.all_threads = semi_full_s.one_thread;
  }

  json out;
  out["benchmark"] = "one NBV evaluation (method 1) on the lab after the first scan, 0.05 m leaf";
  out["points"] = pre.cloud->size();
  out["threads"] = bench::all_threads();
  out["semioctree"] = semi_json;
  out["semioctree_k0"] = homo_json;
  out["octomap_castRay"] = octo_agreement;
  out["semioctree_method2_level2"] = m2_json;
  out["runs"] = runs;
  const std::string subset_note =
      "both sides score the same subset of " + std::to_string(subset_size) +
      " candidates at most (every j-th): the baseline is too slow for all of them; the "
      "semioctree's full run is in runs[].semioctree_full_run";
  json castray = bench::headline("nbv_scoring_vs_octomap_castRay_subset",
                                 "OctoMap castRay scoring seconds / semioctree scoring seconds, "
                                 "same candidates and targets, same threads",
                                 octo_sub_s, semi_sub_s, subset_note);
  json k0 = bench::headline("nbv_scoring_vs_semioctree_k0_subset",
                            "SemiOcTree k = 0 scoring seconds / semioctree scoring seconds, same "
                            "candidates, each map's own occluded targets, same threads",
                            homo_sub_s, semi_sub_s, subset_note);
  // Beside the subset's ratios, the semioctree's scoring of every candidate (no ratio).
  for (json* h : {&castray, &k0})
    (*h)["semioctree_all_candidates_scoring_seconds"] = {
        {"1_thread", semi_full_s.one_thread},
        {"all_threads", bench::seconds_or_null(semi_full_s.all_threads)}};
  out["headlines"] = json::array({castray, k0});
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
