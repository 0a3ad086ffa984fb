// Scene → watertight triangle surfaces, and 2-D polygon helpers.
#include "semioctree/sim/geometry.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace semioctree::sim {

const char* to_string(PartKind kind) {
  switch (kind) {
    case PartKind::wall:
      return "walls";
    case PartKind::slab:
      return "slabs";
    case PartKind::box:
      return "boxes";
    case PartKind::cylinder:
      return "cylinders";
    case PartKind::mesh:
      return "meshes";
  }
  return "?";
}

// --- 2-D polygons -------------------------------------------------------------------

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Sign of the turn a→b→c with a tolerance relative to the edge lengths.
int orientation(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double v = cross2(b - a, c - a);
  const double scale = (b - a).norm() * (c - a).norm();
  if (std::abs(v) <= 1e-12 * std::max(scale, 1e-300)) return 0;
  return v > 0 ? 1 : -1;
}

bool on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return std::min(a.x(), b.x()) - 1e-12 <= p.x() && p.x() <= std::max(a.x(), b.x()) + 1e-12 &&
         std::min(a.y(), b.y()) - 1e-12 <= p.y() && p.y() <= std::max(a.y(), b.y()) + 1e-12;
}

bool segments_touch(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                    const Eigen::Vector2d& q2) {
  const int o1 = orientation(p1, p2, q1), o2 = orientation(p1, p2, q2);
  const int o3 = orientation(q1, q2, p1), o4 = orientation(q1, q2, p2);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;  // proper crossing
  if (o1 == 0 && on_segment(p1, p2, q1)) return true;
  if (o2 == 0 && on_segment(p1, p2, q2)) return true;
  if (o3 == 0 && on_segment(q1, q2, p1)) return true;
  if (o4 == 0 && on_segment(q1, q2, p2)) return true;
  return false;
}

bool point_in_triangle(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                       const Eigen::Vector2d& c) {
  // a, b, c counter-clockwise; boundary counts as inside so that ears are never wrong.
  return cross2(b - a, p - a) >= 0 && cross2(c - b, p - b) >= 0 && cross2(a - c, p - c) >= 0;
}

}  // namespace

double signed_area(const std::vector<Eigen::Vector2d>& polygon) {
  double a = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i)
    a += cross2(polygon[i], polygon[(i + 1) % polygon.size()]);
  return a / 2;
}

bool point_in_polygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

double distance_to_boundary(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2d ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

std::array<int, 2> first_self_intersection(const std::vector<Eigen::Vector2d>& polygon) {
  const int n = static_cast<int>(polygon.size());
  auto p = [&](int i) { return polygon[static_cast<std::size_t>(i % n)]; };
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      if (adjacent) {
        // Adjacent edges share a vertex; they are wrong only if they fold back on each other.
        const int shared_first = (j == i + 1) ? i + 1 : 0;
        const Eigen::Vector2d s = p(shared_first);
        const Eigen::Vector2d a = (j == i + 1) ? p(i) : p(j);
        const Eigen::Vector2d b = (j == i + 1) ? p(j + 1) : p(1);
        if (orientation(a, s, b) == 0 && (a - s).dot(b - s) > 0) return {i, j};
        continue;
      }
      if (segments_touch(p(i), p(i + 1), p(j), p(j + 1))) return {i, j};
    }
  }
  return {-1, -1};
}

std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon) {
  std::vector<int> ring(polygon.size());
  for (std::size_t i = 0; i < ring.size(); ++i) ring[i] = static_cast<int>(i);
  if (signed_area(polygon) < 0) std::reverse(ring.begin(), ring.end());
  std::vector<std::array<int, 3>> out;
  while (ring.size() > 3) {
    const std::size_t n = ring.size();
    bool clipped = false;
    for (std::size_t k = 0; k < n && !clipped; ++k) {
      const int ia = ring[(k + n - 1) % n], ib = ring[k], ic = ring[(k + 1) % n];
      const Eigen::Vector2d &a = polygon[ia], &b = polygon[ib], &c = polygon[ic];
      const int turn = orientation(a, b, c);
      if (turn < 0) continue;  // reflex vertex
      bool empty = true;
      if (turn > 0) {
        for (std::size_t m = 0; m < n && empty; ++m) {
          const int im = ring[m];
          if (im == ia || im == ib || im == ic) continue;
          if (point_in_triangle(polygon[im], a, b, c)) empty = false;
        }
      }
      if (!empty) continue;
      if (turn > 0)
        out.push_back({ia, ib, ic});  // a collinear vertex is dropped without a triangle
      ring.erase(ring.begin() + static_cast<long>(k));
      clipped = true;
    }
    if (!clipped) {  // not simple after all (validation rejects those); fan what is left
      for (std::size_t k = 1; k + 1 < ring.size(); ++k)
        out.push_back({ring[0], ring[k], ring[k + 1]});
      return out;
    }
  }
  if (ring.size() == 3 && orientation(polygon[ring[0]], polygon[ring[1]], polygon[ring[2]]) > 0)
    out.push_back({ring[0], ring[1], ring[2]});
  return out;
}

// --- cylinders and walls --------------------------------------------------------------

int cylinder_segments(double radius, double max_error) {
  if (max_error >= radius) return 8;
  // A chord of angle 2π/n deviates from the arc by r (1 − cos(π/n)).
  const int n = static_cast<int>(std::ceil(M_PI / std::acos(1.0 - max_error / radius)));
  return std::max(8, n);
}

std::vector<Eigen::Vector2d> cylinder_polygon(const Cylinder& c, double max_error) {
  const int n = cylinder_segments(c.radius, max_error);
  std::vector<Eigen::Vector2d> out;
  out.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    out.emplace_back(c.center.x() + c.radius * std::cos(a), c.center.y() + c.radius * std::sin(a));
  }
  return out;
}

WallGrid wall_grid(const Wall& wall) {
  WallGrid g;
  g.u = {0.0, wall.length()};
  g.v = {wall.z0, wall.z1};
  for (const Opening& o : wall.openings) {
    g.u.push_back(o.start);
    g.u.push_back(std::min(o.start + o.width, wall.length()));
    g.v.push_back(wall.z0 + o.sill);
    g.v.push_back(std::min(wall.z0 + o.sill + o.height, wall.z1));
  }
  auto unique_sorted = [](std::vector<double>& x) {
    std::sort(x.begin(), x.end());
    x.erase(
        std::unique(x.begin(), x.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
        x.end());
  };
  unique_sorted(g.u);
  unique_sorted(g.v);
  g.solid.assign(g.u.size() - 1, std::vector<bool>(g.v.size() - 1, true));
  for (std::size_t i = 0; i + 1 < g.u.size(); ++i) {
    for (std::size_t j = 0; j + 1 < g.v.size(); ++j) {
      const double uc = (g.u[i] + g.u[i + 1]) / 2, vc = (g.v[j] + g.v[j + 1]) / 2;
      for (const Opening& o : wall.openings) {
        if (uc > o.start && uc < o.start + o.width && vc > wall.z0 + o.sill &&
            vc < wall.z0 + o.sill + o.height)
          g.solid[i][j] = false;
      }
    }
  }
  return g;
}

// --- tessellation -----------------------------------------------------------------------

namespace {

class TriangleSink {
 public:
  explicit TriangleSink(SceneTriangles& out) : out_(out) {}

  std::uint32_t vertex(const Eigen::Vector3d& p) {
    out_.vertices.push_back(p.cast<float>());
    return static_cast<std::uint32_t>(out_.vertices.size() - 1);
  }
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, PartRef part) {
    out_.triangles.push_back({a, b, c});
    out_.parts.push_back(part);
  }
  // Quad a-b-c-d (a ring); oriented so that its normal points along `outward`.
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
            const Eigen::Vector3d& outward, PartRef part) {
    const Eigen::Vector3d pa = out_.vertices[a].cast<double>(),
                          pb = out_.vertices[b].cast<double>(),
                          pc = out_.vertices[c].cast<double>();
    if ((pb - pa).cross(pc - pa).dot(outward) < 0) std::swap(b, d);
    triangle(a, b, c, part);
    triangle(a, c, d, part);
  }

 private:
  SceneTriangles& out_;
};

void add_wall(TriangleSink& sink, const Wall& wall, PartRef part) {
  const WallGrid g = wall_grid(wall);
  const std::size_t nu = g.u.size(), nv = g.v.size();
  const Eigen::Vector2d d = wall.direction(), n = wall.normal();
  const Eigen::Vector3d d3(d.x(), d.y(), 0), n3(n.x(), n.y(), 0), z3 = Eigen::Vector3d::UnitZ();
  // One vertex per (side, u break, v break): every face below is a union of grid
  // rectangles, so neighbouring faces share edges exactly (no T-junctions).
  std::vector<std::uint32_t> vid(2 * nu * nv);
  for (int s = 0; s < 2; ++s)
    for (std::size_t i = 0; i < nu; ++i)
      for (std::size_t j = 0; j < nv; ++j) {
        const Eigen::Vector2d xy = wall.from + d * g.u[i] + n * ((s ? 0.5 : -0.5) * wall.thickness);
        vid[(s * nu + i) * nv + j] = sink.vertex({xy.x(), xy.y(), g.v[j]});
      }
  auto V = [&](int s, std::size_t i, std::size_t j) { return vid[(s * nu + i) * nv + j]; };
  for (std::size_t i = 0; i + 1 < nu; ++i)
    for (std::size_t j = 0; j + 1 < nv; ++j) {
      if (!g.solid[i][j]) continue;
      sink.quad(V(1, i, j), V(1, i + 1, j), V(1, i + 1, j + 1), V(1, i, j + 1), n3, part);
      sink.quad(V(0, i, j), V(0, i + 1, j), V(0, i + 1, j + 1), V(0, i, j + 1), -n3, part);
    }
  // Faces across the thickness wherever a solid cell meets a hole or the outside.
  for (std::size_t i = 0; i < nu; ++i)
    for (std::size_t j = 0; j + 1 < nv; ++j) {
      const bool before = g.solid_at(static_cast<long>(i) - 1, static_cast<long>(j));
      const bool after = g.solid_at(static_cast<long>(i), static_cast<long>(j));
      if (before == after) continue;
      sink.quad(V(0, i, j), V(1, i, j), V(1, i, j + 1), V(0, i, j + 1), before ? d3 : -d3, part);
    }
  for (std::size_t j = 0; j < nv; ++j)
    for (std::size_t i = 0; i + 1 < nu; ++i) {
      const bool below = g.solid_at(static_cast<long>(i), static_cast<long>(j) - 1);
      const bool above = g.solid_at(static_cast<long>(i), static_cast<long>(j));
      if (below == above) continue;
      sink.quad(V(0, i, j), V(1, i, j), V(1, i + 1, j), V(0, i + 1, j), below ? z3 : -z3, part);
    }
}

// Vertical prism over a polygon, caps by ear clipping.
void add_prism(TriangleSink& sink, std::vector<Eigen::Vector2d> polygon, double z0, double z1,
               PartRef part) {
  if (signed_area(polygon) < 0) std::reverse(polygon.begin(), polygon.end());
  const std::size_t n = polygon.size();
  std::vector<std::uint32_t> bottom(n), top(n);
  for (std::size_t i = 0; i < n; ++i) {
    bottom[i] = sink.vertex({polygon[i].x(), polygon[i].y(), z0});
    top[i] = sink.vertex({polygon[i].x(), polygon[i].y(), z1});
  }
  for (const auto& t : triangulate_polygon(polygon)) {
    sink.triangle(top[t[0]], top[t[1]], top[t[2]], part);
    sink.triangle(bottom[t[0]], bottom[t[2]], bottom[t[1]], part);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = (i + 1) % n;
    const Eigen::Vector2d e = polygon[k] - polygon[i];
    sink.quad(bottom[i], bottom[k], top[k], top[i], {e.y(), -e.x(), 0}, part);
  }
}

void add_box(TriangleSink& sink, const Box& box, PartRef part) {
  const double yaw = box.yaw_deg * M_PI / 180.0;
  const Eigen::Vector3d ax(std::cos(yaw), std::sin(yaw), 0), ay(-std::sin(yaw), std::cos(yaw), 0),
      az = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d h = box.size / 2;
  std::uint32_t v[8];
  for (int k = 0; k < 8; ++k) {
    const double sx = (k & 1) ? 1 : -1, sy = (k & 2) ? 1 : -1, sz = (k & 4) ? 1 : -1;
    v[k] = sink.vertex(box.center + sx * h.x() * ax + sy * h.y() * ay + sz * h.z() * az);
  }
  sink.quad(v[0], v[2], v[6], v[4], -ax, part);
  sink.quad(v[1], v[3], v[7], v[5], ax, part);
  sink.quad(v[0], v[1], v[5], v[4], -ay, part);
  sink.quad(v[2], v[3], v[7], v[6], ay, part);
  sink.quad(v[0], v[1], v[3], v[2], -az, part);
  sink.quad(v[4], v[5], v[7], v[6], az, part);
}

void add_cylinder(TriangleSink& sink, const Cylinder& c, double max_error, PartRef part) {
  const std::vector<Eigen::Vector2d> ring = cylinder_polygon(c, max_error);
  const std::size_t n = ring.size();
  // Fans from the axis rather than ear clipping: no sliver triangles on the caps.
  const std::uint32_t cb = sink.vertex({c.center.x(), c.center.y(), c.z0});
  const std::uint32_t ct = sink.vertex({c.center.x(), c.center.y(), c.z1});
  std::vector<std::uint32_t> bottom(n), top(n);
  for (std::size_t i = 0; i < n; ++i) {
    bottom[i] = sink.vertex({ring[i].x(), ring[i].y(), c.z0});
    top[i] = sink.vertex({ring[i].x(), ring[i].y(), c.z1});
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = (i + 1) % n;
    sink.triangle(ct, top[i], top[k], part);
    sink.triangle(cb, bottom[k], bottom[i], part);
    const Eigen::Vector2d e = ring[k] - ring[i];
    sink.quad(bottom[i], bottom[k], top[k], top[i], {e.y(), -e.x(), 0}, part);
  }
}

}  // namespace

SceneTriangles tessellate(const Scene& scene, double max_cylinder_error) {
  SceneTriangles out;
  TriangleSink sink(out);
  for (std::size_t i = 0; i < scene.walls.size(); ++i)
    add_wall(sink, scene.walls[i], {PartKind::wall, static_cast<int>(i)});
  for (std::size_t i = 0; i < scene.slabs.size(); ++i)
    add_prism(sink, scene.slabs[i].polygon, scene.slabs[i].z0, scene.slabs[i].z1,
              {PartKind::slab, static_cast<int>(i)});
  for (std::size_t i = 0; i < scene.boxes.size(); ++i)
    add_box(sink, scene.boxes[i], {PartKind::box, static_cast<int>(i)});
  for (std::size_t i = 0; i < scene.cylinders.size(); ++i)
    add_cylinder(sink, scene.cylinders[i], max_cylinder_error,
                 {PartKind::cylinder, static_cast<int>(i)});
  for (std::size_t i = 0; i < scene.meshes.size(); ++i) {
    const MeshInstance& m = scene.meshes[i];
    const std::uint32_t base = static_cast<std::uint32_t>(out.vertices.size());
    for (const Eigen::Vector3d& v : m.mesh.vertices) sink.vertex(m.to_world(v));
    for (const Eigen::Vector3i& t : m.mesh.triangles)
      sink.triangle(base + static_cast<std::uint32_t>(t[0]),
                    base + static_cast<std::uint32_t>(t[1]),
                    base + static_cast<std::uint32_t>(t[2]), {PartKind::mesh, static_cast<int>(i)});
  }
  return out;
}

}  // namespace semioctree::sim
