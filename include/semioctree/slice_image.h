// Slice image: the horizontal cut of a SemiOcTree at one height, in the
// paper's colours (Figs 5, 6, 14), each octant outlined so that its size shows,
// with past scan positions, the NBV, a scale bar and a legend.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct SliceOptions {
  double height = 1.5;        // z of the cut, m
  int pixels_per_leaf = 0;    // 0: chosen so the map is about 1200 px wide (≥ 1 per leaf)
  bool outlines = true;       // outline each octant (sizes visible)
  std::vector<Point3> scans;  // past scanner positions (black discs)
  std::optional<Point3> nbv;  // next best view (red disc)
  std::string title;
};

// Writes a PNG (atomically); throws FileError / std::invalid_argument.
void write_slice_png(const SemiOcTree& tree, const std::string& path, const SliceOptions& options);

}  // namespace semioctree
