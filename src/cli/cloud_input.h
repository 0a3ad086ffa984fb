// Shared by the commands that take point clouds: read, place by pose, merge
// and preprocess, with progress lines.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/preprocess.h"

namespace semioctree::cli {

struct CloudInput {
  std::vector<std::string> files;
  std::vector<std::string> poses;  // "X,Y,Z[,YAW]" per file; empty: identity / from the file (PTX)
  std::string pose_file;           // JSON pose for a single file
};

struct PreparedCloud {
  PreprocessResult pre;
  std::vector<Point3> scanners;  // scanner positions in the levelled frame
  std::size_t raw_points = 0;
  std::size_t invalid_dropped = 0;
};

PreparedCloud prepare_clouds(const CloudInput& in, const PreprocessParams& params);

// Adds --target-points / --min-spacing to a command.
void add_preprocess_options(CLI::App& cmd, PreprocessParams& params);

}  // namespace semioctree::cli
