// Scene geometry as triangles (for the ray caster), and the 2-D polygon helpers the
// scene validation and the tessellation share.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "semioctree/sim/scene.h"

namespace semioctree::sim {

enum class PartKind : std::uint8_t { wall, slab, box, cylinder, mesh };
const char* to_string(PartKind kind);

// Which scene element a triangle or surface sample belongs to: e.g. {box, 2} is boxes[2].
struct PartRef {
  PartKind kind = PartKind::wall;
  int index = 0;
};

struct SceneTriangles {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  std::vector<PartRef> parts;                           // one per triangle
};

// Every solid of the scene as a closed, watertight triangle surface: walls with their
// openings cut through, slabs (concave polygons included), boxes, cylinders faceted so
// that the surface error is at most `max_cylinder_error`, meshes placed in the world.
// Faces of one solid share their vertices exactly, so a robust ray caster cannot slip
// through an edge.
SceneTriangles tessellate(const Scene& scene, double max_cylinder_error = 0.005);

// Number of facets for a cylinder of `radius` whose chords deviate from the circle by at
// most `max_error`.
int cylinder_segments(double radius, double max_error = 0.005);
// The faceted cross-section used by tessellate(), counter-clockwise.
std::vector<Eigen::Vector2d> cylinder_polygon(const Cylinder& c, double max_error = 0.005);

// Wall solid split into axis cells of its own (u along the wall, v = z) grid: the
// sorted u breaks (0, opening edges, length) and v breaks (z0, sills, tops, z1), and for
// each cell whether it is solid (not inside an opening).
struct WallGrid {
  std::vector<double> u;
  std::vector<double> v;
  std::vector<std::vector<bool>> solid;  // [iu][iv], size (u.size()-1) x (v.size()-1)
  // solid[i][j], false outside the grid (the wall's ends and top face the outside).
  bool solid_at(long i, long j) const {
    return i >= 0 && j >= 0 && i < static_cast<long>(solid.size()) &&
           j < static_cast<long>(solid[static_cast<std::size_t>(i)].size()) &&
           solid[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
  }
};
WallGrid wall_grid(const Wall& wall);

// --- 2-D polygons -----------------------------------------------------------------
double signed_area(const std::vector<Eigen::Vector2d>& polygon);
bool point_in_polygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);
// Distance from p to the polygon's boundary.
double distance_to_boundary(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);
// Indices (i, j) of the first two non-adjacent edges that touch or cross (edge i joins
// point i to point i+1), or {-1, -1} if the polygon is simple.
std::array<int, 2> first_self_intersection(const std::vector<Eigen::Vector2d>& polygon);
// Ear-clipping triangulation of a simple polygon of either orientation; the triangles
// are counter-clockwise.
std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon);

}  // namespace semioctree::sim
