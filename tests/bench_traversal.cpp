// Benchmark: the visibility question "does segment a→b cross an occupied
// octant before its end cell?" for 1 M random segments in a 10 × 8 × 3 m room
// (r = 0.05, L = 0.8, occupied leaves on walls, floor, ceiling and three
// boxes), answered by SemiOcTree::traverse and by OctoMap's computeRayKeys +
// search on an OcTree holding the same map, in one run. Prints JSON.
//
//   bench_traversal [--segments N] [--seed S] [--rounds R] [--map walls|furnished] [--skip-octomap]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/semioctree.h"
#include "support/bench_common.h"

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

// "walls": the map, occupied leaves on the four walls (floor and
// ceiling points are removed by preprocessing). "furnished": also floor,
// ceiling and three pieces of furniture (more split voxels, a harder case).
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
  return room;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: the visibility question \"does segment a->b cross an occupied octant before "
      "its end cell?\" for random segments in a 10 x 8 x 3 m room (r = 0.05 m, L = 0.8 m), "
      "answered by SemiOcTree::traverse and by OctoMap's computeRayKeys + search on an OcTree "
      "holding the same map, in one run. Prints JSON on stdout, progress on stderr."};
  std::size_t n = 1000000;
  unsigned seed = 1;
  int rounds = 3;
  std::string map = "walls";
  bool skip_octomap = false;  // for profiling our traversal alone
  app.add_option("--segments", n, "number of random segments")
      ->check(CLI::Range(1LL, std::numeric_limits<long long>::max(), "POSITIVE"))
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the random segment end points")->capture_default_str();
  semioctree::bench::add_rounds_option(app, rounds);
  app.add_option("--map", map,
                 "room map: walls (occupied leaves on the four walls) or furnished (also floor, "
                 "ceiling and three pieces of furniture: more split voxels)")
      ->check(CLI::IsMember({"walls", "furnished"}))
      ->capture_default_str();
  app.add_flag("--skip-octomap", skip_octomap,
               "time the SemiOcTree traversal alone and skip the OctoMap baseline (for "
               "profiling; the OctoMap fields and the speedups of the JSON are then null); "
               "default: off");
  CLI11_PARSE(app, argc, argv);
  const bool furnished = map == "furnished";
  std::fprintf(stderr, "building the room map ...\n");
  const auto room = build_room(0.05, 0.8, furnished);
  SemiOcTree& semi = *room;
  semi.prune();
  semi.compact();
  const auto octo = semioctree::to_occupancy_octree(semi);

  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(0.06f, 9.94f), uy(0.06f, 7.94f), uz(0.06f, 2.94f);
  std::vector<octomap::point3d> a(n), b(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = {ux(rng), uy(rng), uz(rng)};
    b[i] = {ux(rng), uy(rng), uz(rng)};
  }

  // The two methods take turns over the whole set of segments, three rounds
  // each, so that load from other processes on this shared machine hits both
  // alike; each method's best round is reported (whole passes keep each
  // method's own data in cache, as in a real batch of rays).
  std::vector<char> semi_blocked(n), octo_blocked(n);
  std::size_t semi_steps = 0, octo_steps = 0;
  std::vector<double> semi_rounds, octo_rounds;
  octomap::KeyRay ray;
  for (int round = 0; round < rounds; ++round) {
    std::fprintf(stderr, "round %d: SemiOcTree traversal of %zu segments ...\n", round + 1, n);
    semi_steps = 0;
    auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < n; ++i) {
      // Stop at the first occupied octant that is not the end cell.
      const octomap::OcTreeKey end = semi.coordToKey(b[i]);
      bool blocked = false;
      semi.traverse(Point3(a[i]), Point3(b[i]), [&](const semioctree::RayStep& s) {
        ++semi_steps;
        if (s.label() == Label::kOccupied && !(s.key == end)) {
          blocked = true;
          return false;
        }
        return true;
      });
      semi_blocked[i] = blocked;
    }
    semi_rounds.push_back(semioctree::bench::seconds_since(t0));
    if (skip_octomap) continue;
    std::fprintf(stderr, "round %d: OctoMap computeRayKeys + search ...\n", round + 1);
    octo_steps = 0;
    t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < n; ++i) {
      // computeRayKeys excludes the end cell; search each key.
      bool blocked = false;
      if (octo->computeRayKeys(a[i], b[i], ray)) {
        for (const octomap::OcTreeKey& k : ray) {
          ++octo_steps;
          const octomap::OcTreeNode* node = octo->search(k);
          if (node && octo->isNodeOccupied(node)) {
            blocked = true;
            break;
          }
        }
      }
      octo_blocked[i] = blocked;
    }
    octo_rounds.push_back(semioctree::bench::seconds_since(t0));
  }
  const double semi_s = *std::min_element(semi_rounds.begin(), semi_rounds.end());
  const double octo_s =
      octo_rounds.empty() ? 0.0 : *std::min_element(octo_rounds.begin(), octo_rounds.end());
  double worst_ratio = 1e300;
  for (std::size_t r = 0; r < octo_rounds.size(); ++r)
    worst_ratio = std::min(worst_ratio, octo_rounds[r] / semi_rounds[r]);

  std::size_t agree = 0, blocked_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    agree += semi_blocked[i] == octo_blocked[i];
    blocked_count += semi_blocked[i];
  }
  const auto stats = semi.statistics();
  // Without the baseline its fields and the ratios are null (valid JSON).
  char octo_json[512] = "null", speedup[32] = "null", worst[32] = "null";
  if (!skip_octomap) {
    std::snprintf(octo_json, sizeof octo_json,
                  "{\"best_round_seconds\": %.4f, \"keys_visited\": %zu, \"keys_per_second\": "
                  "%.4g, \"segments_per_second\": %.4g, \"nodes_in_map\": %zu}",
                  octo_s, octo_steps, octo_steps / octo_s, n / octo_s, octo->size());
    std::snprintf(speedup, sizeof speedup, "%.2f", octo_s / semi_s);
    std::snprintf(worst, sizeof worst, "%.2f", worst_ratio);
  }
  std::printf(
      "{\n"
      "  \"benchmark\": \"segment visibility, 10 x 8 x 3 m room, r = 0.05 m, L = 0.8 m\",\n"
      "  \"map\": \"%s\",\n"
      "  \"segments\": %zu,\n"
      "  \"blocked_segments\": %zu,\n"
      "  \"answers_agree\": %s,\n"
      "  \"semioctree\": {\"best_round_seconds\": %.4f, \"octants_visited\": %zu, "
      "\"octants_per_second\": %.4g,"
      " \"segments_per_second\": %.4g, \"octants_in_map\": %llu},\n"
      "  \"octomap_computeRayKeys_search\": %s,\n"
      "  \"rounds\": %d,\n  \"speedup_same_question\": %s,\n"
      "  \"speedup_worst_round\": %s\n"
      "}\n",
      furnished ? "furnished" : "walls", n, blocked_count,
      skip_octomap ? "null" : std::to_string(agree).c_str(), semi_s, semi_steps,
      semi_steps / semi_s, n / semi_s, static_cast<unsigned long long>(stats.total()), octo_json,
      rounds, speedup, worst);
  return 0;
}
