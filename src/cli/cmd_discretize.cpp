// `semioctree discretize --cloud FILE [--pose X,Y,Z,YAW] --leaf R --coarse L --out DIR`
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cloud_input.h"
#include "commands.h"
#include "semioctree/discretize.h"
#include "semioctree/figures.h"
#include "semioctree/outputs.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

void add_discretize_command(CLI::App& app) {
  struct Options {
    ScanSource source;
    DiscretizeParams disc;
    ScannerView limits;
    std::string out;
    double slice_height = -1;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "discretize",
      "Preprocess a scan (level, cut floor and ceiling, decimate) and discretize it into a "
      "SemiOcTree (occupancy analysis). Returns outside the scanner's limits (--min-range, "
      "--elevation-min: on a robot, the lowest elevation that clears its body) are dropped. "
      "Writes semioctree.ot, labels_color.ot, occupancy.bt, "
      "slice.png and stats.json.");
  add_scan_source_options(*cmd, o->source,
                          "scanner pose X,Y,Z[,YAW_DEG] of each --cloud in the survey frame "
                          "(default: the pose its file carries, a PTX header or a PCD "
                          "viewpoint, else the origin)");
  add_grid_options(*cmd, o->disc);
  add_scanner_limit_options(*cmd, o->limits);
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--slice-height", o->slice_height,
                  "height of the slice image in metres above the floor (default: scanner height)");
  cmd->callback([o] {
    SemiOcTree::leaf_level_for(o->disc.leaf, o->disc.coarse);  // fail before reading anything
    std::vector<std::string> written = map_files_written();
    check_outputs_spare_inputs(source_paths(o->source), {}, {{{"--out", o->out}, written}});
    const PreparedCloud cloud = prepare(o->source, "discretize", &o->limits);
    const auto t0 = Clock::now();
    DiscretizeReport rep;
    const auto tree = discretize(*cloud.pre.cloud, cloud.pre.ceiling_height, o->disc, &rep);
    tree->prune();
    tree->compact();
    const DiscretizationRun run = describe_run(*tree, seconds_since(t0));
    std::printf(
        "discretize: %zu coarse voxels, %llu octants (%zu occupied leaves) at %g → %g m [%.2f s]\n",
        tree->coarse_count(), static_cast<unsigned long long>(run.stats.total()),
        rep.occupied_leaves, o->disc.coarse, o->disc.leaf, run.seconds);
    SliceOptions slice;
    slice.height = o->slice_height >= 0 ? o->slice_height
                                        : (cloud.scanners.empty() ? 1.5 : cloud.scanners.front().z);
    slice.scans = cloud.scanners;
    slice.title = source_name(o->source);
    write_map_files(*tree, o->out, slice);
    write_run_json(run, (std::filesystem::path(o->out) / "stats.json").string());
    std::printf("wrote %s/{semioctree.ot, labels_color.ot, occupancy.bt, slice.png, stats.json}\n",
                o->out.c_str());
  });
}

}  // namespace semioctree::cli
