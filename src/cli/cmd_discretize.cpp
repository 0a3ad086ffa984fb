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
#ifdef SEMIOCTREE_HAVE_SIM
#include "sim_input.h"
#endif

namespace semioctree::cli {

void add_discretize_command(CLI::App& app) {
  struct Options {
    CloudInput input;
    std::string scene;
    std::uint64_t seed = 1;
    PreprocessParams pre;
    DiscretizeParams disc;
    std::string out;
    double slice_height = -1;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "discretize",
      "Preprocess a scan (level, cut floor and ceiling, decimate) and discretize it into a "
      "SemiOcTree (occupancy analysis). Writes semioctree.ot, labels_color.ot, occupancy.bt, "
      "slice.png and stats.json.");
  auto* cloud_opt =
      cmd->add_option("--cloud", o->input.files,
                      "point cloud: .pcd, .ply, .xyz/.txt or .ptx (repeat for several)")
          ->check(CLI::ExistingFile);
#ifdef SEMIOCTREE_HAVE_SIM
  cmd->add_option("--scene", o->scene,
                  "scene file: scan it from the robot's start with the synthetic scanner")
      ->check(CLI::ExistingFile)
      ->excludes(cloud_opt);
  cmd->add_option("--seed", o->seed, "scanner noise seed (with --scene)")->capture_default_str();
#else
  (void)cloud_opt;
#endif
  cmd->add_option("--pose", o->input.poses,
                  "scanner pose X,Y,Z[,YAW_DEG] in the survey frame, one per --cloud (default: the "
                  "origin, or the pose stored in a PTX file)");
  cmd->add_option("--pose-file", o->input.pose_file,
                  "JSON pose {\"x\",\"y\",\"z\",\"yaw_deg\"} for a single --cloud")
      ->check(CLI::ExistingFile);
  cmd->add_option("--leaf", o->disc.leaf, "leaf (finest octant) size r in metres")
      ->capture_default_str();
  cmd->add_option("--coarse", o->disc.coarse,
                  "coarse voxel size L in metres; must be r*2^k (L = r gives the homogeneous grid)")
      ->capture_default_str();
  cmd->add_option("--out", o->out, "output directory")->required();
  cmd->add_option("--slice-height", o->slice_height,
                  "height of the slice image in metres above the floor (default: scanner height)");
  add_preprocess_options(*cmd, o->pre);
  cmd->callback([o] {
    SemiOcTree::coarse_level_for(o->disc.leaf, o->disc.coarse);  // fail before reading anything
    if (o->input.files.empty() && o->scene.empty())
      throw std::invalid_argument("discretize: give --cloud FILE or --scene FILE");
    PreparedCloud cloud;
#ifdef SEMIOCTREE_HAVE_SIM
    if (!o->scene.empty())
      cloud = scan_scene_at_start(o->scene, o->seed, o->pre);
    else
#endif
      cloud = prepare_clouds(o->input, o->pre);
    const auto t0 = std::chrono::steady_clock::now();
    DiscretizeReport rep;
    const auto tree = discretize(*cloud.pre.cloud, cloud.pre.ceiling_height, o->disc, &rep);
    tree->prune();
    tree->compact();
    DiscretizationRun run;
    run.method = o->disc.leaf == o->disc.coarse ? "homogeneous" : "semioctree";
    run.leaf = o->disc.leaf;
    run.coarse = o->disc.coarse;
    run.stats = tree->statistics();
    run.memory_bytes = tree->memory_bytes();
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf(
        "discretize: %zu coarse voxels, %llu octants (%zu occupied leaves) at %g → %g m [%.2f s]\n",
        tree->coarse_count(), static_cast<unsigned long long>(run.stats.total()),
        rep.occupied_leaves, o->disc.coarse, o->disc.leaf, run.seconds);
    SliceOptions slice;
    slice.height = o->slice_height >= 0 ? o->slice_height
                                        : (cloud.scanners.empty() ? 1.5 : cloud.scanners.front().z);
    slice.scans = cloud.scanners;
    slice.title = std::filesystem::path(o->scene.empty() ? o->input.files.front() : o->scene)
                      .filename()
                      .string();
    write_map_files(*tree, o->out, slice);
    write_run_json(run, (std::filesystem::path(o->out) / "stats.json").string());
    std::printf("wrote %s/{semioctree.ot, labels_color.ot, occupancy.bt, slice.png, stats.json}\n",
                o->out.c_str());
  });
}

}  // namespace semioctree::cli
