// Triangle meshes: reading OBJ / PLY files and OctoMap .bt files (occupied voxels as
// solid cubes).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace semioctree::sim {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i>
      triangles;  // indices into vertices, counter-clockwise seen from outside

  Eigen::Vector3d min_corner() const;
  Eigen::Vector3d max_corner() const;
};

// Reads an OBJ or PLY (ASCII or binary) triangle mesh; polygons are split into triangle
// fans. Throws std::runtime_error "<path>: <problem>" if the file cannot be read, has
// no triangles or refers to a missing vertex.
TriangleMesh read_mesh_file(const std::string& path);

// Reads an OctoMap .bt file and returns the boundary of its occupied voxels as a closed,
// watertight triangle mesh (faces between two occupied voxels are left out).
TriangleMesh read_octomap_occupied(const std::string& path);

}  // namespace semioctree::sim
