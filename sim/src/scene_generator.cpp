// Generated single-room scenes (docs/generated-scenes.md): the room's outline, its walls
// with doors and windows, a ring of outside space, then obstacles placed one by one, each
// kept only if it keeps the rules (clearances from walls, other obstacles and the zones
// in front of openings); last the robot's start on free floor.
#include "semioctree/sim/scene_generator.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include "semioctree/sim/geometry.h"

namespace semioctree::sim {

using json = nlohmann::ordered_json;
using Vec2 = Eigen::Vector2d;
using Polygon = std::vector<Vec2>;

const char* to_string(GeneratedKind kind) {
  switch (kind) {
    case GeneratedKind::room:
      return "room";
    case GeneratedKind::l_shape:
      return "l-shape";
    case GeneratedKind::hall:
      return "hall";
    default:
      return "any";
  }
}

std::vector<std::string> generated_kind_names() {
  return {"any", "room", "l-shape", "hall"};
}

GeneratedKind generated_kind_from_string(const std::string& name) {
  for (GeneratedKind k :
       {GeneratedKind::any, GeneratedKind::room, GeneratedKind::l_shape, GeneratedKind::hall})
    if (name == to_string(k)) return k;
  throw std::invalid_argument("unknown scene kind '" + name +
                              "': expected any, room, l-shape or hall");
}

namespace {

// Uniform numbers from the engine's raw output (the standard fixes mt19937_64's sequence
// but not its distributions' algorithms).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double unit() { return double(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double real(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int integer(int lo, int hi) {  // [lo, hi]
    return lo + std::min(hi - lo, int(unit() * double(hi - lo + 1)));
  }
  bool chance(double p) { return unit() < p; }

 private:
  std::mt19937_64 engine_;
};

// The seed's stream for the kind of `any`, apart from the scene's own stream, so that
// `--kind K` and the `any` draw that gives K make the same scene.
GeneratedKind draw_kind(std::uint64_t seed) {
  Draw d(seed ^ 0x9e3779b97f4a7c15ULL);
  const double u = d.unit();
  return u < 0.4 ? GeneratedKind::room : u < 0.7 ? GeneratedKind::l_shape : GeneratedKind::hall;
}

double mm(double x) {
  return std::round(x * 1000.0) / 1000.0;
}
std::string num(double x, int decimals = 1) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, x);
  return text;
}
json xy(const Vec2& p) {
  return json::array({mm(p.x()), mm(p.y())});
}
json polygon_json(const Polygon& poly) {
  json a = json::array();
  for (const Vec2& p : poly) a.push_back(xy(p));
  return a;
}

double cross2(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

// Distance between two closed polygons' areas: 0 if they overlap.
double polygon_distance(const Polygon& a, const Polygon& b) {
  if (point_in_polygon(a, b[0]) || point_in_polygon(b, a[0])) return 0.0;
  double best = 1e18;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Vec2 &a0 = a[i], &a1 = a[(i + 1) % a.size()];
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Vec2 &b0 = b[j], &b1 = b[(j + 1) % b.size()];
      if (segments_cross(a0, a1, b0, b1)) return 0.0;
      best = std::min({best, point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1),
                       point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1)});
    }
  }
  return best;
}

// An oriented rectangle in the floor plane.
struct Footprint {
  Vec2 centre = Vec2::Zero();
  double length = 0, depth = 0;  // along the yaw direction, across
  double yaw_deg = 0;

  Polygon corners() const {
    const double a = yaw_deg * M_PI / 180.0;
    const Vec2 u(std::cos(a), std::sin(a)), v(-u.y(), u.x());
    const Vec2 hu = 0.5 * length * u, hv = 0.5 * depth * v;
    return {centre - hu - hv, centre + hu - hv, centre + hu + hv, centre - hu + hv};
  }
};

// The room's outline (counter-clockwise, interior faces of the walls).
struct Outline {
  Polygon polygon;
  double width = 0, depth = 0;  // bounding box [0, width] × [0, depth]
};

struct Generator {
  Draw draw;
  GeneratedKind kind;
  std::uint64_t seed;

  Outline room;
  double height = 0, wall_thickness = 0, robot_radius = 0, scanner_height = 0;
  double passage = 0;  // free width left between obstacles: the robot's diameter and 0.3 m
  bool ceiling = true;
  // Obstacles (their footprints) and zones nothing may stand in: in front of openings,
  // and (for obstacles reaching its underside) under the mezzanine.
  std::vector<Polygon> obstacles, keep_out;
  std::optional<Polygon> mezzanine_footprint;
  double mezzanine_underside = 0;

  json walls = json::array(), slabs = json::array(), boxes = json::array(),
       cylinders = json::array();
  std::vector<std::string> summary;

  Generator(std::uint64_t s, GeneratedKind k) : draw(s), kind(k), seed(s) {}

  json run();
  void make_outline();
  void make_walls_and_openings();
  void make_outside_and_slabs();
  void make_mezzanine();
  void make_columns();
  void make_wall_furniture();
  void make_free_furniture();
  json make_robot();
  json make_scanner();

  Vec2 outward(std::size_t edge) const {
    const Vec2 d = edge_direction(edge);
    return {d.y(), -d.x()};
  }
  Vec2 edge_direction(std::size_t edge) const {
    const Polygon& p = room.polygon;
    return (p[(edge + 1) % p.size()] - p[edge]).normalized();
  }
  double edge_length(std::size_t edge) const {
    const Polygon& p = room.polygon;
    return (p[(edge + 1) % p.size()] - p[edge]).norm();
  }
  // True if `fp` lies inside the room at least `clearance` from its walls, `clearance`
  // from every obstacle and outside every keep-out zone; the zone under the mezzanine
  // only for footprints reaching `top` above its underside.
  bool fits(const Polygon& fp, double clearance_to_walls, double clearance, double top) const {
    for (const Vec2& v : fp)
      if (!point_in_polygon(room.polygon, v) ||
          distance_to_boundary(room.polygon, v) < clearance_to_walls - 1e-9)
        return false;
    for (const Vec2& v : room.polygon) {  // a reflex corner poking into the footprint
      if (point_in_polygon(fp, v)) return false;
      if (clearance_to_walls > 0 && distance_to_boundary(fp, v) < clearance_to_walls - 1e-9)
        return false;
    }
    for (const Polygon& o : obstacles)
      if (polygon_distance(fp, o) < clearance) return false;
    for (const Polygon& z : keep_out)
      if (polygon_distance(fp, z) <= 0.0) return false;
    if (mezzanine_footprint && top > mezzanine_underside - 0.05 &&
        polygon_distance(fp, *mezzanine_footprint) <= 0.05)
      return false;
    return true;
  }
  void add_box(const Vec2& c, double sx, double sy, double z0, double sz, double yaw_deg,
               const std::string& name) {
    json b = {{"center", {mm(c.x()), mm(c.y()), mm(z0 + 0.5 * sz)}},
              {"size", {mm(sx), mm(sy), mm(sz)}},
              {"name", name}};
    if (yaw_deg != 0.0) b["yaw_deg"] = mm(yaw_deg);
    boxes.push_back(b);
  }
  void add_cylinder(const Vec2& c, double r, double z0, double z1, const std::string& name) {
    cylinders.push_back(
        {{"center", xy(c)}, {"radius", mm(r)}, {"z0", mm(z0)}, {"z1", mm(z1)}, {"name", name}});
  }
  Vec2 random_point_in_room() {
    for (;;) {
      const Vec2 p(draw.real(0, room.width), draw.real(0, room.depth));
      if (point_in_polygon(room.polygon, p)) return p;
    }
  }
  double yaw_draw() { return draw.chance(0.7) ? 90.0 * draw.integer(0, 1) : draw.real(0, 180); }
};

void Generator::make_outline() {
  double w = 0, d = 0;
  if (kind == GeneratedKind::room) {
    w = draw.real(4, 14), d = draw.real(4, 12), height = draw.real(2.4, 3.6);
  } else if (kind == GeneratedKind::l_shape) {
    w = draw.real(6, 18), d = draw.real(6, 16), height = draw.real(2.4, 4.0);
  } else {
    w = draw.real(12, 20), d = draw.real(10, 20), height = draw.real(4.5, 6.0);
  }
  w = mm(w), d = mm(d), height = mm(height);
  room.width = w, room.depth = d;
  if (kind == GeneratedKind::l_shape) {
    // The notch takes the north-east corner; each arm stays at least 3 m wide.
    const double a = mm(std::min(draw.real(0.3, 0.6) * w, w - 3.0));
    const double b = mm(std::min(draw.real(0.3, 0.6) * d, d - 3.0));
    room.polygon = {{0, 0}, {w, 0}, {w, d - b}, {w - a, d - b}, {w - a, d}, {0, d}};
    summary.push_back("L-shaped room " + num(w) + " x " + num(d) + " m without its " + num(a) +
                      " x " + num(b) + " m north-east corner");
  } else {
    room.polygon = {{0, 0}, {w, 0}, {w, d}, {0, d}};
    summary.push_back(std::string(kind == GeneratedKind::hall ? "hall " : "room ") + num(w) +
                      " x " + num(d) + " m");
  }
  wall_thickness = std::round(draw.real(0.15, 0.3) * 50.0) / 50.0;  // whole 2 cm: t/2 in mm
  robot_radius = mm(draw.real(0.25, 0.8));
  scanner_height = mm(draw.real(1.0, 2.0));
  passage = 2 * robot_radius + 0.3;
  ceiling = !draw.chance(0.2);
  summary.push_back(num(height, 2) + " m high" + (ceiling ? "" : ", no ceiling slab"));
}

void Generator::make_walls_and_openings() {
  const Polygon& p = room.polygon;
  const std::size_t n = p.size();
  const double t = wall_thickness;
  // Centre lines: the outline offset outwards by t/2 (rectilinear: corner + both edges'
  // normals), each wall continued t/2 past its corners so that the corners close.
  std::vector<Vec2> centre_corner(n);
  for (std::size_t i = 0; i < n; ++i)
    centre_corner[i] = p[i] + 0.5 * t * (outward((i + n - 1) % n) + outward(i));
  struct Hole {
    std::string kind;
    double s0, s1;  // along the interior edge from its first corner
    double sill, height;
  };
  std::vector<std::vector<Hole>> holes(n);
  auto place = [&](const std::string& what, double width, double sill, double hole_height) {
    const double margin = 0.5, gap = 0.5;
    for (int attempt = 0; attempt < 60; ++attempt) {
      const std::size_t e = std::size_t(draw.integer(0, int(n) - 1));
      const double len = edge_length(e);
      if (len < width + 2 * margin) continue;
      const double s0 = mm(draw.real(margin, len - margin - width));
      const double s1 = s0 + width;
      bool clear = true;
      for (const Hole& h : holes[e]) clear = clear && (s1 + gap <= h.s0 || s0 >= h.s1 + gap);
      if (!clear) continue;
      // Nothing stands in front of it: a door's approach (deep enough to turn in), the
      // space in front of a window.
      const Vec2 d = edge_direction(e), in = -outward(e);
      const double side = what == "door" ? 0.2 : 0.1;
      const double depth = what == "door" ? std::max(1.2, passage) : 0.8;
      const Vec2 a = p[e] + d * (s0 - side), b = p[e] + d * (s1 + side);
      const Polygon zone{a, b, b + in * depth, a + in * depth};
      for (const Polygon& o : obstacles) clear = clear && polygon_distance(zone, o) > 0.0;
      // A hole reaching above the mezzanine's underside must not be under its slab.
      if (mezzanine_footprint && sill + hole_height > mezzanine_underside - 0.1) {
        const Polygon hole_line = Footprint{p[e] + d * (0.5 * (s0 + s1)), width, 0.002,
                                            std::atan2(d.y(), d.x()) * 180.0 / M_PI}
                                      .corners();
        clear = clear && polygon_distance(hole_line, *mezzanine_footprint) >= 0.3;
      }
      if (!clear) continue;
      holes[e].push_back({what, s0, s1, sill, hole_height});
      keep_out.push_back(zone);
      return true;
    }
    return false;
  };
  const int doors = draw.integer(0, 4), windows = draw.integer(0, 4);
  int placed_doors = 0, placed_windows = 0;
  for (int i = 0; i < doors; ++i) {
    const double width = mm(draw.real(0.8, 1.8));
    const double h = mm(std::min(draw.real(2.0, 2.4), height - 0.3));
    placed_doors += place("door", width, 0.0, h);
  }
  for (int i = 0; i < windows; ++i) {
    const double width = mm(draw.real(0.6, 2.5));
    const double sill = mm(draw.real(0.5, 1.2));
    const double h = mm(std::min(draw.real(0.6, 2.0), height - 0.3 - sill));
    placed_windows += place("window", width, sill, h);
  }
  summary.push_back(std::to_string(placed_doors) + " doors, " + std::to_string(placed_windows) +
                    " windows");
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    const Vec2 d = edge_direction(i);
    const Vec2 from = centre_corner[i] - 0.5 * t * d, to = centre_corner[j] + 0.5 * t * d;
    json w = {{"from", xy(from)}, {"to", xy(to)}, {"thickness", mm(t)}, {"z1", height}};
    // The interior corner p[i] lies at this distance along the wall from `from`.
    const double offset = (p[i] - from).dot(d);
    json openings = json::array();
    std::sort(holes[i].begin(), holes[i].end(),
              [](const Hole& a, const Hole& b) { return a.s0 < b.s0; });
    for (const Hole& h : holes[i]) {
      json o = {{"kind", h.kind},
                {"start", mm(offset + h.s0)},
                {"width", mm(h.s1 - h.s0)},
                {"height", mm(h.height)}};
      if (h.kind == "window") o["sill"] = mm(h.sill);
      openings.push_back(o);
    }
    if (!openings.empty()) w["openings"] = openings;
    walls.push_back(w);
  }
}

void Generator::make_outside_and_slabs() {
  // Outside space beyond every wall (a corridor, a yard): the openings look onto a floor
  // and, a few metres on, a closed ring of walls.
  const double t = wall_thickness;
  const double gap = mm(draw.real(1.5, 3.5));
  const double lo_x = -t - gap, lo_y = -t - gap, hi_x = room.width + t + gap,
               hi_y = room.depth + t + gap;
  const double ot = 0.2;
  const Vec2 c0(lo_x - ot / 2, lo_y - ot / 2), c1(hi_x + ot / 2, lo_y - ot / 2),
      c2(hi_x + ot / 2, hi_y + ot / 2), c3(lo_x - ot / 2, hi_y + ot / 2);
  const Vec2 ex(ot / 2, 0), ey(0, ot / 2);
  for (const auto& [a, b] : std::vector<std::pair<Vec2, Vec2>>{
           {c0 - ex, c1 + ex}, {c1 - ey, c2 + ey}, {c2 + ex, c3 - ex}, {c3 + ey, c0 - ey}})
    walls.push_back(
        {{"_", "outside"}, {"from", xy(a)}, {"to", xy(b)}, {"thickness", ot}, {"z1", height}});
  const Vec2 m(ot + 0.1, ot + 0.1);
  const Polygon ground{Vec2(lo_x, lo_y) - m, Vec2(hi_x, lo_y) + Vec2(m.x(), -m.y()),
                       Vec2(hi_x, hi_y) + m, Vec2(lo_x, hi_y) + Vec2(-m.x(), m.y())};
  slabs.push_back({{"_", "floor, inside and out"},
                   {"polygon", polygon_json(ground)},
                   {"z0", -0.2},
                   {"z1", 0.0}});
  if (ceiling) {
    // Over the room and its walls (the outline offset by the wall thickness).
    const Polygon& p = room.polygon;
    const std::size_t n = p.size();
    Polygon roof(n);
    for (std::size_t i = 0; i < n; ++i)
      roof[i] = p[i] + t * (outward((i + n - 1) % n) + outward(i));
    slabs.push_back(
        {{"_", "ceiling"}, {"polygon", polygon_json(roof)}, {"z0", height}, {"z1", mm(height + 0.2)}});
  }
}

void Generator::make_mezzanine() {
  // Halls always, other rooms high enough now and then: a slab along the south wall (the
  // first edge, full length in every outline) on legs along its free edge.
  const bool wanted = kind == GeneratedKind::hall || (height >= 3.4 && draw.chance(0.35));
  const double min_underside = std::max(2.4, scanner_height + 0.5);
  const double thickness = mm(draw.real(0.2, 0.3));
  if (!wanted || height - 1.5 - thickness < min_underside) return;
  const double underside = mm(draw.real(min_underside, height - 1.5 - thickness));
  // Its depth leaves the room's narrowest arm at least half open.
  const double arm = kind == GeneratedKind::l_shape ? room.polygon[2].y() : room.depth;
  const double depth = mm(std::min(draw.real(2.5, 6.0), 0.45 * arm));
  if (depth < 2.0) return;
  const double x0 = 0.01, x1 = room.width - 0.01;
  const Polygon slab{{x0, 0.01}, {x1, 0.01}, {x1, depth}, {x0, depth}};
  slabs.push_back({{"_", "mezzanine"},
                   {"polygon", polygon_json(slab)},
                   {"z0", underside},
                   {"z1", mm(underside + thickness)}});
  mezzanine_footprint = slab;
  mezzanine_underside = underside;
  // Legs along the free edge, a passage apart and a passage from the side walls.
  const double leg_r = mm(draw.real(0.08, 0.2));
  const double first = passage + leg_r, last = room.width - passage - leg_r;
  const double span = last - first;
  const int gaps = std::max(1, int(std::ceil(span / draw.real(3.0, 5.0))));
  const double step = span / gaps;
  if (step - 2 * leg_r < passage) return;  // cannot happen for halls ≥ 12 m
  for (int i = 0; i <= gaps; ++i) {
    const Vec2 c(first + i * step, depth - leg_r - 0.02);
    add_cylinder(c, leg_r, 0.0, underside, "mezzanine-leg-" + std::to_string(i + 1));
    obstacles.push_back(Footprint{c, 2 * leg_r, 2 * leg_r, 0}.corners());
  }
  summary.push_back("a mezzanine " + num(depth) + " m deep, its underside at " + num(underside, 2) +
                    " m");
}

void Generator::make_columns() {
  const double top = height;  // floor to ceiling (or the walls' top without one)
  auto try_column = [&](const Vec2& c, int index) {
    const bool round = draw.chance(0.6);
    const double r = mm(round ? draw.real(0.15, 0.35) : 0.5 * draw.real(0.3, 0.6));
    const Polygon fp = Footprint{c, 2 * r, 2 * r, 0}.corners();
    if (!fits(fp, passage, passage, top)) return false;
    const std::string name = "column-" + std::to_string(index);
    if (round)
      add_cylinder(c, r, 0.0, top, name);
    else
      add_box(c, 2 * r, 2 * r, 0.0, top, 0.0, name);
    obstacles.push_back(fp);
    return true;
  };
  int count = 0;
  if (kind == GeneratedKind::hall) {
    const double sx = draw.real(4.0, 7.0), sy = draw.real(4.0, 7.0);
    for (double x = sx; x < room.width - 1.0; x += sx)
      for (double y = sy; y < room.depth - 1.0; y += sy)
        count += try_column(Vec2(mm(x), mm(y)), count + 1);
  } else if (draw.chance(0.35)) {
    const int wanted = draw.integer(1, kind == GeneratedKind::l_shape ? 2 : 1);
    for (int i = 0, attempts = 0; i < wanted && attempts < 40; ++attempts)
      if (try_column(random_point_in_room(), count + 1)) ++i, ++count;
  }
  if (count) summary.push_back(std::to_string(count) + " columns");
}

void Generator::make_wall_furniture() {
  const Polygon& p = room.polygon;
  double perimeter = 0;
  for (std::size_t e = 0; e < p.size(); ++e) perimeter += edge_length(e);
  const int wanted = draw.integer(0, std::max(1, int(perimeter / 5.0)));
  int placed = 0;
  for (int i = 0, attempts = 0; i < wanted && attempts < 30 * wanted; ++attempts) {
    const bool cabinet = draw.chance(0.4);
    const double length = mm(cabinet ? draw.real(0.6, 1.2) : draw.real(1.0, 4.0));
    const double depth = mm(cabinet ? draw.real(0.4, 0.6) : draw.real(0.6, 0.9));
    const double h =
        mm(cabinet ? std::min(draw.real(1.8, 2.4), height - 0.2) : draw.real(0.75, 0.95));
    const std::size_t e = std::size_t(draw.integer(0, int(p.size()) - 1));
    const double len = edge_length(e);
    if (len < length + 0.1) continue;
    const double s = draw.real(0.05, len - 0.05 - length);
    const Vec2 d = edge_direction(e), in = -outward(e);
    const Vec2 c = p[e] + d * (s + 0.5 * length) + in * (0.01 + 0.5 * depth);
    const double yaw = std::atan2(d.y(), d.x()) * 180.0 / M_PI;
    const Polygon fp = Footprint{c, length, depth, yaw}.corners();
    if (!fits(fp, 0.0, passage, h)) continue;
    const std::string name = (cabinet ? "cabinet-" : "bench-") + std::to_string(placed + 1);
    add_box(c, length, depth, 0.0, h, std::fmod(yaw + 360.0, 180.0), name);
    obstacles.push_back(fp);
    ++i, ++placed;
  }
  if (placed) summary.push_back(std::to_string(placed) + " benches and cabinets along the walls");
}

void Generator::make_free_furniture() {
  double area = std::abs(signed_area(room.polygon));
  const double per = kind == GeneratedKind::hall ? 25.0 : 12.0;
  const int wanted = draw.integer(0, std::max(1, int(area / per)));
  int placed = 0;
  for (int i = 0, attempts = 0; i < wanted && attempts < 30 * wanted; ++attempts) {
    const int what = draw.integer(0, kind == GeneratedKind::hall ? 3 : 2);
    const Vec2 c = random_point_in_room();
    const double yaw = yaw_draw();
    const std::string index = std::to_string(placed + 1);
    if (what == 0) {  // a table on thin legs
      const double length = mm(draw.real(1.2, 2.4)), depth = mm(draw.real(0.6, 1.2));
      const double h = mm(draw.real(0.72, 0.78)), top = 0.04, leg = mm(draw.real(0.04, 0.06));
      const Footprint f{c, length, depth, yaw};
      const Polygon fp = f.corners();
      if (!fits(fp, passage, passage, h)) continue;
      add_box(c, length, depth, h - top, top, yaw, "table-" + index);
      const Footprint inner{c, length - 2 * leg - 0.04, depth - 2 * leg - 0.04, yaw};
      int k = 0;
      for (const Vec2& corner : inner.corners())
        add_box(corner, leg, leg, 0.0, h - top, yaw,
                "table-" + index + "-leg-" + std::to_string(++k));
      obstacles.push_back(fp);
    } else if (what == 1) {  // a pole: a lamp, a sign, a pipe
      const double r = mm(draw.real(0.03, 0.06)), h = mm(draw.real(1.0, std::min(2.5, height)));
      const Polygon fp = Footprint{c, 2 * r, 2 * r, 0}.corners();
      if (!fits(fp, passage, passage, h)) continue;
      add_cylinder(c, r, 0.0, h, "pole-" + index);
      obstacles.push_back(fp);
    } else if (what == 2) {  // a free-standing cabinet or crate
      const double sx = mm(draw.real(0.4, 1.2)), sy = mm(draw.real(0.4, 1.0));
      const double h = mm(draw.real(0.5, std::min(2.2, height - 0.2)));
      const Polygon fp = Footprint{c, sx, sy, yaw}.corners();
      if (!fits(fp, passage, passage, h)) continue;
      add_box(c, sx, sy, 0.0, h, yaw, "cabinet-free-" + index);
      obstacles.push_back(fp);
    } else {  // a machine: a base with a smaller block on it
      const double sx = mm(draw.real(1.0, 3.0)), sy = mm(draw.real(1.0, 2.5));
      const double h = mm(draw.real(0.8, 1.5)), h2 = mm(draw.real(0.4, 1.2));
      const Polygon fp = Footprint{c, sx, sy, yaw}.corners();
      if (!fits(fp, passage, passage, h + h2)) continue;
      add_box(c, sx, sy, 0.0, h, yaw, "machine-" + index);
      add_box(c, mm(0.5 * sx), mm(0.6 * sy), h, h2, yaw, "machine-" + index + "-top");
      obstacles.push_back(fp);
    }
    ++i, ++placed;
  }
  if (placed)
    summary.push_back(std::to_string(placed) + " free-standing tables, poles, cabinets" +
                      (kind == GeneratedKind::hall ? ", machines" : ""));
}

json Generator::make_robot() {
  // On free floor, its cylinder (and 0.15 m more) clear of walls, the columns and the
  // mezzanine's legs, and outside the zones in front of openings; then that square is
  // kept free of the furniture placed after. Columns stand a passage apart, so such a
  // point exists in every outline (each arm is at least 3 m wide).
  const double clear = robot_radius + 0.15;
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const Vec2 c(mm(draw.real(0, room.width)), mm(draw.real(0, room.depth)));
    const Polygon square = Footprint{c, 2 * clear, 2 * clear, 0}.corners();
    if (!fits(square, 0.0, 0.0, 0.0) || distance_to_boundary(room.polygon, c) < clear) continue;
    bool free = true;
    for (const Polygon& o : obstacles) free = free && polygon_distance(square, o) > 0.0;
    if (!free) continue;
    keep_out.push_back(square);
    return {
        {"start", xy(c)}, {"start_yaw_deg", mm(draw.real(-180, 180))}, {"radius", robot_radius}};
  }
  throw std::logic_error("scene generator: no free start for seed " + std::to_string(seed));
}

json Generator::make_scanner() {
  // Angular step: about 3 cm between neighbouring rays at the far side of the room (its
  // diagonal), kept between 0.1° and 0.15° (5.4 to 2.4 million rays a scan).
  const double diagonal = std::hypot(room.width, room.depth);
  const double step =
      std::round(std::clamp(0.03 / diagonal * 180.0 / M_PI, 0.1, 0.15) * 100.0) / 100.0;
  const double el_min = mm(draw.real(-90, -30)), el_max = mm(draw.real(30, 90));
  return {{"height", scanner_height},
          {"azimuth_step_deg", step},
          {"elevation_step_deg", step},
          {"elevation_min_deg", el_min},
          {"elevation_max_deg", el_max}};
}

json Generator::run() {
  make_outline();
  // The mezzanine before the openings (none cut into its slab), the obstacles after
  // them (none in their zones): columns, then the wall furniture, then the free one.
  make_mezzanine();
  make_walls_and_openings();
  make_outside_and_slabs();
  make_columns();
  // The start before the furniture, kept free of it: a start always exists.
  const json robot = make_robot();
  make_wall_furniture();
  make_free_furniture();
  const json scanner = make_scanner();
  std::ostringstream description;
  description << "Generated scene (seed " << seed << ", kind " << to_string(kind) << "): ";
  for (std::size_t i = 0; i < summary.size(); ++i) description << (i ? "; " : "") << summary[i];
  description << "; robot radius " << robot_radius << " m, scanner at " << scanner_height << " m.";
  json scene = {{"format", "semioctree-scene"},
                {"version", 1},
                {"name", std::string("gen-") + to_string(kind) + "-" + std::to_string(seed)},
                {"description", description.str()},
                {"walls", walls},
                {"slabs", slabs}};
  if (!boxes.empty()) scene["boxes"] = boxes;
  if (!cylinders.empty()) scene["cylinders"] = cylinders;
  scene["robot"] = robot;
  scene["scanner"] = scanner;
  scene["survey_area"] = polygon_json(room.polygon);
  return scene;
}

}  // namespace

GeneratedKind resolve_generated_kind(std::uint64_t seed, GeneratedKind kind) {
  return kind == GeneratedKind::any ? draw_kind(seed) : kind;
}

std::string generate_scene_json(std::uint64_t seed, GeneratedKind kind) {
  Generator g(seed, resolve_generated_kind(seed, kind));
  const json scene = g.run();
  // One line per key, and per element of the arrays of objects (walls, boxes, ...).
  std::string text = "{\n";
  bool first = true;
  for (const auto& item : scene.items()) {
    text += (first ? "  " : ",\n  ") + json(item.key()).dump() + ": ";
    first = false;
    const json& v = item.value();
    if (v.is_array() && !v.empty() && v.front().is_object()) {
      text += "[\n";
      for (std::size_t i = 0; i < v.size(); ++i)
        text += "    " + v[i].dump() + (i + 1 < v.size() ? ",\n" : "\n");
      text += "  ]";
    } else {
      text += v.dump();
    }
  }
  return text + "\n}\n";
}

Scene generate_scene(std::uint64_t seed, GeneratedKind kind) {
  const GeneratedKind k = resolve_generated_kind(seed, kind);
  return parse_scene_json(generate_scene_json(seed, k),
                          std::string("generated-") + to_string(k) + "-" + std::to_string(seed),
                          ".");
}

}  // namespace semioctree::sim
