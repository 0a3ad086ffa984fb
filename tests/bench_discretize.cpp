// Benchmark: preprocessing + discretization of one lab scan (decimated to
// ~400 000 points, as in the paper) at 0.8 → 0.05 m, the semioctree against
// the homogeneous grid (a SemiOcTree with k = 0) over the same region, in one run. Both
// run on one thread (discretize has no threads), so the JSON's all-threads ratios are null.
// Prints JSON.
//
//   bench_discretize [--rounds R]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
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
  const double pre_best = bench::best_round(pre_s);
  const double semi_best = bench::best_round(semi_s);
  const double homo_best = bench::best_round(homo_s);
  nlohmann::ordered_json out;
  out["benchmark"] = "preprocess + discretize one lab scan, 0.8 -> 0.05 m";
  out["scan_points"] = lab.world.size();
  out["points_after_preprocess"] = kept;
  out["rounds"] = rounds;
  out["preprocess_seconds"] = pre_best;
  out["semioctree"] = {
      {"discretize_seconds", semi_best}, {"octants", semi_octants}, {"memory_bytes", semi_mem}};
  out["homogeneous"] = {
      {"discretize_seconds", homo_best}, {"octants", homo_octants}, {"memory_bytes", homo_mem}};
  out["octant_ratio"] = double(homo_octants) / double(semi_octants);
  const std::string one_thread =
      "discretize has no threads: both sides run on one thread, ratio_1_thread is the headline";
  out["headlines"] = nlohmann::ordered_json::array(
      {bench::headline("discretize_vs_semioctree_k0",
                       "SemiOcTree k = 0 discretize seconds / semioctree discretize seconds, "
                       "same cloud and region",
                       {homo_best, -1}, {semi_best, -1}, one_thread),
       bench::headline("preprocess_plus_discretize_vs_semioctree_k0",
                       "preprocess + discretize seconds, k = 0 / semioctree (the preprocessing "
                       "is the same on both sides)",
                       {pre_best + homo_best, -1}, {pre_best + semi_best, -1}, one_thread)});
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
