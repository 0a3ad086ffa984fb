#include "semioctree/nbv/scoring.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include "../parallel_for.h"
#include "../scanner_limits.h"
#include "label_roles.h"
#include "semioctree/timing.h"
#include "targets.h"
#include "visibility.h"
#include "wall_shadows.h"

namespace semioctree {

namespace {

using detail::parallel_for;
using detail::ScannerLimits;
using detail::thread_count;
using nbv_detail::BlockerCache;
using nbv_detail::BlockingColumns;
using nbv_detail::facing_area;
using nbv_detail::Los;
using nbv_detail::los_cells;
using nbv_detail::los_octants;
using nbv_detail::method1_targets;
using nbv_detail::resolve_level;
using nbv_detail::Target;
using nbv_detail::targets_for;
using nbv_detail::WallShadows;

// Targets per partial sum of a score: a score is the sum, in order, of the sums over
// consecutive blocks of this many targets, each in order, whoever computes them.
constexpr std::size_t kTargetsPerSum = 16384;
// Fewer candidates than this are scored a block of targets at a time, spread over the
// threads; more, a candidate at a time (its blocker cache warm over all its targets).
constexpr std::size_t kSplitBelow = 8;

// Eq 3 of each position over `targets` (docs/nbv.md, "Score" and "Cost").
std::vector<double> score_targets(const SemiOcTree& tree, const std::vector<Target>& targets,
                                  const std::vector<Point3>& positions, const NbvParams& params,
                                  ScoringStats* stats) {
  const unsigned level = resolve_level(tree, params);
  const ScannerLimits lim(params.limits);
  const std::size_t blocks =
      std::max<std::size_t>(1, (targets.size() + kTargetsPerSum - 1) / kTargetsPerSum);
  const bool split = positions.size() < kSplitBelow;
  const std::size_t per_item = split ? 1 : blocks;  // blocks of targets per work item
  const std::size_t items_per_position = blocks / per_item;
  std::vector<double> partial(positions.size() * blocks, 0.0);
  std::vector<ScoringStats> per(positions.size() * items_per_position);
  // The last blocker found on a line to each target, from any candidate: the
  // occluder that hides a target usually hides it from the neighbouring
  // candidates too. It only saves traversals (any blocker is a proof), so the
  // races between threads on it do not change any result.
  std::vector<std::atomic<std::uint64_t>> memo(2 * targets.size());
  for (auto& m : memo) m.store(0, std::memory_order_relaxed);
  const unsigned threads = thread_count(params.threads);
  std::vector<BlockerCache> caches(threads, BlockerCache(tree));
  // The plane around the candidates and the targets, for the walls' shadows.
  Point3 lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity());
  Point3 hi(-lo.x, -lo.y, -lo.z);
  const auto extend = [&](const Point3& p) {
    lo = Point3(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
    hi = Point3(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
  };
  for (const Target& t : targets) extend(t.center);
  for (const Point3& p : positions) extend(p);
  std::optional<BlockingColumns> columns;
  if (!targets.empty() && !positions.empty())
    columns.emplace(tree, params.see_through_doors, positions.front().z, lo, hi, lo.z, hi.z);
  std::vector<WallShadows> shadows;
  if (columns) shadows.assign(threads, WallShadows(*columns));
  // The position each worker's cache and shadows were last set for.
  std::vector<std::size_t> set_for(threads, positions.size());
  std::vector<std::atomic<std::size_t>> items_left(positions.size());
  for (auto& n : items_left) n.store(items_per_position, std::memory_order_relaxed);
  std::atomic<std::size_t> scored{0};
  const double cpu = parallel_for(
      positions.size() * items_per_position, threads, 1, [&](std::size_t item, unsigned worker) {
        const std::size_t c = item / items_per_position;
        const std::size_t first_block = (item % items_per_position) * per_item;
        const Point3& a = positions[c];
        BlockerCache& cache = caches[worker];
        WallShadows* shadow = columns ? &shadows[worker] : nullptr;
        if (set_for[worker] != c) {
          set_for[worker] = c;
          cache.reset(a);
          if (shadow) {
            const std::optional<Octant> own = tree.find_octant(a);
            shadow->reset(a, !own || nbv_detail::blocks(own->label(), params.see_through_doors));
          }
        }
        // Counted here, stored once an item: neighbouring items' counts share a cache line.
        ScoringStats st;
        for (std::size_t b = first_block; b < first_block + per_item; ++b) {
          double sum = 0;
          const std::size_t end = std::min(targets.size(), (b + 1) * kTargetsPerSum);
          for (std::size_t i = b * kTargetsPerSum; i < end; ++i) {
            const Target& t = targets[i];
            const double weight = params.method == 3 ? facing_area(t, a) : t.weight;
            if (weight == 0 || !lim.in_view(a, t.center)) continue;
            ++st.segments;
            if (shadow && shadow->hides(t.center)) {
              ++st.blocked_by_walls;
              continue;
            }
            cache.aim(t.center);
            if (cache.blocked_in_bin() ||
                cache.passes_through(memo[2 * i].load(std::memory_order_relaxed)) ||
                cache.passes_through(memo[2 * i + 1].load(std::memory_order_relaxed))) {
              ++st.blocked_by_cache;
              continue;
            }
            const Los los = params.method == 2
                                ? los_cells(tree, level, a, t, &cache, params.see_through_doors)
                                : los_octants(tree, a, t.center, &cache, params.see_through_doors);
            // Keep the last two blockers (stored only when new: the other workers read
            // these lines).
            if (los.blocker && memo[2 * i].load(std::memory_order_relaxed) != los.blocker) {
              memo[2 * i + 1].store(memo[2 * i].load(std::memory_order_relaxed),
                                    std::memory_order_relaxed);
              memo[2 * i].store(los.blocker, std::memory_order_relaxed);
            }
            if (!los.visible) continue;
            ++st.visible;
            // Method 3: a frontier face in view is new surface whatever lies on the way.
            sum += params.method == 3 ? weight : weight / (1.0 + double(los.n));
          }
          partial[c * blocks + b] = sum;
        }
        per[item] = st;
        if (items_left[c].fetch_sub(1, std::memory_order_acq_rel) == 1) {
          const std::size_t done = scored.fetch_add(1, std::memory_order_relaxed) + 1;
          if (params.progress) params.progress(done, positions.size());
        }
      });
  std::vector<double> scores(positions.size(), 0.0);
  for (std::size_t c = 0; c < positions.size(); ++c)
    for (std::size_t b = 0; b < blocks; ++b) scores[c] += partial[c * blocks + b];
  if (stats) {
    *stats = ScoringStats{};
    stats->targets = targets.size();
    stats->cpu_seconds = cpu;
    for (const ScoringStats& p : per) {
      stats->segments += p.segments;
      stats->blocked_by_cache += p.blocked_by_cache;
      stats->blocked_by_walls += p.blocked_by_walls;
      stats->visible += p.visible;
    }
  }
  return scores;
}

}  // namespace

std::vector<double> score_positions(const SemiOcTree& tree, const std::vector<Point3>& positions,
                                    const NbvParams& params, ScoringStats* stats) {
  return score_targets(tree, targets_for(tree, params), positions, params, stats);
}

namespace {

// Eq 5's denominator: the volume of all but unknown space (m³), inside `room` if given.
double counted_volume(const SemiOcTree& tree, const std::optional<RoomBox>& room) {
  double total = 0;
  if (room) {
    tree.for_each_octant([&](const Octant& o) {
      if (o.label() != Label::kUnknown) total += room->overlap(o.center, o.size);
    });
  } else {
    const OctantStatistics stats = tree.statistics();
    for (Label l : {Label::kOccluded, Label::kEmpty, Label::kOccupied, Label::kOut, Label::kDoor,
                    Label::kWindow, Label::kScan, Label::kNbv})
      total += stats.volume[static_cast<int>(l)];
  }
  return total;
}

// Eq 5 from `nbv` over `targets`, method 1's targets in `room`.
double stop_percentage_over(const SemiOcTree& tree, const std::vector<Target>& targets,
                            const Point3& nbv, const ScannerView& limits, unsigned threads,
                            const std::optional<RoomBox>& room) {
  const double total = counted_volume(tree, room);
  if (total <= 0) return 0.0;
  const ScannerLimits lim(limits);
  // Each target's share seen: its Eq 4 term (1, 1/(1+n) or 0).
  std::vector<double> share(targets.size(), 0.0);
  parallel_for(targets.size(), thread_count(threads), 256, [&](std::size_t i, unsigned) {
    if (!lim.in_view(nbv, targets[i].center)) return;
    const Los los = los_octants(tree, nbv, targets[i].center);
    if (los.visible) share[i] = 1.0 / (1.0 + double(los.n));
  });
  const double leaf_volume = std::pow(tree.leaf_size(), 3);
  double seen = 0;
  for (std::size_t i = 0; i < targets.size(); ++i)
    seen += share[i] * targets[i].weight * leaf_volume;
  return 100.0 * seen / total;
}

}  // namespace

double stop_percentage(const SemiOcTree& tree, const Point3& nbv, const ScannerView& limits,
                       unsigned threads, const std::optional<RoomBox>& room) {
  return stop_percentage_over(tree, method1_targets(tree, room), nbv, limits, threads, room);
}

NbvResult next_best_view(const SemiOcTree& tree, const RobotGeometry& robot,
                         const Point3& robot_position, const std::vector<Point3>& past_scans,
                         const NbvParams& params) {
  const auto t0 = Clock::now();
  std::vector<double> path_m;
  CandidateReport report;
  const std::vector<Point3> positions =
      find_candidates(tree, robot, robot_position, past_scans, params, &report, &path_m);
  std::vector<NbvCandidate> candidates;
  candidates.reserve(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    NbvCandidate& c = candidates.emplace_back();
    c.position = positions[i];
    c.path_m = path_m[i];
  }
  const double seconds_candidates = seconds_since(t0);
  NbvResult res = best_view_among(tree, std::move(candidates), params);
  res.candidate_report = report;
  res.seconds_candidates = seconds_candidates;
  return res;
}

NbvResult best_view_among(const SemiOcTree& tree, std::vector<NbvCandidate> candidates,
                          const NbvParams& params) {
  if (!(params.travel_weight >= 0))
    throw std::invalid_argument("NbvParams::travel_weight must be >= 0");
  NbvResult res;
  auto t0 = Clock::now();
  std::vector<Point3> positions;
  positions.reserve(candidates.size());
  for (const NbvCandidate& c : candidates) positions.push_back(c.position);
  const std::vector<Target> targets = targets_for(tree, params);
  // Where the targets far outnumber a prediction's rays (a real scan seen through its
  // openings: a million targets, 24 000 rays), every candidate's overlap is predicted
  // first, at a tenth of its scoring at most, and only the candidates predicted to
  // register are scored: the best of those is the NBV either way.
  std::vector<std::optional<OverlapPrediction>> overlap(positions.size());
  std::vector<std::size_t> to_score, skipped;
  const bool predict_first =
      params.overlap_top &&
      double(targets.size()) >= params.predict_first_factor * double(prediction_rays(params));
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (predict_first) {
      overlap[i] = predict_overlap(tree, positions[i], params);
      if (overlap[i]->share < params.min_overlap) {
        skipped.push_back(i);
        continue;
      }
    }
    to_score.push_back(i);
  }
  res.low_overlap = skipped.size();
  std::vector<Point3> scored_positions;
  for (std::size_t i : to_score) scored_positions.push_back(positions[i]);
  const std::vector<double> scored =
      score_targets(tree, targets, scored_positions, params, &res.scoring);
  std::vector<double> scores(positions.size(), 0.0);
  for (std::size_t k = 0; k < to_score.size(); ++k) scores[to_score[k]] = scored[k];
  // None predicted to register sees anything: whether any candidate does decides between
  // "no safe NBV" and "nothing left to see" (below), so the rest are scored too; and
  // when none sees anything, the best is taken unpredicted, as without predicting first.
  if (!skipped.empty() &&
      std::none_of(scored.begin(), scored.end(), [](double s) { return s > 0; })) {
    std::vector<Point3> skipped_positions;
    for (std::size_t i : skipped) skipped_positions.push_back(positions[i]);
    const std::vector<double> more =
        score_targets(tree, targets, skipped_positions, params, nullptr);
    for (std::size_t k = 0; k < skipped.size(); ++k) scores[skipped[k]] = more[k];
    if (std::none_of(more.begin(), more.end(), [](double s) { return s > 0; })) {
      overlap.assign(positions.size(), std::nullopt);
      res.low_overlap = 0;
    }
  }
  res.candidates = std::move(candidates);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    NbvCandidate& c = res.candidates[i];
    c.score = scores[i];
    c.value =
        params.travel_weight > 0 ? c.score * std::exp(-params.travel_weight * c.path_m) : c.score;
    c.predicted_overlap.reset();
    if (overlap[i]) c.predicted_overlap = overlap[i]->share;
  }
  res.seconds_scoring = seconds_since(t0);
  t0 = Clock::now();
  // Best value first (grid order on ties); with a prediction, the first whose scan is
  // predicted to overlap the map enough. A candidate that sees nothing (score 0) is not
  // tried: as the best it only says that the survey is done (Eq 5 is 0 there), and when
  // every candidate that sees something is passed over, there is no safe NBV.
  std::vector<std::size_t> order(res.candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return res.candidates[a].value > res.candidates[b].value;
  });
  for (std::size_t i : order) {
    NbvCandidate& c = res.candidates[i];
    if (overlap[i] && overlap[i]->share < params.min_overlap) continue;  // counted above
    if (res.low_overlap > 0 && c.score <= 0) break;
    if (params.overlap_top && c.score > 0) {
      if (!overlap[i]) {
        overlap[i] = predict_overlap(tree, c.position, params);
        c.predicted_overlap = overlap[i]->share;
        if (overlap[i]->share < params.min_overlap) {
          ++res.low_overlap;
          continue;
        }
      }
      res.best_overlap = *overlap[i];
    }
    res.best = c;
    break;
  }
  res.seconds_overlap = seconds_since(t0);
  t0 = Clock::now();
  if (res.best) {
    // Eq 5 counts method 1's targets, whatever the score's method, with doors blocking.
    // A method-1 score with doors blocking is Eq 5's sum already: the same targets, the
    // same lines and shares 1/(1 + n) (the blocker cache and the walls' shadows only
    // prove blocks that the traversal would find), in leaf volumes. Then only the
    // volume is counted; else the targets' lines are traversed again from the NBV.
    const bool from_score = params.method == 1 && !params.see_through_doors;
    const std::vector<Target> method1 =
        params.method == 1 ? std::vector<Target>() : method1_targets(tree, params.room);
    const std::vector<Target>& eq5_targets = params.method == 1 ? targets : method1;
    const double total = from_score ? counted_volume(tree, params.room) : 0;
    const double leaf_volume = std::pow(tree.leaf_size(), 3);
    const auto eq5_at = [&](const NbvCandidate& c) {
      if (!from_score)
        return stop_percentage_over(tree, eq5_targets, c.position, params.limits, params.threads,
                                    params.room);
      return total > 0 ? 100.0 * c.score * leaf_volume / total : 0.0;
    };
    res.stop_percent = eq5_at(*res.best);
    // Weighed by the path, the NBV may see less than the highest-scoring candidate: what
    // that one would still see keeps the survey going (a far view of much hidden space),
    // unless it was passed over for its overlap.
    const NbvCandidate& top = *std::max_element(
        res.candidates.begin(), res.candidates.end(),
        [](const NbvCandidate& a, const NbvCandidate& b) { return a.score < b.score; });
    const bool weighed = params.travel_weight > 0;
    const bool passed_over = top.predicted_overlap && *top.predicted_overlap < params.min_overlap;
    if (weighed && top.score > res.best->score && !passed_over)
      res.stop_percent = std::max(res.stop_percent, eq5_at(top));
  }
  res.seconds_stop = seconds_since(t0);
  return res;
}

}  // namespace semioctree
