// `semioctree classify --cloud FILE... [--pose X,Y,Z,YAW ...] --out DIR`:
// preprocess, discretize and classify real scans whose scanner poses are known
// (one pose per file; the first scan at the origin by default).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cloud_input.h"
#include "commands.h"
#include "semioctree/discretize.h"
#include "semioctree/figures.h"
#include "semioctree/occlusion.h"
#include "semioctree/openings.h"
#include "semioctree/outputs.h"
#include "semioctree/timing.h"

namespace semioctree::cli {

void add_classify_command(CLI::App& app) {
  struct Options {
    ScanSource source;
    DiscretizeParams disc;
    ScannerView limits;
    std::string out;
    double slice_height = -1;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "classify",
      "Preprocess and discretize scans with known scanner poses, then classify every octant "
      "as empty, occupied, occluded, door, window or out by ray casting from the scanner positions "
      "(the "
      "occlusion study). Doors and windows are detected first (walls by RANSAC, holes confirmed by "
      "line of sight). Returns outside the scanner's limits (--min-range, --elevation-min: its "
      "mount, the robot) are dropped first. Writes the files of `discretize` with all classes, "
      "and openings.json.");
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
    SemiOcTree::leaf_level_for(o->disc.leaf, o->disc.coarse);
    std::vector<std::string> written = map_files_written();
    written.push_back("openings.json");
    check_outputs_spare_inputs(source_paths(o->source), {}, {{{"--out", o->out}, written}});
    const PreparedCloud cloud = prepare(o->source, "classify", &o->limits);
    auto t0 = Clock::now();
    const auto tree = discretize(*cloud.pre.cloud, cloud.pre.ceiling_height, o->disc);
    std::printf("discretize: %zu coarse voxels [%.2f s]\n", tree->coarse_count(),
                seconds_since(t0));
    t0 = Clock::now();
    OpeningsReport orep;
    const std::vector<ScannerView> views = scanner_views(cloud.scanners, o->limits, cloud.returns);
    const auto openings = detect_openings(*cloud.pre.cloud, cloud.pre.ceiling_height, *tree, views,
                                          OpeningParams{}, &orep);
    label_openings(*tree, openings);
    std::printf(
        "openings: %zu walls, %zu candidates, %zu confirmed, %zu rejected as occlusion shadows "
        "[%.2f s]\n",
        orep.walls.size(), orep.candidates, openings.size(), orep.rejected.size(),
        seconds_since(t0));
    for (const auto& op : openings)
      std::printf("  %-6s %.2f x %.2f m, sill %.2f m, line of sight %.0f %%\n", to_string(op.kind),
                  op.width, op.height, op.sill, 100 * op.los_fraction);
    t0 = Clock::now();
    const OcclusionReport rep = study_occlusion(*tree, views);
    tree->compact();
    const DiscretizationRun run = describe_run(*tree, seconds_since(t0));
    std::printf(
        "occlusion study: %zu octants tested, %zu split, %zu segments; empty %.1f %%, occupied "
        "%.1f %%, "
        "occluded %.1f %%, out %.1f %% of the volume [%.2f s]\n",
        rep.octants_tested, rep.octants_split, rep.segments,
        volume_percent(run.stats, Label::kEmpty), volume_percent(run.stats, Label::kOccupied),
        volume_percent(run.stats, Label::kOccluded), volume_percent(run.stats, Label::kOut),
        run.seconds);
    SliceOptions slice;
    slice.height = o->slice_height >= 0 ? o->slice_height
                                        : (cloud.scanners.empty() ? 1.5 : cloud.scanners.front().z);
    slice.scans = cloud.scanners;
    slice.title = "classified";
    write_map_files(*tree, o->out, slice);
    write_run_json(run, (std::filesystem::path(o->out) / "stats.json").string());
    write_openings_json(openings, (std::filesystem::path(o->out) / "openings.json").string());
    std::printf(
        "wrote %s/{semioctree.ot, labels_color.ot, occupancy.bt, slice.png, stats.json, "
        "openings.json}\n",
        o->out.c_str());
  });
}

}  // namespace semioctree::cli
