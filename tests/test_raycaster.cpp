// Tessellation and ray casting: known distances, openings, watertightness (rays aimed at
// the edges and corners of the triangles never slip through), polygons, cylinders.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scene.h"

namespace {

using namespace semioctree::sim;

const std::string kScenes = SEMIOCTREE_SOURCE_DIR "/sim/scenes";

RayHit cast(const RayCaster& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  Ray r;
  r.origin = o.cast<float>();
  r.direction = d.normalized().cast<float>();
  return c.intersect(r);
}

TEST(RayCaster, KnownDistanceAndNormalToAWall) {
  const Scene s = load_scene_json(kScenes + "/box-room.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  // Room interior x in [0, 6], y in [0, 4], z in [0, 2.8].
  const RayHit h = cast(*caster, {2, 1.5, 1.5}, {1, 0, 0});
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 4.0, 1e-5);
  EXPECT_NEAR(h.normal.x(), -1.0, 1e-6);  // the wall's face looks back into the room
  const RayHit up = cast(*caster, {2, 1.5, 1.5}, {0, 0, 1});
  ASSERT_TRUE(up.hit);
  EXPECT_NEAR(up.distance, 1.3, 1e-5);
  EXPECT_NEAR(up.normal.z(), -1.0, 1e-6);
  const RayHit slanted = cast(*caster, {2, 1.5, 1.5}, {0, -1, -1});
  ASSERT_TRUE(slanted.hit);
  EXPECT_NEAR(slanted.distance, 1.5 * std::sqrt(2.0), 1e-5);  // the corner line of floor and wall
}

TEST(RayCaster, RaysPassThroughOpenings) {
  const Scene s = load_scene_json(kScenes + "/one-door-window.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  // Window in the south wall (y = -0.1): x in [1.9, 3.4], z in [0.9, 2.1]; nothing outside.
  EXPECT_FALSE(cast(*caster, {2.6, 2, 1.5}, {0, -1, 0}).hit);
  EXPECT_FALSE(cast(*caster, {2.6, 2, 1.5}, {0.2, -1, -0.1}).hit);
  // Just beside the window the wall is there, at its inner face y = 0.
  const RayHit beside = cast(*caster, {1.7, 2, 1.5}, {0, -1, 0});
  ASSERT_TRUE(beside.hit);
  EXPECT_NEAR(beside.distance, 2.0, 1e-5);
  // Below the sill as well.
  EXPECT_TRUE(cast(*caster, {2.6, 2, 0.5}, {0, -1, 0}).hit);
  // Door in the east wall (x = 6.1): y in [0.9, 1.8], z in [0, 2.05].
  EXPECT_FALSE(cast(*caster, {5, 1.35, 1.0}, {1, 0, 0}).hit);
  EXPECT_TRUE(cast(*caster, {5, 1.35, 2.3}, {1, 0, 0}).hit);  // above the door
  // From inside the wall, a ray along it meets the door's jamb at y = 0.9.
  const RayHit jamb = cast(*caster, {6.1, 0.5, 1.0}, {0, 1, 0});
  ASSERT_TRUE(jamb.hit);
  EXPECT_NEAR(jamb.distance, 0.4, 1e-5);
  EXPECT_NEAR(jamb.normal.y(), 1.0, 1e-6);  // the jamb faces into the hole
}

TEST(RayCaster, SegmentBlocked) {
  const Scene s = load_scene_json(kScenes + "/one-door-window.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  EXPECT_FALSE(
      caster->segment_blocked({1, 1, 1.5}, {5, 3.5, 1.5}));  // across the room, over the table
  EXPECT_TRUE(caster->segment_blocked({1, 2, 0.4}, {5, 2, 0.4}));        // through the table
  EXPECT_TRUE(caster->segment_blocked({1, 2, 1.5}, {-1, 2, 1.5}));       // through the west wall
  EXPECT_FALSE(caster->segment_blocked({2.6, 2, 1.5}, {2.6, -3, 1.5}));  // out through the window
}

// Every vertex and every edge point of the room's shell (walls, floor, ceiling) is on a
// surface that is flat or concave seen from inside: a ray aimed at it must stop there
// (or earlier), never slip through. Openings are closed here so that nothing may
// legitimately fly out. (Convex edges of furniture are left out: a ray aimed exactly at
// a silhouette edge only grazes it.)
TEST(RayCaster, RaysAimedAtEdgesAndCornersDoNotLeak) {
  for (const char* name : {"box-room", "one-door-window", "lab"}) {
    Scene s = load_scene_json(kScenes + "/" + name + ".scene.json");
    for (Wall& w : s.walls) w.openings.clear();
    const SceneTriangles tri = tessellate(s);
    const auto caster = make_ray_caster(tri);
    const Eigen::Vector3d origin(s.robot.start.x(), s.robot.start.y(), s.scanner.height);
    std::vector<Ray> rays;
    std::vector<double> target_distance;
    for (std::size_t i = 0; i < tri.triangles.size(); ++i) {
      if (tri.parts[i].kind != PartKind::wall && tri.parts[i].kind != PartKind::slab) continue;
      const auto& t = tri.triangles[i];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d a = tri.vertices[t[k]].cast<double>(),
                              b = tri.vertices[t[(k + 1) % 3]].cast<double>();
        for (double f : {0.0, 0.5, 1.0 / 3.0, 0.1}) {
          const Eigen::Vector3d d = a + f * (b - a) - origin;
          Ray r;
          r.origin = origin.cast<float>();
          r.direction = d.normalized().cast<float>();
          rays.push_back(r);
          target_distance.push_back(d.norm());
        }
      }
    }
    std::vector<RayHit> hits(rays.size());
    caster->intersect(rays.data(), hits.data(), rays.size());
    int leaks = 0;
    for (std::size_t i = 0; i < rays.size(); ++i)
      if (!hits[i].hit || hits[i].distance > target_distance[i] + 1e-3) ++leaks;
    EXPECT_EQ(leaks, 0) << name << ": " << leaks << " of " << rays.size()
                        << " rays slipped through";
  }
}

// A dense fan of rays from inside the closed room: every one must hit.
TEST(RayCaster, ClosedRoomCatchesEveryRay) {
  const Scene s = load_scene_json(kScenes + "/box-room.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  const int count = 200000;
  std::vector<Ray> rays(count);
  for (Ray& r : rays) {
    r.origin = Eigen::Vector3f(3.0f, 2.0f, 1.4f);
    r.direction = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized().cast<float>();
  }
  std::vector<RayHit> hits(count);
  caster->intersect(rays.data(), hits.data(), hits.size());
  int misses = 0;
  for (const RayHit& h : hits) misses += !h.hit;
  EXPECT_EQ(misses, 0);
}

TEST(RayCaster, BatchAgreesWithSingleRays) {
  const Scene s = load_scene_json(kScenes + "/lab.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  std::vector<Ray> rays(1000);  // not a multiple of the packet size
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    Ray& r = rays[i];
    // Runs of rays from one origin, and stretches where every ray has its own.
    r.origin = i < 500 ? Eigen::Vector3f(5.2f, 3.6f, 1.5f)
                       : Eigen::Vector3f(5.2f + jitter(rng), 3.6f, 1.5f);
    r.direction = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized().cast<float>();
    r.t_far = 8.0f;
  }
  std::vector<RayHit> batch(rays.size());
  caster->intersect(rays.data(), batch.data(), rays.size());
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit one = caster->intersect(rays[i]);
    ASSERT_EQ(one.hit, batch[i].hit) << i;
    if (one.hit) {
      EXPECT_EQ(one.distance, batch[i].distance);
      EXPECT_EQ(one.triangle, batch[i].triangle);
      EXPECT_LE(one.distance, 8.0f);
      ++hits;
    }
  }
  EXPECT_GT(hits, 0);
  EXPECT_LT(hits, 1000);  // t_far = 8 m leaves some rays without a hit
}

// Packets whose rays point almost along an axis, with tiny components of both signs:
// the case where Embree's coherent packet traversal loses rays if handed them together.
TEST(RayCaster, BatchAgreesWithSingleRaysNearTheAxes) {
  const Scene s = load_scene_json(kScenes + "/box-room.scene.json");
  const auto caster = make_ray_caster(tessellate(s));
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> axis(0, 2), sign(0, 1), exponent(-20, -1);
  std::uniform_real_distribution<double> mantissa(1, 10);
  std::vector<Ray> rays(4096);
  for (Ray& r : rays) {
    Eigen::Vector3d d;
    for (int k = 0; k < 3; ++k)
      d[k] = (sign(rng) ? 1 : -1) * mantissa(rng) * std::pow(10.0, exponent(rng));
    d[axis(rng)] = sign(rng) ? 1 : -1;
    r.origin = Eigen::Vector3f(3.0f, 2.0f, 1.4f);
    r.direction = d.normalized().cast<float>();
  }
  std::vector<RayHit> batch(rays.size());
  caster->intersect(rays.data(), batch.data(), rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(batch[i].hit) << "ray " << i << " direction " << rays[i].direction.transpose();
    EXPECT_EQ(batch[i].distance, caster->intersect(rays[i]).distance);
  }
}

TEST(Tessellation, WallWithOpeningsIsClosed) {
  Scene s;
  Wall w;
  w.from = {0, 0};
  w.to = {5, 0};
  w.z1 = 2.5;
  w.openings = {{OpeningKind::door, 0.5, 0.9, 0.0, 2.0}, {OpeningKind::window, 2.0, 1.5, 0.9, 1.0}};
  s.walls.push_back(w);
  const SceneTriangles tri = tessellate(s);
  // Closed 2-manifold: every edge is used by exactly two triangles, in opposite directions.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : tri.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u)
        << "open edge " << edge.first << "-" << edge.second;
  }
  // Volume by the divergence theorem = wall box minus the holes.
  double volume = 0;
  for (const auto& t : tri.triangles)
    volume += tri.vertices[t[0]].cast<double>().dot(
                  tri.vertices[t[1]].cast<double>().cross(tri.vertices[t[2]].cast<double>())) /
              6;
  EXPECT_NEAR(volume, 0.2 * (5 * 2.5 - 0.9 * 2.0 - 1.5 * 1.0), 1e-5);
  for (const PartRef& p : tri.parts) EXPECT_EQ(p.kind, PartKind::wall);
}

TEST(Tessellation, EveryElementIsAClosedSurfaceWithTheRightVolume) {
  const Scene s = load_scene_json(kScenes + "/lab.scene.json");
  const SceneTriangles tri = tessellate(s);
  std::map<std::pair<int, int>, double> volumes;  // per part
  auto volume = [&](PartKind kind, std::size_t i) {
    return volumes[{static_cast<int>(kind), static_cast<int>(i)}];
  };
  for (std::size_t i = 0; i < tri.triangles.size(); ++i) {
    const auto& t = tri.triangles[i];
    volumes[{static_cast<int>(tri.parts[i].kind), tri.parts[i].index}] +=
        tri.vertices[t[0]].cast<double>().dot(
            tri.vertices[t[1]].cast<double>().cross(tri.vertices[t[2]].cast<double>())) /
        6;
  }
  for (std::size_t i = 0; i < s.boxes.size(); ++i)
    EXPECT_NEAR(volume(PartKind::box, i), s.boxes[i].size.prod(), 1e-3 * s.boxes[i].size.prod())
        << s.boxes[i].name;
  for (std::size_t i = 0; i < s.slabs.size(); ++i)
    EXPECT_NEAR(volume(PartKind::slab, i),
                std::abs(signed_area(s.slabs[i].polygon)) * (s.slabs[i].z1 - s.slabs[i].z0), 1e-2);
  for (std::size_t i = 0; i < s.cylinders.size(); ++i) {
    const Cylinder& c = s.cylinders[i];
    const double v = volume(PartKind::cylinder, i);
    const double exact = M_PI * c.radius * c.radius * (c.z1 - c.z0);
    EXPECT_LT(v, exact);  // facets lie inside the circle, less than 5 mm from it
    EXPECT_GT(v, M_PI * (c.radius - 0.005) * (c.radius - 0.005) * (c.z1 - c.z0));
  }
  // Walls: length x thickness x height minus openings.
  for (std::size_t i = 0; i < s.walls.size(); ++i) {
    const Wall& w = s.walls[i];
    double expected = w.length() * (w.z1 - w.z0);
    for (const Opening& o : w.openings) expected -= o.width * o.height;
    EXPECT_NEAR(volume(PartKind::wall, i), expected * w.thickness, 1e-3);
  }
}

TEST(Tessellation, CylinderFacetsStayWithinFiveMillimetres) {
  for (double r : {0.05, 0.15, 0.25, 0.5, 1.0, 3.0}) {
    Cylinder c;
    c.radius = r;
    const std::vector<Eigen::Vector2d> ring = cylinder_polygon(c);
    double worst = 0;
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Eigen::Vector2d mid =
          (ring[i] + ring[(i + 1) % ring.size()]) / 2;  // farthest from the arc
      worst = std::max(worst, r - mid.norm());
      EXPECT_NEAR(ring[i].norm(), r, 1e-12);
    }
    EXPECT_LE(worst, 0.005) << "radius " << r;
    EXPECT_GT(worst, 0.0025) << "radius " << r
                             << ": more facets than needed";  // not wastefully fine
  }
}

TEST(Polygons, ConcavePolygonsTriangulate) {
  // An L and a U, given clockwise and counter-clockwise.
  const std::vector<std::vector<Eigen::Vector2d>> shapes = {
      {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 3}, {0, 3}},
      {{0, 0}, {0, 3}, {1, 3}, {1, 1}, {2, 1}, {2, 3}, {3, 3}, {3, 0}},
      {{0, 0}, {2, 0}, {2, 0.5}, {2, 1}, {0, 1}},  // with a collinear vertex
  };
  for (const auto& poly : shapes) {
    const auto tris = triangulate_polygon(poly);
    double area = 0;
    for (const auto& t : tris) {
      const double a = ((poly[t[1]] - poly[t[0]]).x() * (poly[t[2]] - poly[t[0]]).y() -
                        (poly[t[1]] - poly[t[0]]).y() * (poly[t[2]] - poly[t[0]]).x()) /
                       2;
      EXPECT_GT(a, 0);  // counter-clockwise, no degenerate triangle
      area += a;
    }
    EXPECT_NEAR(area, std::abs(signed_area(poly)), 1e-12);
  }
}

TEST(Polygons, ConcaveSlabIsHitOnlyWhereItIs) {
  Scene s;
  Slab l;
  l.polygon = {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 3}, {0, 3}};
  l.z0 = -0.2;
  l.z1 = 0;
  s.slabs.push_back(l);
  const auto caster = make_ray_caster(tessellate(s));
  EXPECT_TRUE(cast(*caster, {3.5, 0.5, 1}, {0, 0, -1}).hit);
  EXPECT_TRUE(cast(*caster, {0.5, 2.5, 1}, {0, 0, -1}).hit);
  EXPECT_FALSE(cast(*caster, {2.5, 2.0, 1}, {0, 0, -1}).hit);  // in the notch of the L
  EXPECT_NEAR(cast(*caster, {0.5, 0.5, 1}, {0, 0, -1}).distance, 1.0, 1e-6);
}

TEST(Polygons, PointInPolygonAndSelfIntersection) {
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 3}, {0, 3}};
  EXPECT_TRUE(point_in_polygon(l, {0.5, 2}));
  EXPECT_FALSE(point_in_polygon(l, {2, 2}));
  EXPECT_NEAR(distance_to_boundary(l, {0.5, 2}), 0.5, 1e-12);
  EXPECT_EQ(first_self_intersection(l), (std::array<int, 2>{-1, -1}));
  const std::vector<Eigen::Vector2d> bow = {{0, 0}, {2, 2}, {2, 0}, {0, 2}};
  EXPECT_EQ(first_self_intersection(bow), (std::array<int, 2>{0, 2}));
  // A vertex touching another edge is not simple either.
  const std::vector<Eigen::Vector2d> touch = {{0, 0}, {4, 0}, {4, 2}, {2, 0}, {0, 2}};
  EXPECT_NE(first_self_intersection(touch)[0], -1);
}

TEST(Meshes, PlacementAppliesScaleYawAndPosition) {
  Scene s = load_scene_json(kScenes + "/box-room.scene.json");
  MeshInstance m;
  m.mesh = read_mesh_file(kScenes + "/meshes/chair.obj");
  m.position = {3, 2, 0};
  m.yaw_deg = 90;
  m.scale = 2;
  s.meshes.push_back(m);
  const auto caster = make_ray_caster(tessellate(s));
  // Seat top at 2 x 0.47 = 0.94 m; the backrest (local +y) turned to world -x, at x = 3 - 2 x
  // 0.225.
  const RayHit seat = cast(*caster, {3, 2, 2.5}, {0, 0, -1});
  ASSERT_TRUE(seat.hit);
  EXPECT_NEAR(2.5 - seat.distance, 0.94, 1e-5);
  const RayHit back = cast(*caster, {1, 2, 1.5}, {1, 0, 0});
  ASSERT_TRUE(back.hit);
  EXPECT_NEAR(1 + back.distance, 3 - 2 * 0.225, 1e-5);
}

}  // namespace
