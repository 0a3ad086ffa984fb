// The scene's solids in closed form (boxes, prisms, triangle sets), independent of the
// triangle surfaces handed to the ray caster. Used to check the ray caster and the
// scanner ("no point inside a solid or behind a wall"), and for floor tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "semioctree/sim/scene.h"

namespace semioctree::sim {

class SolidModel {
 public:
  // Cylinders are taken as their faceted prism (the same facets the ray caster sees).
  explicit SolidModel(const Scene& scene);

  // Distance along the ray (origin + t·dir, |dir| = 1, origin outside every solid) to
  // where it first enters a solid, if that is at most t_max.
  std::optional<double> first_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                  double t_max) const;

  // Name of a solid that contains p deeper than `margin` (e.g. `boxes[2] "table"`), or
  // empty if none does. Mesh solids are tested with the generalized winding number.
  // `with_meshes = false` skips mesh solids (their test costs one term per triangle).
  std::string solid_containing(const Eigen::Vector3d& p, double margin = 0.0,
                               bool with_meshes = true) const;
  bool contains(const Eigen::Vector3d& p, double margin = 0.0, bool with_meshes = true) const {
    return !solid_containing(p, margin, with_meshes).empty();
  }

 private:
  struct OrientedBox {
    Eigen::Vector3d center, half, axis_u, axis_v;  // axes in the xy-plane, third is z
    std::string name;
  };
  struct Prism {
    std::vector<Eigen::Vector2d> polygon;
    double z0, z1;
    Eigen::Vector2d min_xy, max_xy;
    std::string name;
  };
  struct TriangleSet {
    std::vector<Eigen::Vector3d> a, b, c;
    Eigen::Vector3d min_corner, max_corner;
    std::string name;
  };
  void index_boxes();  // fills box_grid_ from boxes_

  std::vector<OrientedBox> boxes_;  // box elements and the solid cells of walls
  // The boxes by square cells of the xy-plane (each listed, in ascending order, in every
  // cell its xy bounding box meets), so that a point is tested against the few boxes of
  // its cell: a floor of a hundred rooms has a thousand.
  struct BoxGrid {
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
    double cell = 1.0;
    int nx = 0, ny = 0;
    std::vector<std::vector<std::uint32_t>> boxes;  // per cell, row-major
    const std::vector<std::uint32_t>* at(const Eigen::Vector2d& p) const;
  } box_grid_;
  std::vector<Prism> prisms_;  // slabs and faceted cylinders
  std::vector<TriangleSet> meshes_;
};

}  // namespace semioctree::sim
