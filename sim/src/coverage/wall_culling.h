// Decisions about a segment taken at the walls alone, without a ray query (internal):
// whether it passes through an opening, whether it certainly hits a wall's solid part, and
// whether a whole box of scan positions is cut off from a sample by one wall.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/scene.h"

namespace semioctree::sim::detail {

// A wall as the slab |dot(normal, x − origin)| ≤ half, with its face rectangle
// u ∈ [0, length] (u = dot(along, x − origin)), z ∈ [z0, z1] and the rectangles of its
// openings (from opening_rects, cut to the wall) in the same (u, z) coordinates.
struct WallSlab {
  struct Rect {
    double u0, u1, z0, z1;
  };
  Eigen::Vector3d origin, along, normal;  // origin: wall.from at z = 0, on the centre plane
  double length, z0, z1, half;
  std::vector<Rect> holes;
};

// One slab per wall of the scene, in the order of scene.walls.
std::vector<WallSlab> wall_slabs(const Scene& scene);

// out[k] = signed distance of p from the centre plane of walls[k] (walls.size() values).
void wall_offsets(const std::vector<WallSlab>& walls, const Eigen::Vector3d& p, double* out);

// What a segment does at the walls.
enum class AtWalls { nothing_known, opening, solid };

// `opening` if a→b passes through an opening (as segment_through_opening). With
// `find_solid`, `solid` if it certainly crosses a wall's solid part, far enough from every
// edge that the ray caster reports the hit too. Otherwise `nothing_known`: only a ray
// query can tell. `wa` and `wb` are the wall_offsets of a and b.
AtWalls at_walls(const std::vector<WallSlab>& walls, const Eigen::Vector3d& a, const double* wa,
                 const Eigen::Vector3d& b, const double* wb, bool find_solid);

// The distinct corners of the bounding box of some scan positions (4 when they share one
// height).
struct PositionBox {
  std::vector<Eigen::Vector3d> corners;
};

// The box of positions[m] for m in `members` (not empty).
PositionBox box_of(const std::vector<Eigen::Vector3d>& positions,
                   const std::vector<std::uint32_t>& members);

// True if no optical centre in `box` can see `sample`, whose segments end at `target`
// (`target_offsets`: its wall_offsets): none faces the sample, or one wall cuts every
// segment from the box to it inside that wall's face rectangle, through a hole or the solid.
bool hidden_from_box(const SurfaceSample& sample, const Eigen::Vector3d& target,
                     const double* target_offsets, const PositionBox& box,
                     const std::vector<WallSlab>& walls);

}  // namespace semioctree::sim::detail
