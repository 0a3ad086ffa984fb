// Ground truth of a scene: openings, surface samples, visibility, floor plan.
#include "semioctree/sim/ground_truth.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <queue>
#include <random>
#include <stdexcept>

namespace semioctree::sim {

std::vector<OpeningRect> opening_rects(const Scene& scene) {
  std::vector<OpeningRect> out;
  for (std::size_t w = 0; w < scene.walls.size(); ++w) {
    const Wall& wall = scene.walls[w];
    for (std::size_t i = 0; i < wall.openings.size(); ++i) {
      const Opening& o = wall.openings[i];
      OpeningRect r;
      r.kind = o.kind;
      r.wall = static_cast<int>(w);
      r.index = static_cast<int>(i);
      const auto corners = opening_corners(wall, o);
      std::copy(corners.begin(), corners.end(), r.corners.begin());
      r.width = o.width;
      r.height = o.height;
      r.normal = {wall.normal().x(), wall.normal().y(), 0.0};
      out.push_back(r);
    }
  }
  return out;
}

namespace {

// Samples at the centres of a grid of about `spacing` over the rectangle
// origin + [0, len1]·e1 + [0, len2]·e2.
// The samplers hand each sample to `emit` (a callable taking a SurfaceSample), in an order
// fixed by the part alone.
template <class Emit>
void sample_rect(const Eigen::Vector3d& origin, const Eigen::Vector3d& e1, double len1,
                 const Eigen::Vector3d& e2, double len2, const Eigen::Vector3d& normal,
                 double spacing, PartRef part, Emit& emit) {
  if (len1 <= 0 || len2 <= 0) return;
  const int n1 = std::max(1, static_cast<int>(std::lround(len1 / spacing)));
  const int n2 = std::max(1, static_cast<int>(std::lround(len2 / spacing)));
  for (int i = 0; i < n1; ++i)
    for (int j = 0; j < n2; ++j)
      emit(SurfaceSample{origin + e1 * (len1 * (i + 0.5) / n1) + e2 * (len2 * (j + 0.5) / n2),
                         normal, part});
}

template <class Emit>
void sample_wall(const Wall& wall, double spacing, PartRef part, Emit& emit) {
  const WallGrid g = wall_grid(wall);
  const std::size_t nu = g.u.size(), nv = g.v.size();
  const Eigen::Vector2d d2 = wall.direction(), n2 = wall.normal();
  const Eigen::Vector3d d(d2.x(), d2.y(), 0), n(n2.x(), n2.y(), 0), z = Eigen::Vector3d::UnitZ();
  auto point = [&](double u, double side, double v) {
    const Eigen::Vector2d xy = wall.from + d2 * u + n2 * (side * wall.thickness / 2);
    return Eigen::Vector3d(xy.x(), xy.y(), v);
  };
  // Same faces as the tessellation: both sides of each solid cell, and the faces across
  // the thickness where a solid cell meets a hole or the outside (ends, jambs, sills, top).
  for (std::size_t i = 0; i + 1 < nu; ++i)
    for (std::size_t j = 0; j + 1 < nv; ++j) {
      if (!g.solid[i][j]) continue;
      const double du = g.u[i + 1] - g.u[i], dv = g.v[j + 1] - g.v[j];
      sample_rect(point(g.u[i], 1, g.v[j]), d, du, z, dv, n, spacing, part, emit);
      sample_rect(point(g.u[i], -1, g.v[j]), d, du, z, dv, -n, spacing, part, emit);
    }
  for (std::size_t i = 0; i < nu; ++i)
    for (std::size_t j = 0; j + 1 < nv; ++j) {
      const bool before = g.solid_at(static_cast<long>(i) - 1, static_cast<long>(j));
      if (before == g.solid_at(static_cast<long>(i), static_cast<long>(j))) continue;
      sample_rect(point(g.u[i], -1, g.v[j]), n, wall.thickness, z, g.v[j + 1] - g.v[j],
                  before ? d : -d, spacing, part, emit);
    }
  for (std::size_t j = 0; j < nv; ++j)
    for (std::size_t i = 0; i + 1 < nu; ++i) {
      const bool below = g.solid_at(static_cast<long>(i), static_cast<long>(j) - 1);
      if (below == g.solid_at(static_cast<long>(i), static_cast<long>(j))) continue;
      sample_rect(point(g.u[i], -1, g.v[j]), d, g.u[i + 1] - g.u[i], n, wall.thickness,
                  below ? z : -z, spacing, part, emit);
    }
}

template <class Emit>
void sample_box(const Box& b, double spacing, PartRef part, Emit& emit) {
  const double yaw = b.yaw_deg * M_PI / 180.0;
  const Eigen::Vector3d axes[3] = {
      {std::cos(yaw), std::sin(yaw), 0}, {-std::sin(yaw), std::cos(yaw), 0}, {0, 0, 1}};
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    for (double s : {-1.0, 1.0}) {
      const Eigen::Vector3d corner = b.center + s * axes[k] * b.size[k] / 2 -
                                     axes[k1] * b.size[k1] / 2 - axes[k2] * b.size[k2] / 2;
      sample_rect(corner, axes[k1], b.size[k1], axes[k2], b.size[k2], s * axes[k], spacing, part,
                  emit);
    }
  }
}

template <class Emit>
void sample_cylinder(const Cylinder& c, double spacing, PartRef part, Emit& emit) {
  const double h = c.z1 - c.z0;
  const int n_theta = std::max(3, static_cast<int>(std::lround(2 * M_PI * c.radius / spacing)));
  const int n_z = std::max(1, static_cast<int>(std::lround(h / spacing)));
  for (int i = 0; i < n_theta; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / n_theta;
    const Eigen::Vector3d radial(std::cos(a), std::sin(a), 0);
    for (int j = 0; j < n_z; ++j)
      emit(SurfaceSample{Eigen::Vector3d(c.center.x(), c.center.y(), c.z0 + h * (j + 0.5) / n_z) +
                             c.radius * radial,
                         radial, part});
  }
  // Caps: rings of equal width, each with points about `spacing` apart.
  const int n_rings = std::max(1, static_cast<int>(std::lround(c.radius / spacing)));
  for (int k = 0; k < n_rings; ++k) {
    const double r = c.radius * (k + 0.5) / n_rings;
    const int n = std::max(1, static_cast<int>(std::lround(2 * M_PI * r / spacing)));
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * (i + 0.5) / n;
      const Eigen::Vector2d xy = c.center + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      emit(SurfaceSample{{xy.x(), xy.y(), c.z1}, Eigen::Vector3d::UnitZ(), part});
      emit(SurfaceSample{{xy.x(), xy.y(), c.z0}, -Eigen::Vector3d::UnitZ(), part});
    }
  }
}

template <class Emit>
void sample_mesh(const MeshInstance& m, double spacing, PartRef part, Emit& emit) {
  // Uniform random points, as many per triangle as its area asks for; the fraction left
  // over carries to the next triangle so that small triangles are not all skipped.
  std::mt19937_64 rng(0x5eed0000u + static_cast<unsigned>(part.index));
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  double carry = 0;
  for (const auto& t : m.mesh.triangles) {
    const Eigen::Vector3d a = m.to_world(m.mesh.vertices[static_cast<std::size_t>(t[0])]);
    const Eigen::Vector3d b = m.to_world(m.mesh.vertices[static_cast<std::size_t>(t[1])]);
    const Eigen::Vector3d c = m.to_world(m.mesh.vertices[static_cast<std::size_t>(t[2])]);
    const Eigen::Vector3d cr = (b - a).cross(c - a);
    const double area = cr.norm() / 2;
    if (area <= 0) continue;
    carry += area / (spacing * spacing);
    const Eigen::Vector3d normal = cr.normalized();
    for (; carry >= 1; carry -= 1) {
      double u = uniform(), v = uniform();
      if (u + v > 1) u = 1 - u, v = 1 - v;
      emit(SurfaceSample{a + u * (b - a) + v * (c - a), normal, part});
    }
  }
}

// Every sample of the scene's surfaces, buried ones included, in a fixed order.
template <class Emit>
void each_sample(const Scene& scene, double spacing, Emit& emit) {
  for (std::size_t i = 0; i < scene.walls.size(); ++i)
    sample_wall(scene.walls[i], spacing, {PartKind::wall, static_cast<int>(i)}, emit);
  for (std::size_t i = 0; i < scene.boxes.size(); ++i)
    sample_box(scene.boxes[i], spacing, {PartKind::box, static_cast<int>(i)}, emit);
  for (std::size_t i = 0; i < scene.cylinders.size(); ++i)
    sample_cylinder(scene.cylinders[i], spacing, {PartKind::cylinder, static_cast<int>(i)}, emit);
  for (std::size_t i = 0; i < scene.meshes.size(); ++i)
    sample_mesh(scene.meshes[i], spacing, {PartKind::mesh, static_cast<int>(i)}, emit);
}

// Samples buried in another solid are dropped: just outside the surface must be free.
bool exposed(const SolidModel& solids, const SurfaceSample& s, double spacing) {
  const double offset = std::min(0.005, spacing / 4);
  return !solids.contains(s.position + offset * s.normal, 0.0, false);
}

}  // namespace

std::vector<SurfaceSample> surface_samples(const Scene& scene, double spacing) {
  // Two passes over the same samples, the first to judge and count them, so that the
  // result is allocated once at its size.
  const SolidModel solids(scene);
  std::vector<bool> kept_flags;
  std::size_t kept = 0;
  auto judge = [&](const SurfaceSample& s) {
    kept_flags.push_back(exposed(solids, s, spacing));
    kept += kept_flags.back();
  };
  each_sample(scene, spacing, judge);
  std::vector<SurfaceSample> out;
  out.reserve(kept);
  std::size_t next = 0;
  auto keep_exposed = [&](const SurfaceSample& s) {
    if (kept_flags[next++]) out.push_back(s);
  };
  each_sample(scene, spacing, keep_exposed);
  return out;
}

void for_each_surface_sample(const Scene& scene, double spacing,
                             const std::function<void(const SurfaceSample&)>& f) {
  const SolidModel solids(scene);
  auto emit_exposed = [&](const SurfaceSample& s) {
    if (exposed(solids, s, spacing)) f(s);
  };
  each_sample(scene, spacing, emit_exposed);
}

std::vector<SurfaceSample> surface_samples_at(const Scene& scene, double spacing,
                                              const std::vector<std::uint32_t>& indices,
                                              std::size_t* total) {
  if (!std::is_sorted(indices.begin(), indices.end()))
    throw std::invalid_argument("surface_samples_at: the indices must be ascending");
  std::vector<SurfaceSample> out;
  out.reserve(indices.size());
  std::size_t index = 0;
  for_each_surface_sample(scene, spacing, [&](const SurfaceSample& s) {
    while (out.size() < indices.size() && indices[out.size()] == index) out.push_back(s);
    ++index;
  });
  if (total) *total = index;
  return out;
}

GroundTruth::GroundTruth(const Scene& scene)
    : scene_(scene),
      triangles_(tessellate(scene)),
      caster_(make_ray_caster(triangles_)),
      solids_(scene) {}

bool GroundTruth::segment_free(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  const double len = (b - a).norm();
  if (len <= 0.002) return true;
  const Eigen::Vector3d dir = (b - a) / len;
  return !caster_->segment_blocked((a + 0.001 * dir).cast<float>(),
                                   (b - 0.001 * dir).cast<float>());
}

bool GroundTruth::standing_free(const Eigen::Vector2d& p) const {
  const double r = scene_.robot.radius, h = scene_.scanner.height, z0 = 0.02;
  auto at = [&](const Eigen::Vector2d& q, double z) { return Eigen::Vector3d(q.x(), q.y(), z); };
  if (solids_.contains(at(p, z0))) return false;
  // Vertical lines on two rings and the axis, and spokes at a few heights: an object in
  // the robot's cylinder crosses at least one of them unless it is smaller than their gaps.
  std::vector<Eigen::Vector2d> ring;
  for (double radius : {r, r / 2})
    for (int i = 0; i < 16; ++i) {
      const double a = 2 * M_PI * i / 16;
      ring.push_back(p + radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
  if (!segment_free(at(p, z0), at(p, h))) return false;
  for (const auto& q : ring) {
    if (!segment_free(at(q, z0), at(q, h))) return false;
  }
  for (double z : {z0, 0.25, 0.5, 0.75, 1.0, 1.25, h})
    for (int i = 0; i < 16; ++i)
      if (!segment_free(at(p, std::min(z, h)),
                        at(ring[static_cast<std::size_t>(i)], std::min(z, h))))
        return false;
  return true;
}

std::ptrdiff_t FloorPlan::index_of(const Eigen::Vector2d& p, int dx, int dy) const {
  const int ix = static_cast<int>(std::floor((p.x() - origin.x()) / cell)) + dx;
  const int iy = static_cast<int>(std::floor((p.y() - origin.y()) / cell)) + dy;
  if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) return -1;
  return static_cast<std::ptrdiff_t>(iy) * nx + ix;
}

bool FloorPlan::reachable_near(const Eigen::Vector2d& p) const {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const std::ptrdiff_t k = index_of(p, dx, dy);
      if (k >= 0 && reachable[static_cast<std::size_t>(k)]) return true;
    }
  return false;
}

bool FloorPlan::in_survey_area(const Eigen::Vector2d& p) const {
  const std::ptrdiff_t k = index_of(p);
  return k >= 0 && survey[static_cast<std::size_t>(k)];
}

int FloorPlan::room_at(const Eigen::Vector2d& p) const {
  const std::ptrdiff_t k = index_of(p);
  return k >= 0 ? room[static_cast<std::size_t>(k)] : -1;
}

namespace {

// 4-connected components of cells where `open` holds; returns a label per cell (-1 where
// closed) and the cell count of each component.
std::vector<int> components(int nx, int ny, const std::vector<bool>& open,
                            std::vector<std::size_t>& sizes, std::vector<bool>& touches_border) {
  std::vector<int> label(open.size(), -1);
  for (int start = 0; start < nx * ny; ++start) {
    if (!open[static_cast<std::size_t>(start)] || label[static_cast<std::size_t>(start)] >= 0)
      continue;
    const int id = static_cast<int>(sizes.size());
    sizes.push_back(0);
    touches_border.push_back(false);
    std::queue<int> q;
    q.push(start);
    label[static_cast<std::size_t>(start)] = id;
    while (!q.empty()) {
      const int c = q.front();
      q.pop();
      ++sizes.back();
      const int x = c % nx, y = c / nx;
      if (x == 0 || y == 0 || x == nx - 1 || y == ny - 1) touches_border.back() = true;
      const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& n : nb) {
        if (n[0] < 0 || n[1] < 0 || n[0] >= nx || n[1] >= ny) continue;
        const int k = n[1] * nx + n[0];
        if (open[static_cast<std::size_t>(k)] && label[static_cast<std::size_t>(k)] < 0) {
          label[static_cast<std::size_t>(k)] = id;
          q.push(k);
        }
      }
    }
  }
  return label;
}

}  // namespace

FloorPlan GroundTruth::floor_plan(double cell) const {
  FloorPlan plan;
  plan.cell = cell;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& v : triangles_.vertices) {
    lo = lo.cwiseMin(v.head<2>().cast<double>());
    hi = hi.cwiseMax(v.head<2>().cast<double>());
  }
  lo = lo.cwiseMin(scene_.robot.start);
  hi = hi.cwiseMax(scene_.robot.start);
  plan.origin = lo - Eigen::Vector2d::Constant(2 * cell);  // a free margin all round
  // Each wall visits every cell: a scene spread over kilometres (a stray object
  // far away) would take minutes and gigabytes before failing.
  const double cells_x = std::ceil((hi.x() - plan.origin.x()) / cell) + 2,
               cells_y = std::ceil((hi.y() - plan.origin.y()) / cell) + 2;
  if (!(cells_x * cells_y <= kMaxFloorPlanCells)) {
    char msg[300];
    std::snprintf(msg, sizeof msg,
                  "the scene spans %.1f x %.1f m: its floor plan at %g m cells would have %.3g "
                  "cells (at most %.3g); is an object placed far away by mistake?",
                  hi.x() - lo.x(), hi.y() - lo.y(), cell, cells_x * cells_y, kMaxFloorPlanCells);
    throw std::invalid_argument(msg);
  }
  plan.nx = static_cast<int>(cells_x);
  plan.ny = static_cast<int>(cells_y);
  const std::size_t n = static_cast<std::size_t>(plan.nx) * static_cast<std::size_t>(plan.ny);
  auto centre = [&](int ix, int iy) -> Eigen::Vector2d {
    return plan.origin + cell * Eigen::Vector2d(ix + 0.5, iy + 0.5);
  };

  // Rooms: regions enclosed by wall footprints (openings count as wall).
  std::vector<bool> open(n, true);
  for (const Wall& w : scene_.walls) {
    const Eigen::Vector2d d = w.direction(), nrm = w.normal();
    // A cell is wall if its centre is in the footprint. Two 4-neighbours are at most one
    // cell apart across the wall, so a wall thinner than a cell is widened to one cell
    // (else the flood fill would leak through it).
    const double grow = std::max(0.0, (cell - w.thickness) / 2 + 1e-9);
    for (int iy = 0; iy < plan.ny; ++iy)
      for (int ix = 0; ix < plan.nx; ++ix) {
        const Eigen::Vector2d q = centre(ix, iy) - w.from;
        const double u = q.dot(d), t = q.dot(nrm);
        if (u >= -grow && u <= w.length() + grow && std::abs(t) <= w.thickness / 2 + grow)
          open[static_cast<std::size_t>(iy) * plan.nx + ix] = false;
      }
  }
  std::vector<std::size_t> sizes;
  std::vector<bool> border;
  const std::vector<int> comp = components(plan.nx, plan.ny, open, sizes, border);
  std::vector<int> rooms;  // component ids of enclosed regions, by decreasing size
  for (std::size_t c = 0; c < sizes.size(); ++c)
    if (!border[c] && !scene_.walls.empty()) rooms.push_back(static_cast<int>(c));
  std::stable_sort(rooms.begin(), rooms.end(), [&](int a, int b) { return sizes[a] > sizes[b]; });
  std::vector<int> room_of_comp(sizes.size(), -1);
  for (std::size_t r = 0; r < rooms.size(); ++r) {
    room_of_comp[static_cast<std::size_t>(rooms[r])] = static_cast<int>(r);
    plan.room_area.push_back(static_cast<double>(sizes[static_cast<std::size_t>(rooms[r])]) * cell *
                             cell);
  }
  plan.room.assign(n, -1);
  for (std::size_t k = 0; k < n; ++k)
    if (comp[k] >= 0) plan.room[k] = room_of_comp[static_cast<std::size_t>(comp[k])];
  plan.start_room = plan.room_at(scene_.robot.start);

  // Free floor: something to stand on just below z = 0, nothing from there up to the
  // scanner; then keep the robot's radius from anything else, and what is reachable.
  plan.reachable.assign(n, false);
  {
    const double h = scene_.scanner.height;
    std::vector<bool> free(n, false);
    for (int iy = 0; iy < plan.ny; ++iy)
      for (int ix = 0; ix < plan.nx; ++ix) {
        const Eigen::Vector2d c = centre(ix, iy);
        const Eigen::Vector3d low(c.x(), c.y(), 0.02);
        const bool floor =
            caster_->segment_blocked(low.cast<float>(), Eigen::Vector3f(c.x(), c.y(), -0.05f));
        free[static_cast<std::size_t>(iy) * plan.nx + ix] =
            floor && !solids_.contains(low, 0.0, false) &&
            !caster_->segment_blocked(low.cast<float>(),
                                      Eigen::Vector3f(c.x(), c.y(), static_cast<float>(h)));
      }
    const int reach = static_cast<int>(std::ceil(scene_.robot.radius / cell));
    std::vector<bool> stand(n, false);
    for (int iy = 0; iy < plan.ny; ++iy)
      for (int ix = 0; ix < plan.nx; ++ix) {
        bool ok = free[static_cast<std::size_t>(iy) * plan.nx + ix];
        for (int dy = -reach; dy <= reach && ok; ++dy)
          for (int dx = -reach; dx <= reach && ok; ++dx) {
            if ((dx * dx + dy * dy) * cell * cell > scene_.robot.radius * scene_.robot.radius)
              continue;
            const int x = ix + dx, y = iy + dy;
            if (x < 0 || y < 0 || x >= plan.nx || y >= plan.ny ||
                !free[static_cast<std::size_t>(y) * plan.nx + x])
              ok = false;
          }
        stand[static_cast<std::size_t>(iy) * plan.nx + ix] = ok;
      }
    std::vector<std::size_t> s_sizes;
    std::vector<bool> s_border;
    const std::vector<int> reachable = components(plan.nx, plan.ny, stand, s_sizes, s_border);
    // The start's component; a start that stands clear (standing_free) may still have its
    // cell centre a hair too close to something on this grid: then a neighbour's.
    const std::ptrdiff_t k0 = plan.index_of(scene_.robot.start);
    int start_comp = k0 >= 0 ? reachable[static_cast<std::size_t>(k0)] : -1;
    for (int dy = -1; dy <= 1 && start_comp < 0; ++dy)
      for (int dx = -1; dx <= 1 && start_comp < 0; ++dx) {
        const std::ptrdiff_t k = plan.index_of(scene_.robot.start, dx, dy);
        if (k >= 0) start_comp = reachable[static_cast<std::size_t>(k)];
      }
    if (start_comp >= 0)
      for (std::size_t k = 0; k < n; ++k) plan.reachable[k] = reachable[k] == start_comp;
  }
  if (scene_.survey_area) {
    plan.survey.assign(n, false);
    for (int iy = 0; iy < plan.ny; ++iy)
      for (int ix = 0; ix < plan.nx; ++ix)
        plan.survey[static_cast<std::size_t>(iy) * plan.nx + ix] =
            point_in_polygon(*scene_.survey_area, centre(ix, iy));
  } else {
    plan.survey = plan.reachable;
  }
  plan.survey_area_m2 =
      static_cast<double>(std::count(plan.survey.begin(), plan.survey.end(), true)) * cell * cell;
  return plan;
}

}  // namespace semioctree::sim
