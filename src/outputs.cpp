#include "semioctree/outputs.h"

#include <filesystem>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

void write_map_files(const SemiOcTree& tree, const std::string& dir, const SliceOptions& slice,
                     const MapFiles& names) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw FileError(dir + ": cannot create directory: " + ec.message());
  const fs::path d(dir);
  write_tree_file(tree, (d / names.semioctree).string());
  write_tree_file(*to_color_octree(tree), (d / names.color).string());
  write_binary_file(*to_occupancy_octree(tree), (d / names.occupancy).string());
  write_slice_png(tree, (d / names.slice).string(), slice);
}

}  // namespace semioctree
