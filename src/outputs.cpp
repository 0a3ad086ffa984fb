#include "semioctree/outputs.h"

#include <filesystem>
#include <ostream>
#include <string>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

namespace {

// The markers of the exports: a cube of 3×3×3 leaves at each scan position labelled
// `scan`, and at the NBV labelled `nbv` (after the scans: it wins where they meet).
std::vector<LeafMark> marker_leaves(const SemiOcTree& tree, const std::vector<Point3>& scans,
                                    const std::optional<Point3>& nbv) {
  std::vector<LeafMark> marks;
  const double r = tree.leaf_size();
  auto mark = [&](const Point3& c, Label label) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          octomap::OcTreeKey key;
          if (tree.key_of(Point3(c.x + dx * r, c.y + dy * r, c.z + dz * r), key))
            marks.push_back({key, label});
        }
  };
  for (const Point3& s : scans) mark(s, Label::kScan);
  if (nbv) mark(*nbv, Label::kNbv);
  return marks;
}

// `dir`, created if need be (FileError if it cannot be).
std::filesystem::path output_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FileError(dir + ": cannot create directory: " + ec.message());
  return dir;
}

}  // namespace

void write_map_files(const SemiOcTree& tree, const std::string& dir, const SliceOptions& slice,
                     const MapFiles& names) {
  const std::filesystem::path d = output_directory(dir);
  const std::vector<LeafMark> marks = marker_leaves(tree, slice.scans, slice.nbv);
  write_color_octree_file(tree, marks, (d / names.color).string());
  write_occupancy_binary_file(tree, marks, (d / names.occupancy).string());
  write_tree_file(tree, (d / names.semioctree).string());
  write_slice_png(tree, (d / names.slice).string(), slice);
}

void write_ply(const std::string& path, std::size_t count, const PlyLayout& layout,
               const std::function<PlyVertex(std::size_t)>& vertex) {
  static_assert(sizeof(float) == 4, "PLY float is 4 bytes");
  write_file_atomically(path, [&](std::ostream& os) {
    os << "ply\nformat binary_little_endian 1.0\ncomment " << layout.comment << "\nelement vertex "
       << count << "\nproperty float x\nproperty float y\nproperty float z\n";
    if (layout.colour) os << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (!layout.flag.empty()) os << "property uchar " << layout.flag << "\n";
    os << "end_header\n";
    for (std::size_t i = 0; i < count; ++i) {  // x86: already little-endian
      const PlyVertex v = vertex(i);
      const float xyz[3] = {v.x, v.y, v.z};
      os.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
      if (layout.colour) {
        const std::uint8_t rgb[3] = {v.red, v.green, v.blue};
        os.write(reinterpret_cast<const char*>(rgb), sizeof rgb);
      }
      if (!layout.flag.empty()) os.write(reinterpret_cast<const char*>(&v.flag), 1);
    }
  });
}

void write_cloud_ply(const Cloud& cloud, const std::string& path) {
  write_ply(path, cloud.size(), {"semioctree merged cloud", false, ""}, [&](std::size_t i) {
    const auto& p = cloud[i];
    return PlyVertex{p.x, p.y, p.z};
  });
}

}  // namespace semioctree
