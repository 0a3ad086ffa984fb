#include "semioctree/nbv/candidates.h"

#include <dynamicEDT3D/dynamicEDT3D.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <unordered_set>
#include <utility>

#include "blind_zone.h"
#include "label_roles.h"
#include "plane_grid.h"

namespace semioctree {

namespace {

using nbv_detail::blind_octant;
using nbv_detail::coarse_columns;
using nbv_detail::free_space;
using nbv_detail::Plane;
using nbv_detail::plane_over;

// Key of a leaf cell, packed for a hash set.
std::uint64_t packed_cell(const octomap::OcTreeKey& k) {
  return (std::uint64_t(k[0]) << 32) | (std::uint64_t(k[1]) << 16) | std::uint64_t(k[2]);
}

// The leaf cells of unknown or occluded specks enclosed in free space (NbvParams::
// enclosed_speck_leaves, docs/nbv.md): face-connected components of unknown or
// occluded octants, every one at most `max_leaves` leaves a side, that fit in a cube
// of `max_leaves` leaves and whose face neighbours outside the component are all free
// space (empty, out, door or window; no occupied leaf, nothing outside the map), but for
// the floor's leaves under it (rays grazing the floor leave gaps just above it). Only
// components reaching a leaf layer below `layers` are looked at.
std::unordered_set<std::uint64_t> enclosed_specks(const SemiOcTree& tree, std::int64_t layers,
                                                  int max_leaves) {
  std::unordered_set<std::uint64_t> specks, not_specks;
  if (max_leaves <= 0) return specks;
  const unsigned k = tree.leaf_level();
  auto unobserved = [](Label l) { return l == Label::kUnknown || l == Label::kOccluded; };
  auto carved = [](Label l) {
    return free_space(l) || l == Label::kOut || l == Label::kDoor || l == Label::kWindow;
  };
  tree.for_each_octant([&](const Octant& o) {
    const std::int64_t size = std::int64_t(1) << (k - o.level);
    if (!unobserved(o.label()) || size > max_leaves || leaf_cell(o.key.k[2]) >= layers) return;
    if (specks.count(packed_cell(o.key)) || not_specks.count(packed_cell(o.key))) return;
    // Flood the component through leaf cells; stop as soon as it is no speck.
    std::vector<octomap::OcTreeKey> todo;
    std::unordered_set<std::uint64_t> seen;
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = hi[a] = o.key.k[a];
    bool speck = true;
    auto add = [&](const Octant& x) {  // every leaf cell of octant x
      const int n = 1 << (k - x.level);
      for (int dz = 0; dz < n; ++dz)
        for (int dy = 0; dy < n; ++dy)
          for (int dx = 0; dx < n; ++dx) {
            octomap::OcTreeKey c = x.key;
            c.k[0] = octomap::key_type(c.k[0] + dx);
            c.k[1] = octomap::key_type(c.k[1] + dy);
            c.k[2] = octomap::key_type(c.k[2] + dz);
            if (!seen.insert(packed_cell(c)).second) continue;
            todo.push_back(c);
            for (int b = 0; b < 3; ++b) {
              lo[b] = std::min<std::int64_t>(lo[b], c.k[b]);
              hi[b] = std::max<std::int64_t>(hi[b], c.k[b]);
              speck = speck && hi[b] - lo[b] < max_leaves;
            }
          }
    };
    add(o);
    while (speck && !todo.empty()) {
      const octomap::OcTreeKey c = todo.back();
      todo.pop_back();
      for (int a = 0; a < 3 && speck; ++a)
        for (int d = -1; d <= 1 && speck; d += 2) {
          octomap::OcTreeKey n = c;
          n.k[a] = octomap::key_type(int(n.k[a]) + d);
          if (seen.count(packed_cell(n))) continue;
          const std::optional<Octant> on = tree.find_octant(n);
          if (!on || !on->node)
            speck = false;  // the map's edge: nothing carved beyond
          else if (carved(on->label()))
            continue;
          else if (a == 2 && d < 0 && on->label() == Label::kOccupied && leaf_cell(n.k[2]) <= 0)
            continue;  // the floor under it (its layer, z = 0 after levelling)
          else if (!unobserved(on->label()) || (std::int64_t(1) << (k - on->level)) > max_leaves)
            speck = false;  // an occupied leaf, or unobserved space too large
          else
            add(*on);
        }
    }
    (speck ? specks : not_specks).insert(seen.begin(), seen.end());
  });
  return specks;
}

// 1 for each cell whose column holds an obstacle for the safety cylinder: the
// border (outside the map is unknown space), columns without coarse voxels, and
// occupied, unknown or occluded (unless blind, with the rule on) octants in
// z ∈ [clearance, top). Counts the blind octants exempted in `rep`.
std::vector<std::uint8_t> obstacle_columns(const SemiOcTree& tree, const Plane& plane,
                                           const RobotGeometry& robot,
                                           const std::vector<Point3>& past_scans,
                                           const NbvParams& params, CandidateReport& rep) {
  const double r = tree.leaf_size();
  const unsigned k = tree.leaf_level();
  const std::int64_t span = std::int64_t(1) << k;
  const int nx = plane.nx, ny = plane.ny;
  std::vector<std::uint8_t> obstacle(plane.cells(), 0);
  for (int x = 0; x < nx; ++x) obstacle[plane.index(x, 0)] = obstacle[plane.index(x, ny - 1)] = 1;
  for (int y = 0; y < ny; ++y) obstacle[plane.index(0, y)] = obstacle[plane.index(nx - 1, y)] = 1;
  // The robot stood at every past scan position: nothing else stands in the cylinder it
  // filled there (a static scene), whatever the scans could see of it. Cells whose centre
  // lies within the robot's radius of a past position are no obstacle unless a return
  // fell in them (docs/nbv.md, "The robot's own footprint").
  std::vector<std::uint8_t> footprint(plane.cells(), 0);
  const double radius_cells = robot.radius / r;
  for (const Point3& s : past_scans) {
    const double sx = s.x / r - 0.5, sy = s.y / r - 0.5;  // in cell indices
    const auto x_lo = std::int64_t(std::ceil(sx - radius_cells)),
               x_hi = std::int64_t(std::floor(sx + radius_cells));
    const auto y_lo = std::int64_t(std::ceil(sy - radius_cells)),
               y_hi = std::int64_t(std::floor(sy + radius_cells));
    for (std::int64_t y = std::max(y_lo, plane.y0); y <= std::min(y_hi, plane.y0 + ny - 1); ++y)
      for (std::int64_t x = std::max(x_lo, plane.x0); x <= std::min(x_hi, plane.x0 + nx - 1); ++x)
        if ((double(x) - sx) * (double(x) - sx) + (double(y) - sy) * (double(y) - sy) <=
            radius_cells * radius_cells)
          footprint[plane.index(int(x - plane.x0), int(y - plane.y0))] = 1;
  }
  auto mark = [&](std::int64_t cx, std::int64_t cy, std::int64_t size, bool occupied = true) {
    for (std::int64_t y = cy; y < cy + size; ++y)
      for (std::int64_t x = cx; x < cx + size; ++x) {
        const std::size_t i = plane.index(int(x - plane.x0), int(y - plane.y0));
        if (occupied || !footprint[i]) obstacle[i] = 1;
      }
  };

  // Leaf layers of the cylinder: z ∈ [0, top); octants lying wholly below the
  // ground clearance, or within the floor's own leaf layer, are driven over.
  const CoarseIndex &lo = plane.lo, &hi = plane.hi;
  const std::int64_t layers =
      std::max<std::int64_t>(1, std::llround(std::ceil(robot.top() / r - 1e-9)));
  const double clearance = floor_layer_clearance(robot, r) / r + 1e-9;   // in cells
  const std::int64_t first_layer = std::int64_t(std::floor(clearance));  // its lowest layer
  for (int cx = lo.x; cx <= hi.x; ++cx)
    for (int cy = lo.y; cy <= hi.y; ++cy)
      for (std::int64_t cz = 0; cz <= (layers - 1) >> k; ++cz)
        if (double((cz + 1) * span) > clearance && !tree.find_coarse({cx, cy, int(cz)}))
          mark(cx * span, cy * span, span);
  const detail::ScannerLimits limits(params.limits);
  const std::unordered_set<std::uint64_t> specks =
      enclosed_specks(tree, layers, params.enclosed_speck_leaves);
  tree.for_each_octant([&](const Octant& o) {
    const std::int64_t size = std::int64_t(1) << (k - o.level);
    const std::int64_t z = leaf_cell(o.key.k[2]);
    if (z >= layers || double(z + size) <= clearance) return;
    const Label l = o.label();
    if (l == Label::kOccluded) {
      if (params.blind_zone_is_free &&
          blind_octant(o, k, first_layer, layers - 1, past_scans, limits)) {
        ++rep.blind_octants_freed;
        return;
      }
    } else if (l != Label::kOccupied && l != Label::kUnknown) {
      return;
    }
    if (l != Label::kOccupied && specks.count(packed_cell(o.key))) {
      rep.specks_freed += std::size_t(size * size * size);
      return;
    }
    mark(leaf_cell(o.key.k[0]), leaf_cell(o.key.k[1]), size, l == Label::kOccupied);
  });
  return obstacle;
}

// 1 for each cell with no obstacle cell centre within radius + leaf/2 of its
// centre (dynamicEDT3D on the one-layer obstacle map).
std::vector<std::uint8_t> clear_cells(const std::vector<std::uint8_t>& obstacle, const Plane& plane,
                                      double radius, double r) {
  const int nx = plane.nx, ny = plane.ny;
  const double reach = (radius + 0.5 * r) / r;  // in cells
  const int max_cells = static_cast<int>(std::ceil(reach)) + 2;
  DynamicEDT3D edt(max_cells * max_cells);
  edt.initializeEmpty(nx, ny, 1, true);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      if (obstacle[plane.index(x, y)]) edt.occupyCell(x, y, 0);
  edt.update(false);
  std::vector<std::uint8_t> clear(obstacle.size(), 0);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      clear[plane.index(x, y)] = double(edt.getSQCellDistance(x, y, 0)) > reach * reach;
  return clear;
}

// The length of the shortest path from the robot's cell to each cell through clear
// cells (the robot's own cell always counts), in cells: steps to the 8 neighbours, a
// diagonal one only when both cells beside it are clear (the robot does not cut a
// corner), so the cells reached are those 4-connected to the robot's. Infinity for the
// others, and everywhere when the robot stands outside the map. `routes` (if given) gets
// each cell's previous one.
std::vector<float> path_lengths(const SemiOcTree& tree, const Plane& plane,
                                const Point3& robot_position,
                                const std::vector<std::uint8_t>& clear, CandidateReport& rep,
                                RouteTree* routes) {
  constexpr float kNone = std::numeric_limits<float>::infinity();
  std::vector<float> dist(clear.size(), kNone);
  if (routes) {
    *routes = RouteTree{tree.leaf_size(), plane.x0, plane.y0, plane.nx, plane.ny, -1, {}};
    routes->previous.assign(clear.size(), -1);
  }
  octomap::OcTreeKey rk;
  if (!tree.key_of(robot_position, rk)) return dist;
  const std::int64_t rx = leaf_cell(rk.k[0]) - plane.x0;
  const std::int64_t ry = leaf_cell(rk.k[1]) - plane.y0;
  if (!(rx > 0 && ry > 0 && rx < plane.nx - 1 && ry < plane.ny - 1)) return dist;
  rep.robot_in_map = true;
  using Item = std::pair<float, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  const std::size_t start = plane.index(int(rx), int(ry));
  if (routes) routes->start = std::int64_t(start);
  dist[start] = 0;
  queue.push({0.0f, start});
  const auto nx = std::ptrdiff_t(plane.nx);
  const float diagonal = float(std::sqrt(2.0));
  while (!queue.empty()) {
    const float d = queue.top().first;
    const std::size_t i = queue.top().second;
    queue.pop();
    if (d > dist[i]) continue;
    const auto step = [&](std::ptrdiff_t offset, float length) {
      const std::size_t j = std::size_t(std::ptrdiff_t(i) + offset);
      if (!clear[j] || d + length >= dist[j]) return;
      dist[j] = d + length;
      if (routes) routes->previous[j] = std::int32_t(i);
      queue.push({dist[j], j});
    };
    // The border cells are never clear: no neighbour lies off the plane.
    const bool e = clear[i + 1], w = clear[i - 1], n = clear[std::size_t(std::ptrdiff_t(i) + nx)],
               s = clear[std::size_t(std::ptrdiff_t(i) - nx)];
    step(1, 1.0f), step(-1, 1.0f), step(nx, 1.0f), step(-nx, 1.0f);
    if (e && n) step(nx + 1, diagonal);
    if (w && n) step(nx - 1, diagonal);
    if (e && s) step(-nx + 1, diagonal);
    if (w && s) step(-nx - 1, diagonal);
  }
  return dist;
}

}  // namespace

std::vector<Point3> RouteTree::route_to(const Point3& to) const {
  std::vector<Point3> route;
  const std::int64_t x = std::int64_t(std::floor(to.x / leaf)) - x0;
  const std::int64_t y = std::int64_t(std::floor(to.y / leaf)) - y0;
  if (start < 0 || x < 0 || y < 0 || x >= nx || y >= ny) return route;
  std::int64_t i = y * nx + x;
  if (i != start && previous[std::size_t(i)] < 0) return route;
  std::vector<std::int64_t> cells{i};
  while (i != start) cells.push_back(i = previous[std::size_t(i)]);
  std::reverse(cells.begin(), cells.end());
  const auto centre = [&](std::int64_t c) {
    return Point3((double(c % nx + x0) + 0.5) * leaf, (double(c / nx + y0) + 0.5) * leaf, to.z);
  };
  // Only the cells where the step changes: the start, the turns, the end.
  for (std::size_t k = 0; k < cells.size(); ++k)
    if (k == 0 || k + 1 == cells.size() || cells[k] - cells[k - 1] != cells[k + 1] - cells[k])
      route.push_back(centre(cells[k]));
  return route;
}

double floor_layer_clearance(const RobotGeometry& robot, double leaf_size) {
  if (!(robot.ground_clearance > 0)) return 0.0;  // no clearance: the floor layer counts too
  return std::max(robot.ground_clearance, leaf_size);
}

PlatformBody platform_body(const RobotGeometry& robot, double leaf_size) {
  PlatformBody body;
  body.radius = robot.radius;
  body.below = robot.scanner_height - floor_layer_clearance(robot, leaf_size);
  body.above = robot.top_margin;
  return body;
}

std::vector<Point3> find_candidates(const SemiOcTree& tree, const RobotGeometry& robot,
                                    const Point3& robot_position,
                                    const std::vector<Point3>& past_scans, const NbvParams& params,
                                    CandidateReport* report, std::vector<double>* path_m,
                                    RouteTree* routes) {
  CandidateReport rep;
  std::vector<Point3> out;
  if (path_m) path_m->clear();
  if (routes) *routes = RouteTree{};
  if (report) *report = rep;
  if (tree.coarse_count() == 0) return out;
  if (!(robot.radius >= 0) || !(robot.scanner_height > 0) || !(robot.top() > 0))
    throw std::invalid_argument("RobotGeometry: radius >= 0 and scanner height > 0 required");
  const double r = tree.leaf_size();

  const Plane plane = plane_over(tree);
  const std::vector<std::uint8_t> obstacle =
      obstacle_columns(tree, plane, robot, past_scans, params, rep);
  const std::vector<std::uint8_t> clear = clear_cells(obstacle, plane, robot.radius, r);
  const std::vector<float> path = path_lengths(tree, plane, robot_position, clear, rep, routes);

  // The candidate grid: every m-th leaf cell (world-aligned), at its centre.
  const std::int64_t m = std::max<std::int64_t>(1, std::llround(params.candidate_spacing / r));
  std::int64_t off_x = m / 2, off_y = m / 2;  // grid points: leaf cells ≡ off (mod m)
  if (params.grid_anchor) {
    octomap::OcTreeKey ak;
    if (!tree.key_of(Point3(params.grid_anchor->x, params.grid_anchor->y, 0.0), ak))
      throw std::invalid_argument("NbvParams: the candidate grid's anchor is beyond the key range");
    off_x = ((leaf_cell(ak.k[0])) % m + m) % m;
    off_y = ((leaf_cell(ak.k[1])) % m + m) % m;
  }
  auto first_on_grid = [&](std::int64_t v, std::int64_t off) {  // smallest g >= v, g ≡ off
    std::int64_t d = v - off;
    std::int64_t q = d >= 0 ? (d + m - 1) / m : -((-d) / m);
    return off + q * m;
  };
  // One position (grid point or doorway) tested: where it stands, whether it may, whether
  // the robot fits and reaches it, whether a scan stood there.
  auto consider = [&](const Point3& p, bool doorway) {
    const auto o = tree.find_octant(p);
    const bool stands = o && (free_space(o->label()) ||
                              (params.stand_beyond_openings && o->label() == Label::kOut) ||
                              (doorway && o->label() == Label::kDoor));
    if (!stands) {
      ++rep.not_empty;
      return;
    }
    if (params.may_stand && !params.may_stand(p)) {
      ++rep.outside_area;
      return;
    }
    octomap::OcTreeKey key;
    tree.key_of(p, key);
    const std::size_t i =
        plane.index(int(leaf_cell(key.k[0]) - plane.x0), int(leaf_cell(key.k[1]) - plane.y0));
    if (!clear[i]) {
      ++rep.cylinder_blocked;
      return;
    }
    if (!std::isfinite(path[i])) {
      ++rep.unreachable;
      return;
    }
    const auto scanned_here = [&](const Point3& c) { return std::hypot(c.x - p.x, c.y - p.y) < r; };
    if (std::any_of(past_scans.begin(), past_scans.end(), scanned_here)) {
      ++rep.already_scanned;
      return;
    }
    ++rep.feasible;
    out.push_back(p);
    if (path_m) path_m->push_back(double(path[i]) * r);
  };
  const std::int64_t x0 = plane.x0, y0 = plane.y0;
  for (std::int64_t gy = first_on_grid(y0 + 1, off_y); gy < y0 + plane.ny - 1; gy += m)
    for (std::int64_t gx = first_on_grid(x0 + 1, off_x); gx < x0 + plane.nx - 1; gx += m) {
      ++rep.grid_points;
      consider(Point3((double(gx) + 0.5) * r, (double(gy) + 0.5) * r, robot.scanner_height), false);
    }
  for (const Point3& d : params.doorways) {
    // Inside the plane's border (its cells are never clear), at its leaf cell's centre.
    octomap::OcTreeKey key;
    if (!tree.key_of(Point3(d.x, d.y, robot.scanner_height), key)) continue;
    const std::int64_t cx = leaf_cell(key.k[0]), cy = leaf_cell(key.k[1]);
    if (cx <= x0 || cy <= y0 || cx >= x0 + plane.nx - 1 || cy >= y0 + plane.ny - 1) continue;
    ++rep.doorways;
    consider(Point3((double(cx) + 0.5) * r, (double(cy) + 0.5) * r, robot.scanner_height), true);
  }
  if (report) *report = rep;
  return out;
}

}  // namespace semioctree
