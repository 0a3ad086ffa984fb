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
#include <tuple>

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
    case GeneratedKind::floor:
      return "floor";
    default:
      return "any";
  }
}

std::vector<std::string> generated_kind_names() {
  return {"any", "room", "l-shape", "hall", "floor"};
}

GeneratedKind generated_kind_from_string(const std::string& name) {
  for (GeneratedKind k : {GeneratedKind::any, GeneratedKind::room, GeneratedKind::l_shape,
                          GeneratedKind::hall, GeneratedKind::floor})
    if (name == to_string(k)) return k;
  throw std::invalid_argument("unknown scene kind '" + name +
                              "': expected any, room, l-shape, hall or floor");
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
  Vec2 lo = Vec2::Zero();
  double width = 0, depth = 0;  // bounding box lo + [0, width] × [0, depth]
};

Outline rectangle(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {x0, y0}, x1 - x0, y1 - y0};
}

// A floor of rooms (docs/generated-scenes.md, "Floors"): rectangular cells between the
// centre lines of the walls that part them (a cell side on the floor's outline is the
// outer wall's interior face), those walls, and the doors that join the cells.
struct Cell {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool corridor = false;
};
struct Split {  // an inner wall's centre line: y = at for x in [lo, hi] (along_x), or x = at
  bool along_x = true;
  double at = 0, lo = 0, hi = 0;
};
// Two cells sharing [u0, u1] of split `split` (`low` on the side of smaller coordinates).
struct Adjacency {
  std::size_t low = 0, high = 0, split = 0;
  double u0 = 0, u1 = 0;
};
struct Door {
  std::size_t split = 0;
  double s0 = 0, s1 = 0;  // along the split's axis
  double height = 0;
};

// An opening cut into an outline edge, along the edge's interior face from its first corner.
struct Hole {
  std::string kind;
  double s0, s1;
  double sill, height;
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

  // A floor's layout.
  FloorRequest asked;
  double inner_thickness = 0;
  std::vector<Cell> cells;
  std::vector<Split> splits;
  std::vector<Door> doors;

  Generator(std::uint64_t s, GeneratedKind k, const FloorRequest& floor)
      : draw(s), kind(k), seed(s), asked(floor) {}

  json run();
  json run_floor();
  json scene_json(const json& robot, const json& scanner) const;
  void make_outline();
  void make_walls_and_openings();
  void write_outline_walls(std::vector<std::vector<Hole>>& holes);
  void make_outside_and_slabs();
  void make_mezzanine();
  void make_columns();
  int make_wall_furniture();
  int make_free_furniture();
  std::optional<json> make_robot();
  json make_scanner(double diagonal);
  // Floors.
  bool partition_layout(int rooms, double min_side);
  bool corridor_layout(int rooms, double min_side);
  std::vector<Adjacency> adjacencies(double min_shared) const;
  bool make_doors(double min_shared);
  void make_floor_windows(std::vector<std::vector<Hole>>& holes);
  void write_inner_walls();
  Outline interior(const Cell& c) const;

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
  // y drawn before x: the order the single-room scenes were first generated in.
  Vec2 random_point_in_room() {
    for (;;) {
      const double y = draw.real(0, room.depth), x = draw.real(0, room.width);
      const Vec2 p = room.lo + Vec2(x, y);
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
  write_outline_walls(holes);
}

// The walls around the outline, their openings `holes` (per edge).
void Generator::write_outline_walls(std::vector<std::vector<Hole>>& holes) {
  const Polygon& p = room.polygon;
  const std::size_t n = p.size();
  const double t = wall_thickness;
  // Centre lines: the outline offset outwards by t/2 (rectilinear: corner + both edges'
  // normals), each wall continued t/2 past its corners so that the corners close.
  std::vector<Vec2> centre_corner(n);
  for (std::size_t i = 0; i < n; ++i)
    centre_corner[i] = p[i] + 0.5 * t * (outward((i + n - 1) % n) + outward(i));
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
    slabs.push_back({{"_", "ceiling"},
                     {"polygon", polygon_json(roof)},
                     {"z0", height},
                     {"z1", mm(height + 0.2)}});
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

int Generator::make_wall_furniture() {
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
  return placed;
}

int Generator::make_free_furniture() {
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
  return placed;
}

std::optional<json> Generator::make_robot() {
  // On free floor, its cylinder (and 0.15 m more) clear of walls, the columns and the
  // mezzanine's legs, and outside the zones in front of openings; then that square is
  // kept free of the furniture placed after. Columns stand a passage apart, so such a
  // point exists in every outline (each arm is at least 3 m wide).
  const double clear = robot_radius + 0.15;
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const double y = draw.real(0, room.depth), x = draw.real(0, room.width);  // as first made
    const Vec2 c(mm(room.lo.x() + x), mm(room.lo.y() + y));
    const Polygon square = Footprint{c, 2 * clear, 2 * clear, 0}.corners();
    if (!fits(square, 0.0, 0.0, 0.0) || distance_to_boundary(room.polygon, c) < clear) continue;
    bool free = true;
    for (const Polygon& o : obstacles) free = free && polygon_distance(square, o) > 0.0;
    if (!free) continue;
    keep_out.push_back(square);
    return json{
        {"start", xy(c)}, {"start_yaw_deg", mm(draw.real(-180, 180))}, {"radius", robot_radius}};
  }
  return std::nullopt;
}

json Generator::make_scanner(double diagonal) {
  // Angular step: about 3 cm between neighbouring rays at the far side of the room (its
  // diagonal), kept between 0.1° and 0.15° (5.4 to 2.4 million rays a scan).
  const double step =
      std::round(std::clamp(0.03 / diagonal * 180.0 / M_PI, 0.1, 0.15) * 100.0) / 100.0;
  const double el_min = mm(draw.real(-90, -30)), el_max = mm(draw.real(30, 90));
  return {{"height", scanner_height},
          {"azimuth_step_deg", step},
          {"elevation_step_deg", step},
          {"elevation_min_deg", el_min},
          {"elevation_max_deg", el_max}};
}

// ---- Floors ----------------------------------------------------------------------------

Outline Generator::interior(const Cell& c) const {
  const double h = 0.5 * inner_thickness, w = room.width, d = room.depth;
  return rectangle(c.x0 + (c.x0 > 1e-9 ? h : 0), c.y0 + (c.y0 > 1e-9 ? h : 0),
                   c.x1 - (c.x1 < w - 1e-9 ? h : 0), c.y1 - (c.y1 < d - 1e-9 ? h : 0));
}

// Cuts a rectangle (the one asked for, else one of about `rooms` × 12-28 m²) into `rooms`
// cells: again and again the largest cell that can be is cut across its longer side, at
// 35-65 %, each part keeping `min_side` between centre lines. False if no cell can be cut
// before the count.
bool Generator::partition_layout(int rooms, double min_side) {
  double w = mm(asked.width), d = mm(asked.depth);
  if (!asked.sized()) {
    const double area = rooms * draw.real(12, 28), aspect = draw.real(1.0, 1.8);
    w = mm(std::sqrt(area * aspect)), d = mm(area / w);
  }
  room = rectangle(0, 0, w, d);
  cells = {Cell{0, 0, w, d}};
  splits.clear();
  while (int(cells.size()) < rooms) {
    std::ptrdiff_t best = -1;
    double best_area = 0;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const Cell& c = cells[i];
      const double a = (c.x1 - c.x0) * (c.y1 - c.y0);
      if (std::max(c.x1 - c.x0, c.y1 - c.y0) >= 2 * min_side && a > best_area)
        best = std::ptrdiff_t(i), best_area = a;
    }
    if (best < 0) return false;
    const Cell c = cells[std::size_t(best)];
    const bool across_x = c.x1 - c.x0 >= c.y1 - c.y0;  // the wall runs along y
    const double lo = across_x ? c.x0 : c.y0, hi = across_x ? c.x1 : c.y1;
    const double at =
        mm(std::clamp(lo + draw.real(0.35, 0.65) * (hi - lo), lo + min_side, hi - min_side));
    Cell a = c, b = c;
    if (across_x) {
      a.x1 = b.x0 = at;
      splits.push_back({false, at, c.y0, c.y1});
    } else {
      a.y1 = b.y0 = at;
      splits.push_back({true, at, c.x0, c.x1});
    }
    cells[std::size_t(best)] = a;
    cells.push_back(b);
  }
  summary.push_back("floor " + num(w) + " x " + num(d) + " m of " + std::to_string(rooms) +
                    " rooms cut from one rectangle");
  return true;
}

// A corridor along x with `rooms` - 1 rooms off it, half on each side (the south side takes
// the odd one); rooms 3.5-6 m deep, each `min_side` wide or more; the north side's widths
// share the south side's length.
bool Generator::corridor_layout(int rooms, double min_side) {
  const int side_rooms = rooms - 1, south = (side_rooms + 1) / 2, north = side_rooms - south;
  if (north < 1) return false;
  const double corridor = mm(std::max(1.4, passage + 0.4) + draw.real(0, 1.0));
  const double south_depth = mm(draw.real(3.5, 6.0)), north_depth = mm(draw.real(3.5, 6.0));
  std::vector<double> south_widths, north_weights;
  double length = 0, weight_sum = 0;
  for (int i = 0; i < south; ++i) {
    south_widths.push_back(mm(min_side + draw.real(0, 3.0)));
    length += south_widths.back();
  }
  for (int i = 0; i < north; ++i) {
    north_weights.push_back(draw.real(0.2, 1.0));
    weight_sum += north_weights.back();
  }
  const double y_south = south_depth, y_north = south_depth + corridor;
  const double d = y_north + north_depth;
  room = rectangle(0, 0, length, d);
  cells.clear();
  splits = {{true, y_south, 0, length}, {true, y_north, 0, length}};
  double x = 0;
  for (int i = 0; i < south; ++i) {
    const double x1 = i + 1 < south ? mm(x + south_widths[std::size_t(i)]) : length;
    cells.push_back({x, 0, x1, y_south});
    if (i + 1 < south) splits.push_back({false, x1, 0, y_south});
    x = x1;
  }
  cells.push_back({0, y_south, length, y_north, true});
  const double spare = length - north * min_side;
  x = 0;
  for (int i = 0; i < north; ++i) {
    const double x1 = i + 1 < north
                          ? mm(x + min_side + spare * north_weights[std::size_t(i)] / weight_sum)
                          : length;
    cells.push_back({x, y_north, x1, d});
    if (i + 1 < north) splits.push_back({false, x1, y_north, d});
    x = x1;
  }
  summary.push_back("floor " + num(length) + " x " + num(d) + " m: a " + num(corridor, 2) +
                    " m corridor with " + std::to_string(side_rooms) + " rooms off it");
  return true;
}

std::vector<Adjacency> Generator::adjacencies(double min_shared) const {
  std::vector<Adjacency> out;
  for (std::size_t k = 0; k < splits.size(); ++k) {
    const Split& s = splits[k];
    for (std::size_t a = 0; a < cells.size(); ++a)
      for (std::size_t b = 0; b < cells.size(); ++b) {
        const Cell &ca = cells[a], &cb = cells[b];
        const bool touch = s.along_x
                               ? std::abs(ca.y1 - s.at) < 1e-9 && std::abs(cb.y0 - s.at) < 1e-9
                               : std::abs(ca.x1 - s.at) < 1e-9 && std::abs(cb.x0 - s.at) < 1e-9;
        if (!touch) continue;
        const double u0 = std::max({s.lo, s.along_x ? ca.x0 : ca.y0, s.along_x ? cb.x0 : cb.y0});
        const double u1 = std::min({s.hi, s.along_x ? ca.x1 : ca.y1, s.along_x ? cb.x1 : cb.y1});
        if (u1 - u0 >= min_shared) out.push_back({a, b, k, u0, u1});
      }
  }
  return out;
}

// Doors that join every cell to the others: on a corridor floor, each room onto the
// corridor; otherwise a spanning tree of the cells sharing `min_shared` of wall, drawn in a
// random order; then 20 % of the other shared walls get a door too. False if the cells
// cannot all be joined.
bool Generator::make_doors(double min_shared) {
  std::vector<Adjacency> adj = adjacencies(min_shared);
  for (std::size_t i = adj.size(); i > 1; --i)  // Fisher-Yates with the scene's draws
    std::swap(adj[i - 1], adj[std::size_t(draw.integer(0, int(i) - 1))]);
  std::vector<std::size_t> group(cells.size());
  for (std::size_t i = 0; i < group.size(); ++i) group[i] = i;
  const auto find = [&group](std::size_t i) {
    while (group[i] != i) i = group[i] = group[group[i]];
    return i;
  };
  const auto is_corridor = [this](const Adjacency& a) {
    return cells[a.low].corridor || cells[a.high].corridor;
  };
  const bool has_corridor =
      std::any_of(cells.begin(), cells.end(), [](const Cell& c) { return c.corridor; });
  std::vector<const Adjacency*> joined;
  std::size_t groups = cells.size();
  for (const Adjacency& a : adj) {
    const bool wanted = has_corridor ? is_corridor(a) : find(a.low) != find(a.high);
    if (wanted || draw.chance(0.2)) {
      joined.push_back(&a);
      if (find(a.low) != find(a.high)) group[find(a.low)] = find(a.high), --groups;
    }
  }
  if (groups != 1) return false;
  doors.clear();
  const double end_margin = 0.5 * inner_thickness + 0.3;
  for (const Adjacency* a : joined) {
    const double width = mm(std::max(draw.real(0.8, 1.2), passage));
    const double s0 = mm(draw.real(a->u0 + end_margin, a->u1 - end_margin - width));
    const double h = mm(std::min(draw.real(2.0, 2.4), height - 0.3));
    doors.push_back({a->split, s0, s0 + width, h});
    // Nothing stands in front of it, on either side.
    const Split& s = splits[a->split];
    const double depth = std::max(1.2, passage), near = 0.5 * inner_thickness;
    for (double side : {-1.0, 1.0}) {
      const double c0 = s.at + side * near, c1 = s.at + side * (near + depth);
      const double u0 = s0 - 0.2, u1 = s0 + width + 0.2;
      keep_out.push_back(s.along_x ? rectangle(u0, std::min(c0, c1), u1, std::max(c0, c1)).polygon
                                   : rectangle(std::min(c0, c1), u0, std::max(c0, c1), u1).polygon);
    }
  }
  return true;
}

// 0-2 windows in each cell's stretch of every outer wall it lies on (0-1 for the
// corridor), 0.5 m from the stretch's ends and from each other.
void Generator::make_floor_windows(std::vector<std::vector<Hole>>& holes) {
  const double w = room.width, d = room.depth, end_margin = 0.5 * inner_thickness + 0.5;
  int placed = 0;
  for (const Cell& c : cells) {
    // The outline's edges: 0 south (s = x), 1 east (s = y), 2 north (s = w - x), 3 west.
    std::vector<std::tuple<std::size_t, double, double>> stretches;
    if (c.y0 < 1e-9) stretches.emplace_back(0, c.x0, c.x1);
    if (c.x1 > w - 1e-9) stretches.emplace_back(1, c.y0, c.y1);
    if (c.y1 > d - 1e-9) stretches.emplace_back(2, w - c.x1, w - c.x0);
    if (c.x0 < 1e-9) stretches.emplace_back(3, d - c.y1, d - c.y0);
    for (const auto& [e, a, b] : stretches) {
      const int wanted = draw.integer(0, c.corridor ? 1 : 2);
      for (int i = 0; i < wanted; ++i) {
        const double width = mm(draw.real(0.6, 2.0));
        const double sill = mm(draw.real(0.5, 1.2));
        const double h = mm(std::min(draw.real(0.6, 1.6), height - 0.3 - sill));
        const double lo = a + end_margin, hi = b - end_margin - width;
        if (hi < lo) continue;
        const double s0 = mm(draw.real(lo, hi)), s1 = s0 + width;
        bool clear = true;
        for (const Hole& o : holes[e]) clear = clear && (s1 + 0.5 <= o.s0 || s0 >= o.s1 + 0.5);
        if (!clear) continue;
        holes[e].push_back({"window", s0, s1, sill, h});
        const Vec2 p = room.polygon[e], dir = edge_direction(e), in = -outward(e);
        const Vec2 q0 = p + dir * (s0 - 0.1), q1 = p + dir * (s1 + 0.1);
        keep_out.push_back({q0, q1, q1 + in * 0.8, q0 + in * 0.8});
        ++placed;
      }
    }
  }
  summary.push_back(std::to_string(doors.size()) + " doors, " + std::to_string(placed) +
                    " windows");
}

// The inner walls on the splits' centre lines, run into the outer walls at the outline,
// their doors cut in.
void Generator::write_inner_walls() {
  const double te = wall_thickness;
  for (std::size_t k = 0; k < splits.size(); ++k) {
    const Split& s = splits[k];
    const double extent = s.along_x ? room.width : room.depth;
    const double lo = s.lo < 1e-9 ? -0.5 * te : s.lo;
    const double hi = s.hi > extent - 1e-9 ? extent + 0.5 * te : s.hi;
    const Vec2 from = s.along_x ? Vec2(lo, s.at) : Vec2(s.at, lo);
    const Vec2 to = s.along_x ? Vec2(hi, s.at) : Vec2(s.at, hi);
    std::vector<const Door*> on;
    for (const Door& door : doors)
      if (door.split == k) on.push_back(&door);
    std::sort(on.begin(), on.end(), [](const Door* a, const Door* b) { return a->s0 < b->s0; });
    json w = {
        {"from", xy(from)}, {"to", xy(to)}, {"thickness", mm(inner_thickness)}, {"z1", height}};
    json openings = json::array();
    for (const Door* door : on)
      openings.push_back({{"kind", "door"},
                          {"start", mm(door->s0 - lo)},
                          {"width", mm(door->s1 - door->s0)},
                          {"height", door->height}});
    if (!openings.empty()) w["openings"] = openings;
    walls.push_back(w);
  }
}

json Generator::run_floor() {
  const int drawn = draw.integer(3, 10);
  const int per_area = std::clamp(int(std::lround(asked.width * asked.depth / 20.0)),
                                  kMinFloorRooms, kMaxFloorRooms);
  const int rooms = asked.rooms ? asked.rooms : asked.sized() ? per_area : drawn;
  height = mm(draw.real(2.5, 3.2));
  wall_thickness = std::round(draw.real(0.2, 0.3) * 50.0) / 50.0;    // outer, whole 2 cm
  inner_thickness = std::round(draw.real(0.1, 0.16) * 50.0) / 50.0;  // inner
  robot_radius = mm(draw.real(0.25, 0.55));
  scanner_height = mm(draw.real(1.0, 1.8));
  passage = 2 * robot_radius + 0.3;
  ceiling = !draw.chance(0.2);
  // Each room at least 3 m across inside; shared walls long enough for the widest door
  // with 0.3 m of wall either side.
  const double min_side = 3.0 + inner_thickness;
  const double min_shared = std::max(1.2, passage) + inner_thickness + 0.6;
  bool laid_out = false;
  for (int attempt = 0; attempt < 200 && !laid_out; ++attempt) {
    summary.clear();
    keep_out.clear();
    const bool corridor = !asked.sized() && rooms >= 3 && draw.chance(0.5);
    laid_out = (corridor ? corridor_layout(rooms, min_side) : partition_layout(rooms, min_side)) &&
               make_doors(min_shared);
  }
  if (!laid_out && asked.sized())
    throw std::invalid_argument("a floor of " + num(asked.width) + " x " + num(asked.depth) +
                                " m has no room for " + std::to_string(rooms) +
                                " rooms 3 m across or more joined by doors: ask for fewer");
  if (!laid_out)
    throw std::logic_error("scene generator: no floor of " + std::to_string(rooms) +
                           " rooms for seed " + std::to_string(seed));
  summary.push_back(num(height, 2) + " m high" + (ceiling ? "" : ", no ceiling slab"));
  const Outline outline = room;
  std::vector<std::vector<Hole>> holes(4);
  make_floor_windows(holes);
  write_outline_walls(holes);
  write_inner_walls();
  make_outside_and_slabs();
  // The start in a room drawn (not the corridor), before the furniture, kept free of it.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (!cells[i].corridor) order.push_back(i);
  for (std::size_t i = order.size(); i > 1; --i)
    std::swap(order[i - 1], order[std::size_t(draw.integer(0, int(i) - 1))]);
  std::optional<json> robot;
  for (std::size_t i = 0; i < order.size() && !robot; ++i) {
    room = interior(cells[order[i]]);
    robot = make_robot();
  }
  room = outline;
  if (!robot)
    throw std::logic_error("scene generator: no free start for seed " + std::to_string(seed));
  // Furniture room by room; none in the corridor, which is a passage.
  int along_walls = 0, free_standing = 0;
  double diagonal = 0;
  for (const Cell& c : cells) {
    room = interior(c);
    diagonal = std::max(diagonal, std::hypot(room.width, room.depth));
    if (c.corridor) continue;
    along_walls += make_wall_furniture();
    free_standing += make_free_furniture();
  }
  room = outline;
  if (along_walls)
    summary.push_back(std::to_string(along_walls) + " benches and cabinets along the walls");
  if (free_standing)
    summary.push_back(std::to_string(free_standing) + " free-standing tables, poles, cabinets");
  return scene_json(*robot, make_scanner(diagonal));
}

json Generator::run() {
  if (kind == GeneratedKind::floor) return run_floor();
  make_outline();
  // The mezzanine before the openings (none cut into its slab), the obstacles after
  // them (none in their zones): columns, then the wall furniture, then the free one.
  make_mezzanine();
  make_walls_and_openings();
  make_outside_and_slabs();
  make_columns();
  // The start before the furniture, kept free of it: a start always exists.
  const std::optional<json> robot = make_robot();
  if (!robot)
    throw std::logic_error("scene generator: no free start for seed " + std::to_string(seed));
  if (const int placed = make_wall_furniture())
    summary.push_back(std::to_string(placed) + " benches and cabinets along the walls");
  if (const int placed = make_free_furniture())
    summary.push_back(std::to_string(placed) + " free-standing tables, poles, cabinets" +
                      (kind == GeneratedKind::hall ? ", machines" : ""));
  return scene_json(*robot, make_scanner(std::hypot(room.width, room.depth)));
}

json Generator::scene_json(const json& robot, const json& scanner) const {
  std::ostringstream description;
  description << "Generated scene (seed " << seed << ", kind " << to_string(kind) << "): ";
  for (std::size_t i = 0; i < summary.size(); ++i) description << (i ? "; " : "") << summary[i];
  description << "; robot radius " << robot_radius << " m, scanner at " << scanner_height << " m.";
  std::string name = std::string("gen-") + to_string(kind) + "-" + std::to_string(seed);
  if (asked.rooms) name += "-" + std::to_string(asked.rooms) + "-rooms";
  if (asked.sized()) {
    char size[64];
    std::snprintf(size, sizeof size, "-%gx%gm", asked.width, asked.depth);
    name += size;
  }
  json scene = {{"format", "semioctree-scene"},     {"version", 1},   {"name", name},
                {"description", description.str()}, {"walls", walls}, {"slabs", slabs}};
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

namespace {
bool floor_side_ok(double side) {
  return side >= kMinFloorSide && side <= kMaxFloorSide;
}
}  // namespace

std::pair<double, double> floor_size_from_string(const std::string& text) {
  const std::size_t x = text.find_first_of("xX");
  try {
    std::size_t used_w = 0, used_d = 0;
    const double w = std::stod(text.substr(0, x), &used_w);
    const double d = x == std::string::npos ? 0 : std::stod(text.substr(x + 1), &used_d);
    if (x != std::string::npos && used_w == x && used_d == text.size() - x - 1 &&
        floor_side_ok(w) && floor_side_ok(d))
      return {w, d};
  } catch (const std::exception&) {
  }
  throw std::invalid_argument("floor size '" + text + "': expected WxD in metres, each side " +
                              num(kMinFloorSide, 0) + " to " + num(kMaxFloorSide, 0) +
                              " (e.g. 60x45)");
}

std::string generate_scene_json(std::uint64_t seed, GeneratedKind kind, const FloorRequest& floor) {
  const GeneratedKind k = resolve_generated_kind(seed, kind);
  if ((floor.rooms != 0 || floor.sized()) && k != GeneratedKind::floor)
    throw std::invalid_argument(std::string("a room count or size is for floors, not for kind ") +
                                to_string(k));
  if (floor.rooms != 0 && (floor.rooms < kMinFloorRooms || floor.rooms > kMaxFloorRooms))
    throw std::invalid_argument("a floor of " + std::to_string(floor.rooms) + " rooms: expected " +
                                std::to_string(kMinFloorRooms) + " to " +
                                std::to_string(kMaxFloorRooms));
  if (floor.sized() && !(floor_side_ok(floor.width) && floor_side_ok(floor.depth)))
    throw std::invalid_argument("a floor of " + num(floor.width) + " x " + num(floor.depth) +
                                " m: each side " + num(kMinFloorSide) + " to " +
                                num(kMaxFloorSide) + " m, both given");
  Generator g(seed, k, floor);
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

Scene generate_scene(std::uint64_t seed, GeneratedKind kind, const FloorRequest& floor) {
  const GeneratedKind k = resolve_generated_kind(seed, kind);
  return parse_scene_json(generate_scene_json(seed, k, floor),
                          std::string("generated-") + to_string(k) + "-" + std::to_string(seed),
                          ".");
}

}  // namespace semioctree::sim
