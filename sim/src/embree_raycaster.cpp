// The only file that talks to Embree (version 3). An Embree 4 port changes this file:
// rtcIntersect*/rtcOccluded* take argument structs instead of RTCIntersectContext.
#include <embree3/rtcore.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "semioctree/sim/raycaster.h"

namespace semioctree::sim {

namespace {

void throw_on_error(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("Embree: ") + what + " failed (error " +
                             std::to_string(static_cast<int>(err)) + ")");
}

class EmbreeRayCaster final : public RayCaster {
 public:
  explicit EmbreeRayCaster(const SceneTriangles& tri) : triangle_count_(tri.triangles.size()) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    // ROBUST: without it a few rays in 1e5 slip through edges shared by two triangles.
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    if (!tri.triangles.empty()) {
      RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                            tri.vertices.size()));
      for (std::size_t i = 0; i < tri.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) v[3 * i + k] = tri.vertices[i][k];
      auto* idx = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(unsigned), tri.triangles.size()));
      normals_.reserve(tri.triangles.size());
      for (std::size_t i = 0; i < tri.triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) idx[3 * i + k] = tri.triangles[i][k];
        const Eigen::Vector3f& a = tri.vertices[tri.triangles[i][0]];
        const Eigen::Vector3f& b = tri.vertices[tri.triangles[i][1]];
        const Eigen::Vector3f& c = tri.vertices[tri.triangles[i][2]];
        const Eigen::Vector3f n = (b - a).cross(c - a);
        normals_.push_back(n.norm() > 0 ? Eigen::Vector3f(n.normalized())
                                        : Eigen::Vector3f::Zero());
      }
      rtcCommitGeometry(geom);
      rtcAttachGeometry(scene_, geom);
      rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene_);
    throw_on_error(device_, "building the scene");
  }

  ~EmbreeRayCaster() override {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }

  EmbreeRayCaster(const EmbreeRayCaster&) = delete;
  EmbreeRayCaster& operator=(const EmbreeRayCaster&) = delete;

  void intersect(const Ray* rays, RayHit* hits, std::size_t count) const override {
    // Packets of 16 in coherent mode: the scanner hands over neighbouring rays of one
    // row, which traverse the BVH together about 4x faster than one by one. Embree 3.13's
    // coherent traversal silently drops rays when a packet mixes direction octants or
    // holds a direction with a near-zero component (huge 1/d, e.g. near the zenith), so
    // packets are cut where the octant or the origin changes (the scanner's packets share
    // one origin; we never hand the frustum code anything else) and such rays are cast
    // alone.
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHit16 packet;
    alignas(64) int valid[16];
    auto octant = [](const Ray& r) {
      constexpr float kTiny = 1e-3f;
      if (std::abs(r.direction.x()) < kTiny || std::abs(r.direction.y()) < kTiny ||
          std::abs(r.direction.z()) < kTiny)
        return -1;
      return std::signbit(r.direction.x()) | (std::signbit(r.direction.y()) << 1) |
             (std::signbit(r.direction.z()) << 2);
    };
    std::size_t base = 0;
    while (base < count) {
      const int first_octant = octant(rays[base]);
      if (first_octant < 0) {
        intersect_one(rays[base], hits[base], context);
        ++base;
        continue;
      }
      std::size_t n = 1;
      while (n < 16 && base + n < count && octant(rays[base + n]) == first_octant &&
             rays[base + n].origin == rays[base].origin)
        ++n;
      for (std::size_t k = 0; k < 16; ++k) {
        const Ray& r = rays[base + std::min(k, n - 1)];
        valid[k] = k < n ? -1 : 0;
        packet.ray.org_x[k] = r.origin.x();
        packet.ray.org_y[k] = r.origin.y();
        packet.ray.org_z[k] = r.origin.z();
        packet.ray.dir_x[k] = r.direction.x();
        packet.ray.dir_y[k] = r.direction.y();
        packet.ray.dir_z[k] = r.direction.z();
        packet.ray.tnear[k] = r.t_near;
        packet.ray.tfar[k] = r.t_far;
        packet.ray.time[k] = 0.0f;
        packet.ray.mask[k] = 0xFFFFFFFFu;
        packet.ray.id[k] = 0;
        packet.ray.flags[k] = 0;
        packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect16(valid, scene_, &context, &packet);
      for (std::size_t k = 0; k < n; ++k) {
        RayHit& h = hits[base + k];
        h.hit = packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        if (h.hit) {
          h.distance = packet.ray.tfar[k];
          h.triangle = packet.hit.primID[k];
          h.normal = normals_[packet.hit.primID[k]];
        }
      }
      base += n;
    }
  }

  void intersect_one(const Ray& r, RayHit& h, RTCIntersectContext& context) const {
    RTCRayHit rh;
    rh.ray.org_x = r.origin.x();
    rh.ray.org_y = r.origin.y();
    rh.ray.org_z = r.origin.z();
    rh.ray.dir_x = r.direction.x();
    rh.ray.dir_y = r.direction.y();
    rh.ray.dir_z = r.direction.z();
    rh.ray.tnear = r.t_near;
    rh.ray.tfar = r.t_far;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    h.hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    if (h.hit) {
      h.distance = rh.ray.tfar;
      h.triangle = rh.hit.primID;
      h.normal = normals_[rh.hit.primID];
    }
  }

  bool segment_blocked(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const override {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    const Eigen::Vector3f d = b - a;
    ray.org_x = a.x();
    ray.org_y = a.y();
    ray.org_z = a.z();
    ray.dir_x = d.x();
    ray.dir_y = d.y();
    ray.dir_z = d.z();
    ray.tnear = 0.0f;
    ray.tfar = 1.0f;  // direction is b − a, so t = 1 is b
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(scene_, &context, &ray);
    return ray.tfar < 0.0f;  // Embree marks an occluded ray with tfar = -inf
  }

  std::size_t triangle_count() const override { return triangle_count_; }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<Eigen::Vector3f> normals_;
  std::size_t triangle_count_ = 0;
};

}  // namespace

std::unique_ptr<RayCaster> make_ray_caster(const SceneTriangles& triangles) {
  return std::make_unique<EmbreeRayCaster>(triangles);
}

}  // namespace semioctree::sim
