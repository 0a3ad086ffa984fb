// Benchmark: building the classified map of one lab scan (~400 000 points) at
// 0.05 m — occupancy + occlusion study on the SemiOcTree (0.8 m coarse) and on
// the homogeneous grid — against OctoMap's insertPointCloud of the same cloud
// from the same origin at the same resolution (ray carving: OctoMap's way to
// tell free from unknown space), in one run. Prints JSON.
//
//   bench_occlusion [--rounds R] [--semioctree-only]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/occlusion.h"
#include "semioctree/preprocess.h"
#include "support/bench_common.h"
#include "support/lab_scan.h"

using namespace semioctree;

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: the classified map of one lab scan (~400 000 points) at 0.05 m (occupancy + "
      "occlusion study) on the SemiOcTree (0.8 m coarse) and on the homogeneous grid, against "
      "OctoMap's insertPointCloud of the same cloud from the same origin, in one run. Prints "
      "JSON on stdout, progress on stderr."};
  int rounds = 2;
  bool semioctree_only = false;  // for profiling: skip the two baselines
  bench::add_rounds_option(app, rounds);
  app.add_flag("--semioctree-only", semioctree_only,
               "time the semioctree alone and skip the homogeneous grid and OctoMap baselines "
               "(for profiling; their JSON fields and the speedups are then 0); default: off");
  CLI11_PARSE(app, argc, argv);
  const testing::LabScan lab = testing::scan_lab();
  const Cloud& raw = lab.world;
  PreprocessParams pp;
  pp.target_points = 400000;
  const PreprocessResult pre = preprocess(raw, pp);
  const Eigen::Vector3d origin = pre.transform * lab.origin;
  const ScannerView view{Point3(origin.x(), origin.y(), origin.z())};
  octomap::Pointcloud octo_cloud;
  for (const auto& p : *pre.cloud) octo_cloud.push_back(p.x, p.y, p.z);

  std::vector<double> semi_s, semi_occupancy_s, homo_s, octo_s;
  std::size_t semi_segments = 0, homo_segments = 0, octo_nodes = 0;
  std::uint64_t semi_octants = 0, homo_octants = 0;
  for (int r = 0; r < rounds; ++r) {
    std::fprintf(stderr, "round %d: semioctree ...\n", r + 1);
    auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    {
      auto t = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.8, 0.8});
      const std::clock_t c1 = std::clock();
      semi_occupancy_s.push_back(bench::seconds_since(t0));
      semi_segments = study_occlusion(*t, {view}).segments;
      semi_s.push_back(bench::seconds_since(t0));
      std::fprintf(stderr, "  cpu: occupancy %.3f s, occlusion %.3f s\n",
                   double(c1 - c0) / CLOCKS_PER_SEC, double(std::clock() - c1) / CLOCKS_PER_SEC);
      semi_octants = t->statistics().total();
    }
    if (semioctree_only) continue;
    std::fprintf(stderr, "round %d: homogeneous grid ...\n", r + 1);
    t0 = std::chrono::steady_clock::now();
    {
      auto t = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.05, 0.8});
      homo_segments = study_occlusion(*t, {view}).segments;
      homo_s.push_back(bench::seconds_since(t0));
      homo_octants = t->statistics().total();
    }
    std::fprintf(stderr, "round %d: OctoMap insertPointCloud ...\n", r + 1);
    t0 = std::chrono::steady_clock::now();
    {
      octomap::OcTree t(0.05);
      t.insertPointCloud(octo_cloud,
                         octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z())));
      octo_s.push_back(bench::seconds_since(t0));
      octo_nodes = t.size();
    }
  }
  auto best = [](const std::vector<double>& v) {
    return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
  };
  const double a = best(semi_s), b = best(homo_s), c = best(octo_s);
  std::printf(
      "{\n  \"benchmark\": \"classified map of one lab scan at 0.05 m (occupancy + occlusion "
      "study)\",\n"
      "  \"points\": %zu, \"rounds\": %d,\n"
      "  \"semioctree\": {\"seconds\": %.4f, \"occupancy_seconds\": %.4f, \"octants\": %llu, "
      "\"segments\": %zu},\n"
      "  \"homogeneous\": {\"seconds\": %.4f, \"octants\": %llu, \"segments\": %zu},\n"
      "  \"octomap_insertPointCloud\": {\"seconds\": %.4f, \"nodes\": %zu},\n"
      "  \"speedup_vs_octomap\": %.2f,\n  \"speedup_vs_homogeneous\": %.2f\n}\n",
      pre.cloud->size(), rounds, a, best(semi_occupancy_s),
      static_cast<unsigned long long>(semi_octants), semi_segments, b,
      static_cast<unsigned long long>(homo_octants), homo_segments, c, octo_nodes, c / a, b / a);
  return 0;
}
