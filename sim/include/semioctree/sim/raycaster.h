// Ray / scene intersection behind a small interface, so that the ray-tracing library
// (Embree 3 today) is confined to one source file.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "semioctree/sim/geometry.h"

namespace semioctree::sim {

struct Ray {
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();  // unit length
  float t_near = 0.0f;
  float t_far = std::numeric_limits<float>::infinity();
};

struct RayHit {
  bool hit = false;
  float distance = 0.0f;                             // along the ray, metres
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // unit geometric normal of the hit triangle
  std::uint32_t triangle = 0;                        // index into SceneTriangles::triangles
};

class RayCaster {
 public:
  virtual ~RayCaster() = default;
  // Nearest hit of each of `count` rays within [t_near, t_far]. Thread-safe.
  virtual void intersect(const Ray* rays, RayHit* hits, std::size_t count) const = 0;
  // True if the open segment a→b crosses a surface. Thread-safe.
  virtual bool segment_blocked(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const = 0;
  virtual std::size_t triangle_count() const = 0;

  RayHit intersect(const Ray& ray) const {
    RayHit h;
    intersect(&ray, &h, 1);
    return h;
  }
};

// Builds the ray caster (Embree 3, robust scene) over `triangles`.
std::unique_ptr<RayCaster> make_ray_caster(const SceneTriangles& triangles);

}  // namespace semioctree::sim
