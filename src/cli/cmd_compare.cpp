// `semioctree compare (--scene FILE | --cloud FILE) --out DIR`: the paper's
// comparison of the semioctree against the homogeneous grid (Table 1, Table 2,
// Fig 15) at 0.4, 0.2, 0.1 and 0.05 m with 0.8 m coarse voxels.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cloud_input.h"
#include "commands.h"
#include "option_checks.h"
#include "semioctree/discretize.h"
#include "semioctree/figures.h"
#include "semioctree/occlusion.h"
#include "semioctree/openings.h"
#include "semioctree/outputs.h"
#include "semioctree/report.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

void add_compare_command(CLI::App& app) {
  struct Options {
    ScanSource source;
    ScannerView limits;
    std::vector<double> leaves = {0.4, 0.2, 0.1, 0.05};
    double coarse = 0.8;
    std::string out;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Discretize and classify the scans (one or more --cloud, placed by their poses, or --scene; "
      "doors, windows, occlusion study) with the semioctree "
      "and with the homogeneous grid at several resolutions; write the paper's Table 1, Table 2 "
      "and Fig 15 (comparison.json, "
      "comparison.md, fig15_octants.svg and .png) and a slice image per run, and report.html "
      "showing them in any browser.");
  add_scan_source_options(*cmd, o->source,
                          "scanner pose X,Y,Z[,YAW_DEG] of each --cloud (default: the pose its "
                          "file carries, else the origin)");
  cmd->add_option("--leaves", o->leaves, "leaf sizes to compare, metres")
      ->capture_default_str()
      ->delimiter(',')
      ->check(finite_positive());
  cmd->add_option("--coarse", o->coarse, "coarse voxel size of the semioctree, metres")
      ->check(finite_positive())
      ->capture_default_str();
  add_scanner_limit_options(*cmd, o->limits);
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->callback([o] {
    check_outputs_spare_inputs(source_paths(o->source), {},
                               {{{"--out", o->out},
                                 {"comparison.json", "comparison.md", "fig15_octants.svg",
                                  "fig15_octants.png", "slice_*.png", "report.html"}}});
    const PreparedCloud cloud = prepare(o->source, "compare", &o->limits);
    std::vector<DiscretizationRun> runs;
    for (const char* method : {"semioctree", "homogeneous"}) {
      for (double leaf : o->leaves) {
        DiscretizeParams p;
        p.leaf = leaf;
        p.coarse = std::string(method) == "homogeneous" ? leaf : o->coarse;
        p.extent_snap = o->coarse;  // both methods cover the same region
        std::printf("%-11s %5.2f → %4.2f m: discretize, openings, occlusion study ...\n", method,
                    p.coarse, leaf);
        std::fflush(stdout);
        const auto t0 = Clock::now();
        const auto tree = discretize(*cloud.pre.cloud, cloud.pre.ceiling_height, p);
        // Table 1 needs every class: doors and windows, then the occlusion study.
        const std::vector<ScannerView> views =
            scanner_views(cloud.scanners, o->limits, cloud.returns);
        label_openings(*tree,
                       detect_openings(*cloud.pre.cloud, cloud.pre.ceiling_height, *tree, views));
        study_occlusion(*tree, views);
        DiscretizationRun run = describe_run(*tree, seconds_since(t0));
        run.method = method;  // k = 0 at the coarsest leaf would read as homogeneous
        std::printf("%-11s %5.2f → %4.2f m: %9llu octants, %7.1f MB [%.2f s]\n", method, p.coarse,
                    leaf, static_cast<unsigned long long>(run.stats.total()),
                    run.memory_bytes / 1e6, run.seconds);
        std::fflush(stdout);
        SliceOptions slice;
        slice.height = cloud.scanners.empty() ? 1.5 : cloud.scanners.front().z;
        slice.scans = cloud.scanners;
        slice.title = std::string(method);
        char name[64];
        std::snprintf(name, sizeof(name), "slice_%s_%g.png", method, leaf);
        std::filesystem::create_directories(o->out);
        write_slice_png(*tree, (std::filesystem::path(o->out) / name).string(), slice);
        runs.push_back(run);
      }
    }
    write_comparison(runs, o->out);
    write_comparison_report(o->out);
    std::printf(
        "wrote %s/{comparison.json, comparison.md, fig15_octants.svg, fig15_octants.png, "
        "slice_*.png, report.html}\n",
        o->out.c_str());
  });
}

}  // namespace semioctree::cli
