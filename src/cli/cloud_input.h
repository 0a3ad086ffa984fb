// Shared by the commands that take point clouds: read, place by pose, merge
// and preprocess, with progress lines.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "option_checks.h"
#include "semioctree/discretize.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/preprocess.h"
#include "semioctree/scan_io.h"

namespace semioctree::cli {

struct CloudInput {
  std::vector<std::string> files;
  std::vector<std::string> poses;  // "X,Y,Z[,YAW]" per file; empty: identity / from the file (PTX)
  std::string pose_file;           // JSON pose for a single file
};

struct PreparedCloud {
  PreprocessResult pre;
  std::vector<Point3> scanners;  // scanner positions in the levelled frame
  // Per scanner, the directions its scan got returns in (levelled frame).
  std::vector<std::shared_ptr<const ReturnDirections>> returns;
  std::size_t raw_points = 0;
  std::size_t invalid_dropped = 0;
  std::size_t outside_limits = 0;  // returns outside the scanner's limits, dropped
};

// Throws std::invalid_argument naming `scan.source` when the returns kept (its
// points within `limits` when given) cannot be mapped: none left within the
// scanner's limits, or all of them within 1 mm of each other (one spot, no room).
void check_scan_usable(const Scan& scan, const ScannerView* limits);

// With `limits`, each scan first loses its returns outside the scanner's
// limits (within_limits: the scanner's mount, the robot), as in `survey`/`nbv`.
PreparedCloud prepare_clouds(const CloudInput& in, const PreprocessParams& params,
                             const ScannerView* limits = nullptr);

// The input of every command that maps scans: --cloud/--pose (real scans), or
// --scene/--seed (the synthetic scanner, when built with sim/), and the
// preprocessing options.
struct ScanSource {
  CloudInput input;
  std::string scene;
  std::uint64_t seed = 1;
  PreprocessParams pre;
};

// Adds those options to `cmd` (`pose_help` explains --pose for this command).
void add_scan_source_options(CLI::App& cmd, ScanSource& src, const std::string& pose_help);
// Reads (or scans) and preprocesses; throws std::invalid_argument when neither
// --cloud nor --scene was given.
PreparedCloud prepare(const ScanSource& src, const std::string& command,
                      const ScannerView* limits = nullptr);
// --max-range, --min-range, --elevation-min, --elevation-max.
void add_scanner_limit_options(CLI::App& cmd, ScannerView& limits);
// min < max for range and elevation; throws std::invalid_argument naming the options.
void check_scanner_limits(const ScannerView& limits);
// --leaf, --coarse: the semioctree's grid.
void add_grid_options(CLI::App& cmd, DiscretizeParams& grid);
// The title of a slice image: the input file's name.
std::string source_name(const ScanSource& src);

// The files a ScanSource reads (--cloud, --pose-file, --scene), for
// check_outputs_spare_inputs.
std::vector<NamedPath> source_paths(const ScanSource& src);
// The files write_map_files writes in its directory, and stats.json.
std::vector<std::string> map_files_written();

// True if `path` ends in `ext` (".ply"), whatever the case.
bool has_extension(const std::string& path, const std::string& ext);

}  // namespace semioctree::cli
