// Closed-form ray entry and containment tests for the scene's solids.
#include "semioctree/sim/solids.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "semioctree/sim/geometry.h"

namespace semioctree::sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string label(const char* kind, std::size_t i, const std::string& name = "") {
  std::string s = std::string(kind) + "[" + std::to_string(i) + "]";
  if (!name.empty()) s += " \"" + name + "\"";
  return s;
}

// Slab test on one axis: narrows [t0, t1] to where |o + t d| <= h.
bool clip_axis(double o, double d, double h, double& t0, double& t1) {
  if (std::abs(d) < 1e-15) return std::abs(o) <= h;
  double a = (-h - o) / d, b = (h - o) / d;
  if (a > b) std::swap(a, b);
  t0 = std::max(t0, a);
  t1 = std::min(t1, b);
  return t0 <= t1;
}

// Möller–Trumbore in double precision; returns t or +inf.
double ray_triangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-18) return kInf;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) * inv;
  if (u < 0 || u > 1) return kInf;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0 || u + v > 1) return kInf;
  const double t = e2.dot(q) * inv;
  return t >= 0 ? t : kInf;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Signed solid angle of triangle abc seen from p (Van Oosterom & Strackee).
double solid_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                   const Eigen::Vector3d& c) {
  const Eigen::Vector3d x = a - p, y = b - p, z = c - p;
  const double lx = x.norm(), ly = y.norm(), lz = z.norm();
  const double num = x.dot(y.cross(z));
  const double den = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
  return 2.0 * std::atan2(num, den);
}

bool ray_hits_aabb(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                   const Eigen::Vector3d& hi, double t_max) {
  double t0 = 0, t1 = t_max;
  const Eigen::Vector3d c = (lo + hi) / 2, h = (hi - lo) / 2;
  for (int k = 0; k < 3; ++k)
    if (!clip_axis(o[k] - c[k], d[k], h[k], t0, t1)) return false;
  return true;
}

}  // namespace

SolidModel::SolidModel(const Scene& scene) {
  for (std::size_t i = 0; i < scene.walls.size(); ++i) {
    const Wall& w = scene.walls[i];
    const WallGrid g = wall_grid(w);
    const Eigen::Vector2d d = w.direction(), n = w.normal();
    for (std::size_t a = 0; a + 1 < g.u.size(); ++a)
      for (std::size_t b = 0; b + 1 < g.v.size(); ++b) {
        if (!g.solid[a][b]) continue;
        const Eigen::Vector2d c = w.from + d * ((g.u[a] + g.u[a + 1]) / 2);
        boxes_.push_back({{c.x(), c.y(), (g.v[b] + g.v[b + 1]) / 2},
                          {(g.u[a + 1] - g.u[a]) / 2, w.thickness / 2, (g.v[b + 1] - g.v[b]) / 2},
                          {d.x(), d.y(), 0},
                          {n.x(), n.y(), 0},
                          label("walls", i)});
      }
  }
  for (std::size_t i = 0; i < scene.boxes.size(); ++i) {
    const Box& b = scene.boxes[i];
    const double yaw = b.yaw_deg * M_PI / 180.0;
    boxes_.push_back({b.center,
                      b.size / 2,
                      {std::cos(yaw), std::sin(yaw), 0},
                      {-std::sin(yaw), std::cos(yaw), 0},
                      label("boxes", i, b.name)});
  }
  auto add_prism = [&](std::vector<Eigen::Vector2d> polygon, double z0, double z1,
                       std::string name) {
    Prism p{std::move(polygon),
            z0,
            z1,
            Eigen::Vector2d::Constant(kInf),
            Eigen::Vector2d::Constant(-kInf),
            std::move(name)};
    for (const auto& q : p.polygon) {
      p.min_xy = p.min_xy.cwiseMin(q);
      p.max_xy = p.max_xy.cwiseMax(q);
    }
    prisms_.push_back(std::move(p));
  };
  for (std::size_t i = 0; i < scene.slabs.size(); ++i)
    add_prism(scene.slabs[i].polygon, scene.slabs[i].z0, scene.slabs[i].z1, label("slabs", i));
  for (std::size_t i = 0; i < scene.cylinders.size(); ++i) {
    const Cylinder& c = scene.cylinders[i];
    add_prism(cylinder_polygon(c), c.z0, c.z1, label("cylinders", i, c.name));
  }
  index_boxes();
  for (std::size_t i = 0; i < scene.meshes.size(); ++i) {
    const MeshInstance& m = scene.meshes[i];
    TriangleSet set;
    set.min_corner = Eigen::Vector3d::Constant(kInf);
    set.max_corner = Eigen::Vector3d::Constant(-kInf);
    std::vector<Eigen::Vector3d> world;
    world.reserve(m.mesh.vertices.size());
    for (const auto& v : m.mesh.vertices) {
      world.push_back(m.to_world(v));
      set.min_corner = set.min_corner.cwiseMin(world.back());
      set.max_corner = set.max_corner.cwiseMax(world.back());
    }
    for (const auto& t : m.mesh.triangles) {
      set.a.push_back(world[static_cast<std::size_t>(t[0])]);
      set.b.push_back(world[static_cast<std::size_t>(t[1])]);
      set.c.push_back(world[static_cast<std::size_t>(t[2])]);
    }
    set.name = label("meshes", i, m.file);
    meshes_.push_back(std::move(set));
  }
}

std::optional<double> SolidModel::first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                            double t_max) const {
  double best = kInf;
  for (const OrientedBox& b : boxes_) {
    const Eigen::Vector3d r = o - b.center;
    double t0 = 0, t1 = std::min(best, t_max);
    if (!clip_axis(r.z(), d.z(), b.half.z(), t0, t1)) continue;
    if (!clip_axis(r.dot(b.axis_u), d.dot(b.axis_u), b.half.x(), t0, t1)) continue;
    if (!clip_axis(r.dot(b.axis_v), d.dot(b.axis_v), b.half.y(), t0, t1)) continue;
    best = std::min(best, t0);
  }
  for (const Prism& p : prisms_) {
    // Quick reject on the prism's bounding box.
    const Eigen::Vector3d lo(p.min_xy.x(), p.min_xy.y(), p.z0),
        hi(p.max_xy.x(), p.max_xy.y(), p.z1);
    if (!ray_hits_aabb(o, d, lo, hi, std::min(best, t_max))) continue;
    const Eigen::Vector2d o2(o.x(), o.y()), d2(d.x(), d.y());
    if (o.z() > p.z0 && o.z() < p.z1 && point_in_polygon(p.polygon, o2)) return 0.0;
    for (double z : {p.z0, p.z1}) {  // caps
      if (std::abs(d.z()) < 1e-15) break;
      const double t = (z - o.z()) / d.z();
      if (t >= 0 && t < best && point_in_polygon(p.polygon, o2 + t * d2)) best = t;
    }
    for (std::size_t i = 0; i < p.polygon.size(); ++i) {  // sides
      const Eigen::Vector2d a = p.polygon[i], e = p.polygon[(i + 1) % p.polygon.size()] - a;
      const double den = d2.x() * e.y() - d2.y() * e.x();
      if (std::abs(den) < 1e-15) continue;
      const Eigen::Vector2d w = a - o2;
      const double t = (w.x() * e.y() - w.y() * e.x()) / den;
      const double s = (w.x() * d2.y() - w.y() * d2.x()) / den;
      if (t < 0 || t >= best || s < 0 || s > 1) continue;
      const double z = o.z() + t * d.z();
      if (z >= p.z0 && z <= p.z1) best = t;
    }
  }
  for (const TriangleSet& m : meshes_) {
    if (!ray_hits_aabb(o, d, m.min_corner, m.max_corner, std::min(best, t_max))) continue;
    for (std::size_t i = 0; i < m.a.size(); ++i)
      best = std::min(best, ray_triangle(o, d, m.a[i], m.b[i], m.c[i]));
  }
  if (best <= t_max) return best;
  return std::nullopt;
}

void SolidModel::index_boxes() {
  // Cells of 1 m, or fewer where the boxes spread over more than 512 m.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(kInf), hi = -lo;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> bounds;
  for (const OrientedBox& b : boxes_) {
    const Eigen::Vector2d half(
        std::abs(b.axis_u.x()) * b.half.x() + std::abs(b.axis_v.x()) * b.half.y(),
        std::abs(b.axis_u.y()) * b.half.x() + std::abs(b.axis_v.y()) * b.half.y());
    const Eigen::Vector2d c = b.center.head<2>();
    bounds.emplace_back(c - half, c + half);
    lo = lo.cwiseMin(c - half);
    hi = hi.cwiseMax(c + half);
  }
  BoxGrid& g = box_grid_;
  if (boxes_.empty()) return;
  g.cell = std::max(1.0, (hi - lo).maxCoeff() / 512.0);
  g.origin = lo;
  g.nx = static_cast<int>((hi.x() - lo.x()) / g.cell) + 1;
  g.ny = static_cast<int>((hi.y() - lo.y()) / g.cell) + 1;
  g.boxes.assign(static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny), {});
  const auto cell_of = [&](double v, double o, int n) {
    return std::clamp(static_cast<int>(std::floor((v - o) / g.cell)), 0, n - 1);
  };
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    const int x0 = cell_of(bounds[i].first.x(), lo.x(), g.nx),
              x1 = cell_of(bounds[i].second.x(), lo.x(), g.nx),
              y0 = cell_of(bounds[i].first.y(), lo.y(), g.ny),
              y1 = cell_of(bounds[i].second.y(), lo.y(), g.ny);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        g.boxes[static_cast<std::size_t>(y) * static_cast<std::size_t>(g.nx) +
                static_cast<std::size_t>(x)]
            .push_back(static_cast<std::uint32_t>(i));
  }
}

const std::vector<std::uint32_t>* SolidModel::BoxGrid::at(const Eigen::Vector2d& p) const {
  const double fx = std::floor((p.x() - origin.x()) / cell),
               fy = std::floor((p.y() - origin.y()) / cell);
  if (!(fx >= 0 && fy >= 0 && fx < nx && fy < ny)) return nullptr;
  return &boxes[static_cast<std::size_t>(fy) * static_cast<std::size_t>(nx) +
                static_cast<std::size_t>(fx)];
}

std::string SolidModel::solid_containing(const Eigen::Vector3d& p, double margin,
                                         bool with_meshes) const {
  const auto inside = [&](const OrientedBox& b) {
    const Eigen::Vector3d r = p - b.center;
    return std::abs(r.z()) < b.half.z() - margin &&
           std::abs(r.dot(b.axis_u)) < b.half.x() - margin &&
           std::abs(r.dot(b.axis_v)) < b.half.y() - margin;
  };
  if (margin >= 0) {  // inside a box deeper than margin ≥ 0: inside its bounds' cell
    if (const std::vector<std::uint32_t>* near = box_grid_.at(p.head<2>()))
      for (std::uint32_t i : *near)
        if (inside(boxes_[i])) return boxes_[i].name;
  } else {
    for (const OrientedBox& b : boxes_)
      if (inside(b)) return b.name;
  }
  for (const Prism& q : prisms_) {
    if (!(p.z() > q.z0 + margin && p.z() < q.z1 - margin)) continue;
    const Eigen::Vector2d p2(p.x(), p.y());
    if (p2.x() < q.min_xy.x() || p2.y() < q.min_xy.y() || p2.x() > q.max_xy.x() ||
        p2.y() > q.max_xy.y())
      continue;
    if (point_in_polygon(q.polygon, p2) && distance_to_boundary(q.polygon, p2) > margin)
      return q.name;
  }
  if (!with_meshes) return {};
  for (const TriangleSet& m : meshes_) {
    if ((p.array() < m.min_corner.array()).any() || (p.array() > m.max_corner.array()).any())
      continue;
    double winding = 0, nearest = kInf;
    for (std::size_t i = 0; i < m.a.size(); ++i) {
      winding += solid_angle(p, m.a[i], m.b[i], m.c[i]);
      if (margin > 0)
        nearest = std::min(nearest, (closest_on_triangle(p, m.a[i], m.b[i], m.c[i]) - p).norm());
    }
    // Generalized winding number: 1 inside a closed surface, 0 outside; robust to parts
    // of the mesh that overlap.
    if (winding / (4 * M_PI) > 0.5 && (margin <= 0 || nearest > margin)) return m.name;
  }
  return {};
}

}  // namespace semioctree::sim
