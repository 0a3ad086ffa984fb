// Benchmark: preprocessing + discretization of one lab scan (decimated to
// ~400 000 points, as in the paper) at 0.8 → 0.05 m, the semioctree against
// the homogeneous grid over the same region, in one run. Prints JSON.
//
//   bench_discretize [--rounds R]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/preprocess.h"
#include "support/bench_common.h"
#include "support/lab_scan.h"

using namespace semioctree;

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: preprocessing + discretization of one lab scan (decimated to ~400 000 points) "
      "at 0.8 -> 0.05 m, the semioctree against the homogeneous grid over the same region, in "
      "one run. Prints JSON on stdout, progress on stderr."};
  int rounds = 3;
  bench::add_rounds_option(app, rounds);
  CLI11_PARSE(app, argc, argv);
  std::fprintf(stderr, "scanning the lab ...\n");
  const testing::LabScan lab = testing::scan_lab();
  const Cloud& cloud = lab.world;

  PreprocessParams pp;
  pp.target_points = 400000;
  std::vector<double> pre_s, semi_s, homo_s;
  std::size_t kept = 0;
  std::uint64_t semi_octants = 0, homo_octants = 0;
  std::size_t semi_mem = 0, homo_mem = 0;
  for (int r = 0; r < rounds; ++r) {
    std::fprintf(stderr, "round %d ...\n", r + 1);
    auto t0 = std::chrono::steady_clock::now();
    const PreprocessResult pre = preprocess(cloud, pp);
    pre_s.push_back(bench::seconds_since(t0));
    kept = pre.output_points;
    t0 = std::chrono::steady_clock::now();
    {
      const auto semi = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.8, 0.8});
      semi_s.push_back(bench::seconds_since(t0));
      semi_octants = semi->statistics().total();
      semi_mem = semi->memory_bytes();
    }
    t0 = std::chrono::steady_clock::now();
    {
      const auto homo = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.05, 0.8});
      homo_s.push_back(bench::seconds_since(t0));
      homo_octants = homo->statistics().total();
      homo_mem = homo->memory_bytes();
    }
  }
  const double pre_best = *std::min_element(pre_s.begin(), pre_s.end());
  const double semi_best = *std::min_element(semi_s.begin(), semi_s.end());
  const double homo_best = *std::min_element(homo_s.begin(), homo_s.end());
  std::printf(
      "{\n  \"benchmark\": \"preprocess + discretize one lab scan, 0.8 -> 0.05 m\",\n"
      "  \"scan_points\": %zu, \"points_after_preprocess\": %zu, \"rounds\": %d,\n"
      "  \"preprocess_seconds\": %.4f,\n"
      "  \"semioctree\": {\"discretize_seconds\": %.4f, \"octants\": %llu, \"memory_bytes\": "
      "%zu},\n"
      "  \"homogeneous\": {\"discretize_seconds\": %.4f, \"octants\": %llu, \"memory_bytes\": "
      "%zu},\n"
      "  \"octant_ratio\": %.2f,\n"
      "  \"discretize_speedup\": %.2f,\n"
      "  \"preprocess_plus_discretize_speedup\": %.2f\n}\n",
      lab.world.size(), kept, rounds, pre_best, semi_best,
      static_cast<unsigned long long>(semi_octants), semi_mem, homo_best,
      static_cast<unsigned long long>(homo_octants), homo_mem,
      double(homo_octants) / double(semi_octants), homo_best / semi_best,
      (pre_best + homo_best) / (pre_best + semi_best));
  return 0;
}
