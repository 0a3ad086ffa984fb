// The map files every command writes into its output directory: the
// SemiOcTree with all labels (.ot), a ColorOcTree for octovis (.ot), the .bt
// occupancy map and the slice image. Each is written atomically.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/scan_io.h"
#include "semioctree/slice_image.h"

namespace semioctree {

struct MapFiles {
  std::string semioctree = "semioctree.ot";
  std::string color = "labels_color.ot";
  std::string occupancy = "occupancy.bt";
  std::string slice = "slice.png";
};

// Creates `dir` if needed. Throws FileError. semioctree.ot is `tree` as it is; the two
// OctoMap files (labels_color.ot, occupancy.bt) carry the markers of docs/outputs.md: a
// cube of 3×3×3 leaves (the scanner's head) labelled `scan` at every position of
// slice.scans and `nbv` at slice.nbv, so that octovis shows where the scans stood and
// where to go next (occupancy.bt shows them as free). The markers are drawn into the
// exports as they are written; `tree` is neither changed nor copied, and no OctoMap tree
// is built (a few bytes a node beside it).
void write_map_files(const SemiOcTree& tree, const std::string& dir, const SliceOptions& slice,
                     const MapFiles& names = {});

// One vertex of a PLY file: its position, and its colour and flag if the layout has them.
struct PlyVertex {
  float x = 0, y = 0, z = 0;
  std::uint8_t red = 0, green = 0, blue = 0, flag = 0;
};
struct PlyLayout {
  std::string comment;  // one line
  bool colour = false;  // uchar red, green, blue
  std::string flag;     // name of a uchar property (empty: none)
};
// Binary little-endian PLY of `count` vertices, vertex(i) each (x y z as float, then the
// layout's uchar properties), written atomically. Throws FileError.
void write_ply(const std::string& path, std::size_t count, const PlyLayout& layout,
               const std::function<PlyVertex(std::size_t)>& vertex);

// Binary little-endian PLY of the points (x y z as float), written atomically;
// CloudCompare, PCL and MeshLab read it. Throws FileError.
void write_cloud_ply(const Cloud& cloud, const std::string& path);

}  // namespace semioctree
