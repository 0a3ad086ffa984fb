// Slice image: the horizontal cut of a SemiOcTree at one height, in the
// paper's colours (Figs 5, 6, 14), each octant outlined so that its size shows,
// with past scan positions, the robot's routes, the NBV, the doors and windows found,
// rooms' outlines, axes in metres, a scale bar and a legend (drawn with cairo).
#pragma once

#include <array>
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

// A room seen from above: its outline (segments x0, y0, x1, y1) and a label inside it.
struct SliceRoom {
  std::vector<std::array<float, 4>> outline;
  Point3 label_at;
  std::string label;
};

struct SliceOptions {
  double height = 1.5;        // z of the cut, m
  int pixels_per_leaf = 0;    // 0: chosen so the map is about 1200 px wide (≥ 1 per leaf)
  bool outlines = true;       // outline each octant (sizes visible)
  std::vector<Point3> scans;  // past scanner positions (black discs)
  std::optional<Point3> nbv;  // next best view (red disc)
  // The robot's drives, each a polyline (RouteTree::route_to), drawn instead of straight
  // lines from each scan to the next when given.
  std::vector<std::vector<Point3>> routes;
  std::vector<SliceRoom> rooms;  // outlined and labelled
  // Doors and windows, whatever their height: a bar in their label colour across the wall,
  // numbered D1, D2, … and W1, W2, … in this order (as survey.json lists them).
  std::vector<SliceOpening> openings;
  std::string title;
};

// The colour rooms are outlined and labelled in.
Rgb slice_room_color();

// Writes a PNG (atomically); throws FileError / std::invalid_argument.
void write_slice_png(const SemiOcTree& tree, const std::string& path, const SliceOptions& options);

}  // namespace semioctree
