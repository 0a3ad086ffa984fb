// The map files every command writes into its output directory: the
// SemiOcTree with all labels (.ot), a ColorOcTree for octovis (.ot), the .bt
// occupancy map and the slice image. Each is written atomically.
#pragma once

#include <string>

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

// Creates `dir` if needed. Throws FileError.
void write_map_files(const SemiOcTree& tree, const std::string& dir, const SliceOptions& slice,
                     const MapFiles& names = {});

// Binary little-endian PLY of the points (x y z as float), written atomically;
// CloudCompare, PCL and MeshLab read it. Throws FileError.
void write_cloud_ply(const Cloud& cloud, const std::string& path);

}  // namespace semioctree
