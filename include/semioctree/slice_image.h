// Slice image: the horizontal cut of a SemiOcTree at one height, in the
// paper's colours (Figs 5, 6, 14), each octant outlined so that its size shows,
// with past scan positions, the NBV, the doors and windows found, axes in metres, a
// scale bar and a legend (drawn with cairo).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

// A door or window seen from above: its bottom edge in the wall, from one side to the other.
struct SliceOpening {
  bool door = true;  // else a window
  Point3 from, to;
};

struct SliceOptions {
  double height = 1.5;        // z of the cut, m
  int pixels_per_leaf = 0;    // 0: chosen so the map is about 1200 px wide (≥ 1 per leaf)
  bool outlines = true;       // outline each octant (sizes visible)
  std::vector<Point3> scans;  // past scanner positions (black discs)
  std::optional<Point3> nbv;  // next best view (red disc)
  // Doors and windows, whatever their height: a bar in their label colour across the wall,
  // numbered D1, D2, … and W1, W2, … in this order (as survey.json lists them).
  std::vector<SliceOpening> openings;
  std::string title;
};

// Writes a PNG (atomically); throws FileError / std::invalid_argument.
void write_slice_png(const SemiOcTree& tree, const std::string& path, const SliceOptions& options);

}  // namespace semioctree
