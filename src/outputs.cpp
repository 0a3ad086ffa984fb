#include "semioctree/outputs.h"

#include <filesystem>
#include <ostream>
#include <string>

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

void write_cloud_ply(const Cloud& cloud, const std::string& path) {
  static_assert(sizeof(float) == 4, "PLY float is 4 bytes");
  write_file_atomically(path, [&](std::ostream& os) {
    os << "ply\nformat binary_little_endian 1.0\ncomment semioctree merged cloud\nelement vertex "
       << cloud.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (const auto& p : cloud) {  // x86: already little-endian
      const float xyz[3] = {p.x, p.y, p.z};
      os.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
    }
  });
}

}  // namespace semioctree
