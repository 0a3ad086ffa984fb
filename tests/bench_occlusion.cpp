// Benchmark: the classified map of one lab scan (~400 000 points after preprocessing) at
// 0.05 m, occupancy + occlusion study from the scan's position, four ways in one run:
//  * semioctree: discretize into the SemiOcTree (0.8 m coarse voxels) + study_occlusion;
//    beside it the same with exact octants (OcclusionParams::exact_octants), whose labels
//    match every voxel judged alone, to show what exactness costs;
//  * semioctree_k0: the same code with coarse voxel = leaf (a SemiOcTree with k = 0);
//  * dense_grid: one label byte per 0.05 m voxel in a flat array over the same region, every
//    free voxel's centre tested by 3D DDA through the array (support/dense_grid.h);
//  * octomap_insertPointCloud: OctoMap's ray carving of the same cloud from the same origin
//    at the same resolution (its way to tell free from unknown space).
// The first three answer the same question (which voxels the scanner sees) and run with 1
// thread and with all threads; OctoMap's insertPointCloud has no threads (the system's
// liboctomap is built without OpenMP) and runs on one. Each side's voxels by label, counted
// over the same region, show what it found. Prints JSON on stdout, progress on stderr.
//
//   bench_occlusion [--rounds R] [--semioctree-only]
#include <octomap/OcTree.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/occlusion.h"
#include "support/bench_common.h"
#include "support/dense_grid.h"
#include "support/lab_map.h"

using namespace semioctree;
using json = nlohmann::ordered_json;  // fields in the order written

namespace {

// Leaf voxels of the map by label (an octant of level l holds 8^(k - l) of them).
json voxels_by_label(const SemiOcTree& tree) {
  std::uint64_t count[kLabelCount] = {};
  tree.for_each_octant([&](const Octant& o) {
    count[unsigned(o.label())] += std::uint64_t(1) << (3 * (tree.leaf_level() - o.level));
  });
  return {{"visible", count[unsigned(Label::kEmpty)]},
          {"occluded", count[unsigned(Label::kOccluded)]},
          {"occupied", count[unsigned(Label::kOccupied)]}};
}

// Voxels of the dense grid whose centre `tree` labels as the grid does.
std::size_t same_labels(const testing::DenseGrid& grid, const SemiOcTree& tree) {
  std::size_t same = 0;
  for (std::int64_t k = 0; k < grid.size(2); ++k)
    for (std::int64_t j = 0; j < grid.size(1); ++j)
      for (std::int64_t i = 0; i < grid.size(0); ++i) {
        const auto o = tree.find_octant(grid.centre(i, j, k));
        same += o && o->label() == grid.label(i, j, k);
      }
  return same;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark: the classified map of one lab scan (~400 000 points) at 0.05 m (occupancy + "
      "occlusion study) on the SemiOcTree (0.8 m coarse), on the SemiOcTree with k = 0 and on "
      "a dense array (3D DDA), with 1 thread and with all threads, against OctoMap's "
      "insertPointCloud of the same cloud from the same origin (one thread), in one run. "
      "Prints JSON on stdout, progress on stderr."};
  int rounds = 2;
  bool semioctree_only = false;  // for profiling: skip the baselines
  bench::add_rounds_option(app, rounds);
  app.add_flag("--semioctree-only", semioctree_only,
               "time the semioctree alone and skip the three baselines (for profiling; their "
               "JSON fields and the ratios are then null); default: off");
  CLI11_PARSE(app, argc, argv);
  std::fprintf(stderr, "scanning the lab ...\n");
  const testing::PreprocessedLab lab = testing::preprocessed_lab(true);
  const PreprocessResult& pre = lab.pre;
  // The baselines know nothing of the scan's returns: all is compared from a view without
  // them, but exact octants cost most where the depths decide, so the exact/sampled ratio is
  // also timed with them, as in a survey.
  const ScannerView view{lab.origin};
  ScannerView view_with_returns = view;
  view_with_returns.returns = lab.returns;
  octomap::Pointcloud octo_cloud;
  for (const auto& p : *pre.cloud) octo_cloud.push_back(p.x, p.y, p.z);
  const octomap::point3d octo_origin(float(lab.origin.x), float(lab.origin.y), float(lab.origin.z));

  // The classified map of one side: occupancy, then the study on `threads` threads.
  struct Timed {
    double seconds = 0, occupancy_seconds = 0;
  };
  auto semioctree_map = [&](double coarse, unsigned threads, std::unique_ptr<SemiOcTree>& tree,
                            OcclusionReport& report, bool exact = false,
                            const ScannerView* seen_from = nullptr) {
    const auto t0 = std::chrono::steady_clock::now();
    tree = discretize(*pre.cloud, pre.ceiling_height, {0.05, coarse, 0.8});
    Timed t;
    t.occupancy_seconds = bench::seconds_since(t0);
    OcclusionParams op;
    op.threads = threads;
    op.exact_octants = exact;
    report = study_occlusion(*tree, {seen_from ? *seen_from : view}, op);
    t.seconds = bench::seconds_since(t0);
    return t;
  };

  std::unique_ptr<SemiOcTree> semi, semi_k0, exact;
  std::unique_ptr<testing::DenseGrid> dense;
  OcclusionReport semi_report, k0_report, exact_report;
  testing::DenseOcclusionReport dense_report;
  std::size_t octo_nodes = 0;
  json runs = json::array();
  bench::SideSeconds semi_s, k0_s, dense_s, octo_s;
  std::vector<double> octo_rounds;
  for (unsigned threads : bench::thread_counts()) {
    std::vector<double> semi_rounds, semi_occupancy, semi_study, exact_study, k0_rounds,
        dense_rounds, dense_build, returns_sampled_study, returns_exact_study;
    for (int r = 0; r < rounds; ++r) {
      std::fprintf(stderr, "%u thread(s), round %d: semioctree ...\n", threads, r + 1);
      const Timed semi_t = semioctree_map(0.8, threads, semi, semi_report);
      semi_rounds.push_back(semi_t.seconds);
      semi_occupancy.push_back(semi_t.occupancy_seconds);
      semi_study.push_back(semi_t.seconds - semi_t.occupancy_seconds);
      std::fprintf(stderr, "%u thread(s), round %d: semioctree, exact octants ...\n", threads,
                   r + 1);
      const Timed exact_t = semioctree_map(0.8, threads, exact, exact_report, true);
      exact_study.push_back(exact_t.seconds - exact_t.occupancy_seconds);
      std::fprintf(stderr,
                   "%u thread(s), round %d: sampled and exact octants with the returns ...\n",
                   threads, r + 1);
      std::unique_ptr<SemiOcTree> with_returns;
      OcclusionReport with_returns_report;
      const Timed sampled_r = semioctree_map(0.8, threads, with_returns, with_returns_report, false,
                                             &view_with_returns);
      returns_sampled_study.push_back(sampled_r.seconds - sampled_r.occupancy_seconds);
      const Timed exact_r =
          semioctree_map(0.8, threads, with_returns, with_returns_report, true, &view_with_returns);
      returns_exact_study.push_back(exact_r.seconds - exact_r.occupancy_seconds);
      if (semioctree_only) continue;
      std::fprintf(stderr, "%u thread(s), round %d: semioctree with k = 0 ...\n", threads, r + 1);
      semi_k0.reset();  // one map of this size at a time
      k0_rounds.push_back(semioctree_map(0.05, threads, semi_k0, k0_report).seconds);
      std::fprintf(stderr, "%u thread(s), round %d: dense grid ...\n", threads, r + 1);
      dense.reset();
      const auto t0 = std::chrono::steady_clock::now();
      dense = std::make_unique<testing::DenseGrid>(
          testing::DenseGrid::from_cloud(*pre.cloud, pre.ceiling_height, 0.05, 0.8));
      dense_build.push_back(bench::seconds_since(t0));
      dense_report = testing::study_occlusion_dense(*dense, view, threads);
      dense_rounds.push_back(bench::seconds_since(t0));
      if (threads != 1) continue;  // OctoMap's insertPointCloud runs on one thread
      std::fprintf(stderr, "round %d: OctoMap insertPointCloud ...\n", r + 1);
      const auto t1 = std::chrono::steady_clock::now();
      octomap::OcTree octo(0.05);
      octo.insertPointCloud(octo_cloud, octo_origin);
      octo_rounds.push_back(bench::seconds_since(t1));
      octo_nodes = octo.size();
    }
    json run;
    run["threads"] = threads;
    run["semioctree_seconds"] = bench::best_round(semi_rounds);
    run["semioctree_occupancy_seconds"] = bench::best_round(semi_occupancy);
    run["semioctree_study_seconds"] = bench::best_round(semi_study);
    run["semioctree_exact_study_seconds"] = bench::best_round(exact_study);
    run["exact_over_sampled_study"] =
        bench::best_round(exact_study) / bench::best_round(semi_study);
    run["with_returns"] = {
        {"sampled_study_seconds", bench::best_round(returns_sampled_study)},
        {"exact_study_seconds", bench::best_round(returns_exact_study)},
        {"exact_over_sampled_study",
         bench::best_round(returns_exact_study) / bench::best_round(returns_sampled_study)}};
    run["semioctree_k0_seconds"] =
        semioctree_only ? json(nullptr) : json(bench::best_round(k0_rounds));
    run["dense_grid_seconds"] =
        semioctree_only ? json(nullptr) : json(bench::best_round(dense_rounds));
    run["dense_grid_build_seconds"] =
        semioctree_only ? json(nullptr) : json(bench::best_round(dense_build));
    runs.push_back(run);
    (threads == 1 ? semi_s.one_thread : semi_s.all_threads) = bench::best_round(semi_rounds);
    (threads == 1 ? k0_s.one_thread : k0_s.all_threads) = bench::best_round(k0_rounds);
    (threads == 1 ? dense_s.one_thread : dense_s.all_threads) = bench::best_round(dense_rounds);
  }
  if (bench::all_threads() == 1) {
    semi_s.all_threads = semi_s.one_thread;
    k0_s.all_threads = k0_s.one_thread;
    dense_s.all_threads = dense_s.one_thread;
  }
  octo_s.one_thread = bench::best_round(octo_rounds);

  std::fprintf(stderr, "counting each side's voxels ...\n");
  json out;
  out["benchmark"] =
      "classified map of one lab scan at 0.05 m (occupancy + occlusion study from the scan's "
      "position)";
  out["scan_points"] = lab.scan_points;
  out["points"] = pre.cloud->size();
  out["rounds"] = rounds;
  out["threads"] = bench::all_threads();
  out["runs"] = runs;
  out["semioctree"] = {{"coarse", 0.8},
                       {"octants", semi->statistics().total()},
                       {"memory_bytes", semi->memory_bytes()},
                       {"segments", semi_report.segments},
                       {"voxels", voxels_by_label(*semi)}};
  out["semioctree_exact"] = {
      {"note",
       "exact octants: an octant keeps one label only where it is proven for all of it "
       "(docs/occlusion.md)"},
      {"octants", exact->statistics().total()},
      {"segments", exact_report.segments},
      {"octants_unproven", exact_report.octants_unproven},
      {"voxels", voxels_by_label(*exact)}};
  if (semioctree_only) {
    out["semioctree_k0"] = out["dense_grid"] = out["octomap_insertPointCloud"] = nullptr;
  } else {
    out["semioctree_k0"] = {{"coarse", 0.05},
                            {"octants", semi_k0->statistics().total()},
                            {"memory_bytes", semi_k0->memory_bytes()},
                            {"segments", k0_report.segments},
                            {"voxels", voxels_by_label(*semi_k0)}};
    const std::size_t semi_same = same_labels(*dense, *semi);
    const std::size_t k0_same = same_labels(*dense, *semi_k0);
    out["semioctree_exact"]["voxels_labelled_alike_by_dense_grid"] = same_labels(*dense, *exact);
    out["dense_grid"] = {
        {"size", {dense->size(0), dense->size(1), dense->size(2)}},
        {"memory_bytes", dense->memory_bytes()},
        {"segments", dense_report.segments},
        {"voxels",
         {{"visible", dense_report.visible},
          {"occluded", dense_report.occluded},
          {"occupied", dense_report.occupied}}},
        {"voxels_labelled_alike_by_semioctree", semi_same},
        {"voxels_labelled_alike_by_semioctree_k0", k0_same},
        {"note",
         "every free voxel's centre tested alone (DDA); the semioctree tests an unsplit octant "
         "by its centre and corners and splits it where they disagree, so a few voxels differ "
         "(with exact octants, none should)"}};
    // OctoMap's answer over the same region: what it holds at each voxel's centre.
    octomap::OcTree octo(0.05);
    octo.insertPointCloud(octo_cloud, octo_origin);
    std::size_t free_voxels = 0, occupied_voxels = 0, unknown_voxels = 0;
    for (std::int64_t k = 0; k < dense->size(2); ++k)
      for (std::int64_t j = 0; j < dense->size(1); ++j)
        for (std::int64_t i = 0; i < dense->size(0); ++i) {
          const Point3 c = dense->centre(i, j, k);
          const octomap::OcTreeNode* node = octo.search(c.x, c.y, c.z);
          if (!node)
            ++unknown_voxels;
          else if (octo.isNodeOccupied(node))
            ++occupied_voxels;
          else
            ++free_voxels;
        }
    out["octomap_insertPointCloud"] = {
        {"nodes", octo_nodes},
        {"voxels_in_the_same_region",
         {{"free", free_voxels}, {"occupied", occupied_voxels}, {"unknown", unknown_voxels}}},
        {"note",
         "free = carved by a ray to a return, unknown = no ray crossed it: the nearest OctoMap "
         "answer to visible / occluded; insertPointCloud runs on one thread (no OpenMP in the "
         "system's liboctomap)"}};
  }
  out["headlines"] = json::array(
      {bench::headline("occlusion_vs_dense_grid",
                       "dense array (3D DDA) seconds / semioctree seconds, occupancy + occlusion "
                       "study of the same cloud, same threads",
                       dense_s, semi_s),
       bench::headline("occlusion_vs_semioctree_k0",
                       "SemiOcTree with k = 0 seconds / semioctree seconds, same code, same "
                       "threads",
                       k0_s, semi_s),
       bench::headline("occlusion_vs_octomap_insertPointCloud",
                       "OctoMap insertPointCloud seconds / semioctree seconds, same cloud and "
                       "origin",
                       octo_s, semi_s,
                       "insertPointCloud cannot use more threads: ratio_1_thread (both on one "
                       "thread) is the headline; ratio_all_threads is null")});
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
