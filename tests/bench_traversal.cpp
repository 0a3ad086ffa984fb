// Benchmark: the visibility question "does segment a→b cross an occupied octant before its
// end cell?", answered by SemiOcTree::traverse and by OctoMap's computeRayKeys + search on
// an OcTree holding the same map (to_occupancy_octree), on the same segments and the same
// number of threads (1, then all), in one run. Prints JSON on stdout, progress on stderr.
//
// Maps (--map):
//  * lab (default): the classified lab after its first scan (0.05 m leaves, 0.8 m coarse
//    voxels; support/lab_map.h) and the NBV's own segments: from its feasible candidates
//    (find_candidates, at the scanner's height) to the centres of the occluded octants it
//    scores, pairs drawn at random (every pair when --segments allows), blocked ones
//    included;
//  * walls, furnished: a hand-built 10 × 8 × 3 m room (occupied leaves on the walls; also
//    floor, ceiling and three boxes) and random segments inside it.
//
//   bench_traversal [--map lab|walls|furnished] [--segments N] [--seed S] [--rounds R]
//                   [--skip-octomap]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "semioctree/nbv.h"
#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/semioctree.h"
#include "src/parallel_for.h"
#include "support/bench_common.h"
#include "support/lab_map.h"

using json = nlohmann::ordered_json;  // fields in the order written
using semioctree::Label;
using semioctree::Point3;
using semioctree::SemiOcTree;

namespace {

void occupy_box_surface(SemiOcTree& tree, double x0, double y0, double z0, double x1, double y1,
                        double z1) {
  const double r = tree.leaf_size();
  const unsigned leaf = tree.leaf_level();
  for (double x = x0; x < x1; x += r)
    for (double y = y0; y < y1; y += r)
      for (double z = z0; z < z1; z += r) {
        const bool surface =
            x < x0 + r || x + r >= x1 || y < y0 + r || y + r >= y1 || z < z0 + r || z + r >= z1;
        if (!surface) continue;
        octomap::OcTreeKey key;
        if (tree.key_of({x + 0.5 * r, y + 0.5 * r, z + 0.5 * r}, key))
          tree.set_label(key, leaf, Label::kOccupied);
      }
}

// "walls": occupied leaves on the four walls (floor and ceiling points are removed by
// preprocessing). "furnished": also floor, ceiling and three pieces of furniture (more
// split voxels, a harder case).
std::unique_ptr<SemiOcTree> build_room(double leaf, double coarse, bool furnished) {
  auto room = std::make_unique<SemiOcTree>(leaf, coarse);
  SemiOcTree& tree = *room;
  const double L = tree.coarse_size();
  // Coarse voxels over the room and one voxel around it, all empty.
  for (int i = -1; i * L < 10.0 + L; ++i)
    for (int j = -1; j * L < 8.0 + L; ++j)
      for (int l = -1; l * L < 3.0 + L; ++l) tree.create_coarse({i, j, l}, Label::kEmpty);
  // Walls one leaf thick, just outside the room.
  occupy_box_surface(tree, -0.05, -0.05, 0.0, 0.0, 8.05, 3.0);
  occupy_box_surface(tree, 10.0, -0.05, 0.0, 10.05, 8.05, 3.0);
  occupy_box_surface(tree, -0.05, -0.05, 0.0, 10.05, 0.0, 3.0);
  occupy_box_surface(tree, -0.05, 8.0, 0.0, 10.05, 8.05, 3.0);
  if (furnished) {
    occupy_box_surface(tree, -0.05, -0.05, -0.05, 10.05, 8.05, 3.05);
    occupy_box_surface(tree, 2.0, 2.0, 0.0, 4.0, 3.0, 0.9);
    occupy_box_surface(tree, 6.0, 1.0, 0.0, 7.0, 5.0, 2.0);
    occupy_box_surface(tree, 4.5, 6.0, 0.0, 5.0, 6.5, 3.0);
  }
  room->prune();
  room->compact();
  return room;
}

struct Segments {
  std::vector<octomap::point3d> from, to;
};

// `n` random segments with both ends inside the 10 × 8 × 3 m room.
Segments random_room_segments(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(0.06f, 9.94f), uy(0.06f, 7.94f), uz(0.06f, 2.94f);
  Segments s;
  s.from.resize(n);
  s.to.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.from[i] = {ux(rng), uy(rng), uz(rng)};
    s.to[i] = {ux(rng), uy(rng), uz(rng)};
  }
  return s;
}

// The NBV's segments on the lab map: candidate → occluded target, every pair if there are
// at most `n`, else `n` pairs drawn at random.
Segments nbv_segments(const std::vector<Point3>& candidates, const std::vector<Point3>& targets,
                      std::size_t n, unsigned seed) {
  Segments s;
  auto add = [&](const Point3& a, const Point3& b) {
    s.from.emplace_back(float(a.x), float(a.y), float(a.z));
    s.to.emplace_back(float(b.x), float(b.y), float(b.z));
  };
  const std::size_t pairs = candidates.size() * targets.size();
  if (pairs <= n) {
    for (const Point3& a : candidates)
      for (const Point3& b : targets) add(a, b);
    return s;
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick_candidate(0, candidates.size() - 1),
      pick_target(0, targets.size() - 1);
  for (std::size_t i = 0; i < n; ++i)
    add(candidates[pick_candidate(rng)], targets[pick_target(rng)]);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: the visibility question \"does segment a->b cross an occupied octant before "
      "its end cell?\" answered by SemiOcTree::traverse and by OctoMap's computeRayKeys + "
      "search on an OcTree holding the same map, on the same segments with 1 thread and with "
      "all threads, in one run. Prints JSON on stdout, progress on stderr."};
  std::size_t n = 1000000;
  unsigned seed = 1;
  int rounds = 3;
  std::string map = "lab";
  bool skip_octomap = false;  // for profiling our traversal alone
  app.add_option("--segments", n,
                 "number of segments (lab: at most this many candidate-target pairs, drawn at "
                 "random when there are more)")
      ->check(CLI::Range(1LL, std::numeric_limits<long long>::max(), "POSITIVE"))
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the random segments")->capture_default_str();
  semioctree::bench::add_rounds_option(app, rounds);
  app.add_option("--map", map,
                 "lab: the classified lab map after its first scan, segments from the NBV's "
                 "feasible candidates to the occluded octants' centres; walls: a 10 x 8 x 3 m "
                 "room with occupied leaves on its four walls and random segments inside it (no "
                 "segment is blocked); furnished: that room with floor, ceiling and three pieces "
                 "of furniture")
      ->check(CLI::IsMember({"lab", "walls", "furnished"}))
      ->capture_default_str();
  app.add_flag("--skip-octomap", skip_octomap,
               "time the SemiOcTree traversal alone and skip the OctoMap baseline (for "
               "profiling; the OctoMap fields and the ratios of the JSON are then null); "
               "default: off");
  CLI11_PARSE(app, argc, argv);

  json out;
  std::unique_ptr<SemiOcTree> room;
  Segments seg;
  if (map == "lab") {
    std::fprintf(stderr, "scanning and mapping the lab ...\n");
    const semioctree::testing::PreprocessedLab lab = semioctree::testing::preprocessed_lab();
    room = semioctree::testing::classified_lab_map(lab, 0.8);
    semioctree::RobotGeometry robot;
    robot.scanner_height = lab.origin.z;
    const std::vector<Point3> candidates =
        semioctree::find_candidates(*room, robot, lab.origin, {lab.origin}, {});
    std::vector<Point3> targets;
    room->for_each_octant([&](const semioctree::Octant& o) {
      if (o.label() == Label::kOccluded) targets.push_back(o.center);
    });
    seg = nbv_segments(candidates, targets, n, seed);
    out["benchmark"] =
        "segment visibility on the classified lab map (r = 0.05 m, L = 0.8 m): the NBV's "
        "segments, feasible candidate to occluded octant centre";
    out["candidates"] = candidates.size();
    out["occluded_targets"] = targets.size();
    out["candidate_target_pairs"] = candidates.size() * targets.size();
  } else {
    std::fprintf(stderr, "building the room map ...\n");
    room = build_room(0.05, 0.8, map == "furnished");
    seg = random_room_segments(n, seed);
    out["benchmark"] =
        "segment visibility, 10 x 8 x 3 m room (r = 0.05 m, L = 0.8 m), random segments";
  }
  const SemiOcTree& semi = *room;
  const auto octo = semioctree::to_occupancy_octree(semi);
  const std::size_t count = seg.from.size();

  // Each method takes a turn over the whole set of segments per round and thread count, so
  // that load from other processes on this shared machine hits both alike; each method's
  // best round is reported (whole passes keep each method's own data in cache, as in a
  // real batch of rays). Chunks of segments are handed to the workers in order.
  constexpr std::size_t kChunk = 4096;
  std::vector<char> semi_blocked(count), octo_blocked(count);
  std::vector<std::size_t> semi_steps_of(count), octo_steps_of(count);
  auto semi_pass = [&](unsigned threads) {
    semioctree::detail::parallel_for(count, threads, kChunk, [&](std::size_t i, unsigned) {
      // Stop at the first occupied octant that is not the end cell.
      const octomap::OcTreeKey end = semi.coordToKey(seg.to[i]);
      bool blocked = false;
      std::size_t steps = 0;
      semi.traverse(Point3(seg.from[i]), Point3(seg.to[i]), [&](const semioctree::RayStep& s) {
        ++steps;
        if (s.label() == Label::kOccupied && !(s.key == end)) {
          blocked = true;
          return false;
        }
        return true;
      });
      semi_blocked[i] = blocked;
      semi_steps_of[i] = steps;
    });
  };
  std::vector<octomap::KeyRay> rays(semioctree::bench::all_threads());
  auto octo_pass = [&](unsigned threads) {
    semioctree::detail::parallel_for(count, threads, kChunk, [&](std::size_t i, unsigned worker) {
      // computeRayKeys excludes the end cell; search each key.
      octomap::KeyRay& ray = rays[worker];
      bool blocked = false;
      std::size_t steps = 0;
      if (octo->computeRayKeys(seg.from[i], seg.to[i], ray)) {
        for (const octomap::OcTreeKey& k : ray) {
          ++steps;
          const octomap::OcTreeNode* node = octo->search(k);
          if (node && octo->isNodeOccupied(node)) {
            blocked = true;
            break;
          }
        }
      }
      octo_blocked[i] = blocked;
      octo_steps_of[i] = steps;
    });
  };

  json runs = json::array();
  semioctree::bench::SideSeconds semi_s, octo_s;
  for (unsigned threads : semioctree::bench::thread_counts()) {
    std::vector<double> semi_rounds, octo_rounds;
    for (int round = 0; round < rounds; ++round) {
      std::fprintf(stderr, "%u thread(s), round %d: SemiOcTree traversal of %zu segments ...\n",
                   threads, round + 1, count);
      auto t0 = std::chrono::steady_clock::now();
      semi_pass(threads);
      semi_rounds.push_back(semioctree::bench::seconds_since(t0));
      if (skip_octomap) continue;
      std::fprintf(stderr, "%u thread(s), round %d: OctoMap computeRayKeys + search ...\n", threads,
                   round + 1);
      t0 = std::chrono::steady_clock::now();
      octo_pass(threads);
      octo_rounds.push_back(semioctree::bench::seconds_since(t0));
    }
    const double semi_best = semioctree::bench::best_round(semi_rounds);
    const double octo_best = semioctree::bench::best_round(octo_rounds);
    double worst_ratio = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < octo_rounds.size(); ++r)
      worst_ratio = std::min(worst_ratio, octo_rounds[r] / semi_rounds[r]);
    std::size_t semi_steps = 0, octo_steps = 0;
    for (std::size_t i = 0; i < count; ++i) {
      semi_steps += semi_steps_of[i];
      octo_steps += octo_steps_of[i];
    }
    json run;
    run["threads"] = threads;
    run["semioctree"] = {{"best_round_seconds", semi_best},
                         {"octants_visited", semi_steps},
                         {"segments_per_second", double(count) / semi_best}};
    if (skip_octomap) {
      run["octomap_computeRayKeys_search"] = nullptr;
    } else {
      run["octomap_computeRayKeys_search"] = {{"best_round_seconds", octo_best},
                                              {"keys_visited", octo_steps},
                                              {"segments_per_second", double(count) / octo_best}};
      run["ratio_worst_round"] = worst_ratio;
    }
    runs.push_back(run);
    (threads == 1 ? semi_s.one_thread : semi_s.all_threads) = semi_best;
    (threads == 1 ? octo_s.one_thread : octo_s.all_threads) = octo_best;
  }
  if (semioctree::bench::all_threads() == 1) {
    semi_s.all_threads = semi_s.one_thread;
    octo_s.all_threads = octo_s.one_thread;
  }

  std::size_t agree = 0, blocked_count = 0;
  for (std::size_t i = 0; i < count; ++i) {
    agree += semi_blocked[i] == octo_blocked[i];
    blocked_count += semi_blocked[i];
  }
  out["map"] = map;
  out["segments"] = count;
  out["blocked_segments"] = blocked_count;
  out["answers_agree"] = skip_octomap ? json(nullptr) : json(agree);
  out["octants_in_map"] = semi.statistics().total();
  out["octomap_nodes_in_map"] = octo->size();
  out["rounds"] = rounds;
  out["runs"] = runs;
  out["headlines"] = json::array(
      {semioctree::bench::headline("traversal_vs_octomap_computeRayKeys_search",
                                   "OctoMap computeRayKeys + search seconds / SemiOcTree "
                                   "traverse seconds, same segments, same threads",
                                   octo_s, semi_s)});
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
