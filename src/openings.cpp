#include "semioctree/openings.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "plane_segmentation.h"
#include "random_subset.h"
#include "scanner_limits.h"

namespace semioctree {

const char* to_string(OpeningKind kind) {
  return kind == OpeningKind::kDoor ? "door" : "window";
}

Label label_of(OpeningKind kind) {
  return kind == OpeningKind::kDoor ? Label::kDoor : Label::kWindow;
}

namespace {

// A vertical plane n·p + d = 0 with n horizontal and unit.
struct VerticalPlane {
  Eigen::Vector2d n = Eigen::Vector2d::UnitX();
  double d = 0;
  double distance(const pcl::PointXYZ& p) const { return n.x() * p.x + n.y() * p.y + d; }
};

// Least-squares vertical plane through the points' xy footprint: the normal is
// the direction of least spread. RANSAC's own model comes from 3 points and is
// tilted by their noise; refitting on all inliers makes the wall frame exact
// enough for a grid of leaf-sized cells over 10 m.
VerticalPlane fit_vertical_plane(const Cloud& cloud, const std::vector<int>& indices) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : indices) mean += Eigen::Vector2d(cloud[i].x, cloud[i].y);
  mean /= double(indices.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (int i : indices) {
    const Eigen::Vector2d q = Eigen::Vector2d(cloud[i].x, cloud[i].y) - mean;
    cov += q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  VerticalPlane plane;
  plane.n = eig.eigenvectors().col(0).normalized();  // smallest eigenvalue first
  plane.d = -plane.n.dot(mean);
  return plane;
}

// Occupancy grid of one wall segment: column c covers u ∈ [u0 + c·cell, ...),
// row r covers z ∈ [r·cell, (r+1)·cell); the floor is row 0's bottom.
struct WallGrid {
  int cols = 0, rows = 0;
  double cell = 0, u0 = 0;
  std::vector<std::uint8_t> occupied;  // row-major (r·cols + c)
  // Per cell and scanner (cell · scanners + scanner): -1 not yet cast, 0 the line is
  // blocked, 1 it is free up to the LOS margin.
  std::vector<std::int8_t> los;
  std::size_t scanners = 0;
  bool occ(int c, int r) const { return occupied[std::size_t(r) * cols + c] != 0; }
};

// Rectangle of empty cells, inclusive bounds.
struct CellRect {
  int c0, c1, r0, r1;
  OpeningKind kind;
  int area() const { return (c1 - c0 + 1) * (r1 - r0 + 1); }
  bool overlaps(const CellRect& o) const {
    return c0 <= o.c1 && o.c0 <= c1 && r0 <= o.r1 && o.r0 <= r1;
  }
};

struct WallFrame {
  VerticalPlane plane;
  Eigen::Vector3d normal, u_axis;
  // World point at (u along the wall, height z) in the plane.
  Eigen::Vector3d at(double u, double z) const {
    return -plane.d * normal + u * u_axis + z * Eigen::Vector3d::UnitZ();
  }
};

// How many of the columns c0..c1 have an occupied cell in rows r0..r1 - 1: wall around
// a hole. Where two walls stand in line across a corridor, the corridor is a hole in
// their common plane with nothing above or below it but stray points.
int columns_with_wall(const WallGrid& g, int c0, int c1, int r0, int r1) {
  int n = 0;
  for (int c = c0; c <= c1; ++c)
    for (int r = std::max(0, r0); r < std::min(g.rows, r1); ++r)
      if (g.occ(c, r)) {
        ++n;
        break;
      }
  return n;
}

// Every maximal rectangle of empty cells (no side can grow by a whole row or
// column of empty cells) that does not touch the ends of the wall segment, kept
// when its size fits a door or a window. Maximality is what makes a hole's
// rectangle its full extent; enclosure by wall cells on the left, right and top
// is what separates a hole from the space beyond the end of a wall, and wall over
// most of its columns (under them too, for a window) from the gap between two walls
// in line (columns_with_wall).
std::vector<CellRect> find_hole_candidates(const WallGrid& g, double ceiling,
                                           const OpeningParams& p) {
  std::vector<CellRect> out;
  std::vector<std::uint8_t> free_cols(std::size_t(g.cols));
  const double eps = 1e-9;
  for (int r0 = 0; r0 < g.rows; ++r0) {
    std::fill(free_cols.begin(), free_cols.end(), 1);
    for (int r1 = r0; r1 < g.rows; ++r1) {
      bool any = false;
      for (int c = 0; c < g.cols; ++c) {
        free_cols[c] = free_cols[c] && !g.occ(c, r1);
        any = any || free_cols[c];
      }
      if (!any) break;
      // Runs of columns free over rows r0..r1 (maximal left and right).
      for (int c = 0; c < g.cols;) {
        if (!free_cols[c]) {
          ++c;
          continue;
        }
        int a = c;
        while (c < g.cols && free_cols[c]) ++c;
        const int b = c - 1;
        if (a == 0 || b == g.cols - 1) continue;  // not enclosed by the wall
        if (r1 + 1 >= g.rows) continue;           // reaches the ceiling: not enclosed
        auto row_empty = [&](int r) {
          for (int cc = a; cc <= b; ++cc)
            if (g.occ(cc, r)) return false;
          return true;
        };
        if (row_empty(r1 + 1)) continue;            // could grow upwards
        if (r0 > 0 && row_empty(r0 - 1)) continue;  // could grow downwards
        const double width = (b - a + 1) * g.cell;
        const double bottom = r0 * g.cell;
        const double top = (r1 + 1) * g.cell;
        // Most of its columns have wall over it (a lintel), and a window's under it too.
        const bool lintel = 2 * columns_with_wall(g, a, b, r1 + 1, g.rows - 1) >= b - a + 1;
        const bool parapet = 2 * columns_with_wall(g, a, b, 1, r0) >= b - a + 1;
        const bool door = lintel && bottom <= p.floor_tolerance + eps &&
                          width + eps >= p.door_min_width && width <= p.door_max_width + eps &&
                          top + eps >= p.door_min_height && top <= p.door_max_height + eps &&
                          top <= ceiling - p.min_lintel + eps;
        const bool window =
            lintel && parapet && bottom + eps >= p.window_min_sill &&
            top <= ceiling - p.min_lintel + eps && width + eps >= p.window_min_width &&
            width <= p.window_max_width + eps && top - bottom + eps >= p.window_min_height &&
            top - bottom <= p.window_max_height + eps;
        if (door)
          out.push_back({a, b, r0, r1, OpeningKind::kDoor});
        else if (window)
          out.push_back({a, b, r0, r1, OpeningKind::kWindow});
      }
    }
  }
  return out;
}

// Direct line of sight from scanner `a` to the cell centre `target`: the segment is
// traversed through the octants and stops at the first occupied one. It ends
// `margin` in front of the wall plane (measured along the wall's normal, not
// along the segment) because the leaves of the wall's surface around the hole
// are occupied and reach up to a leaf in front of the plane: cut along the
// segment, an oblique line to a cell beside a jamb still ended inside the
// jamb's surface leaf, and a whole column of the hole went unseen.
bool line_reaches_wall(const SemiOcTree& tree, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& target, double off_wall, double margin) {
  const Eigen::Vector3d end = target + (a - target) * (margin / off_wall);
  const TraversalEnd e =
      tree.traverse(Point3(a.x(), a.y(), a.z()), Point3(end.x(), end.y(), end.z()),
                    [](const RayStep& step) { return step.label() != Label::kOccupied; });
  return e == TraversalEnd::kReachedEnd;
}

// What the LOS test of one hole needs beside the map.
struct LosTest {
  const SemiOcTree& tree;
  const std::vector<ScannerView>& scanners;
  std::vector<detail::ScannerLimits> limits;  // one per scanner
  double margin = 0;                          // OpeningParams::los_end_margin_leaves, m
  double min_off_wall = 0;                    // OpeningParams::los_min_scanner_off_wall
  double max_slack_share = 0;  // of the hole's width and height: los_min_fraction / 2
  std::size_t& rays;
};

// Whether some scanner sees the cell directly, as evidence for a hole of the given
// size. A line that ends `margin` in front of the wall cannot tell the hole from an
// object standing against the wall (a cabinet) within margin / tan(incidence) of the
// cell along the wall: the line ends before it meets the object's side. That slack
// grows without bound as the line grazes the wall. Seen from both ends of a shadow of
// width W, lines with slack s confirm 2s of it; so a line confirms a cell only while its
// slack, along the wall and upright, is below los_min_fraction / 2 of the hole's width
// and height: a shadow can then never reach the 85 % (docs/occlusion.md).
bool cell_visible(WallGrid& g, std::size_t cell, const Eigen::Vector3d& target,
                  const Eigen::Vector3d& wall_normal, const Eigen::Vector3d& u_axis, double width,
                  double height, const LosTest& t) {
  for (std::size_t i = 0; i < t.scanners.size(); ++i) {
    const ScannerView& view = t.scanners[i];
    const Point3& s = view.position;
    const Eigen::Vector3d a(s.x, s.y, s.z);
    const Eigen::Vector3d d = a - target;
    const double off_wall = std::abs(d.dot(wall_normal));
    // A scanner in the wall's plane (a scan taken in one of its doorways) sees
    // the wall edge-on: its lines run along the face and would confirm any hole.
    if (off_wall < t.min_off_wall || off_wall <= t.margin) continue;
    // A scanner sees only within its range and elevation limits: a free line above its
    // highest elevation is no sight (the wall over a cabinet beside a low scanner).
    if (!t.limits[i].in_view(s, Point3(target.x(), target.y(), target.z()))) continue;
    const double slack_along = t.margin * std::abs(d.dot(u_axis)) / off_wall;
    const double slack_up = t.margin * std::abs(d.z()) / off_wall;
    if (slack_along > t.max_slack_share * width || slack_up > t.max_slack_share * height) continue;
    std::int8_t& v = g.los[cell * g.scanners + i];
    if (v < 0) {
      ++t.rays;
      v = line_reaches_wall(t.tree, a, target, off_wall, t.margin) ? 1 : 0;
    }
    if (v == 1) return true;
  }
  return false;
}

// The cells of the hole seen directly (row-major over the rectangle) and their share.
struct HoleSight {
  std::vector<std::uint8_t> seen;
  double fraction = 0;
};

HoleSight hole_sight(WallGrid& g, const WallFrame& f, const CellRect& r, const LosTest& t) {
  HoleSight h;
  const int w = r.c1 - r.c0 + 1, hgt = r.r1 - r.r0 + 1;
  h.seen.assign(std::size_t(w) * hgt, 0);
  std::size_t seen = 0;
  for (int row = r.r0; row <= r.r1; ++row)
    for (int c = r.c0; c <= r.c1; ++c) {
      const Eigen::Vector3d centre = f.at(g.u0 + (c + 0.5) * g.cell, (row + 0.5) * g.cell);
      const bool v = cell_visible(g, std::size_t(row) * g.cols + c, centre, f.normal, f.u_axis,
                                  w * g.cell, hgt * g.cell, t);
      h.seen[std::size_t(row - r.r0) * w + (c - r.c0)] = v;
      seen += v;
    }
  h.fraction = double(seen) / double(r.area());
  return h;
}

// The rule for partly hidden holes (OpeningParams::partly_hidden_min_los): one
// connected region of seen cells (8-neighbours) reaches the sides that define the
// rectangle. What is seen of a door behind a bench is one band across it; what lines
// from either end see of a cabinet's shadow are two strips, each at one side only.
bool seen_region_spans_rect(const HoleSight& h, const CellRect& r) {
  const int w = r.c1 - r.c0 + 1, hgt = r.r1 - r.r0 + 1;
  std::vector<int> region(h.seen.size(), -1);
  int next = 0;
  for (std::size_t start = 0; start < h.seen.size(); ++start) {
    if (!h.seen[start] || region[start] >= 0) continue;
    bool left = false, right = false, top = false, bottom = false;
    std::vector<std::size_t> stack{start};
    region[start] = next;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      const int c = int(i % std::size_t(w)), row = int(i / std::size_t(w));
      left = left || c == 0;
      right = right || c == w - 1;
      bottom = bottom || row == 0;
      top = top || row == hgt - 1;
      for (int dr = -1; dr <= 1; ++dr)
        for (int dc = -1; dc <= 1; ++dc) {
          const int cc = c + dc, rr = row + dr;
          if (cc < 0 || cc >= w || rr < 0 || rr >= hgt) continue;
          const std::size_t j = std::size_t(rr) * w + cc;
          if (h.seen[j] && region[j] < 0) {
            region[j] = next;
            stack.push_back(j);
          }
        }
    }
    if (left && right && top && (r.kind == OpeningKind::kDoor || bottom)) return true;
    ++next;
  }
  return false;
}

DetectedOpening make_opening(const WallGrid& g, const WallFrame& f, const CellRect& r, double los,
                             int wall) {
  DetectedOpening o;
  o.kind = r.kind;
  const double u_near = g.u0 + r.c0 * g.cell, u_far = g.u0 + (r.c1 + 1) * g.cell;
  // A door's hole starts at the floor whatever the lowest empty row is.
  const double bottom = r.kind == OpeningKind::kDoor ? 0.0 : r.r0 * g.cell;
  const double top = (r.r1 + 1) * g.cell;
  o.corners = {f.at(u_near, bottom), f.at(u_far, bottom), f.at(u_far, top), f.at(u_near, top)};
  o.width = u_far - u_near;
  o.height = top - bottom;
  o.sill = bottom;
  o.los_fraction = los;
  o.wall_normal = f.normal;
  o.wall = wall;
  return o;
}

// Runs of columns holding points, where gaps up to `max_gap` columns are
// bridged: a door's lintel keeps its columns non-empty, so only a stretch empty
// at every height between the floor's and the ceiling's bands (another wall's
// corner, a full-height shadow, open space) splits a plane.
std::vector<std::pair<int, int>> column_runs(const std::vector<std::size_t>& col_points,
                                             int max_gap) {
  std::vector<std::pair<int, int>> runs;
  const int n = int(col_points.size());
  int start = -1, last = -1;
  for (int c = 0; c < n; ++c) {
    if (col_points[c] == 0) continue;
    if (start < 0) {
      start = c;
    } else if (c - last - 1 > max_gap) {
      runs.emplace_back(start, last);
      start = c;
    }
    last = c;
  }
  if (start >= 0) runs.emplace_back(start, last);
  return runs;
}

// A hole through a wall is a hole in both of its faces: once a scan stood beyond the
// wall (through one of its doors), the same opening is found on the far face too. Of two
// openings of one kind on parallel planes less than a wall's thickness apart whose
// rectangles overlap (IoU ≥ 0.5 across the wall), the one nearer `first_scanner` (the
// face of the room the survey started in) is kept.
std::vector<DetectedOpening> drop_far_faces(std::vector<DetectedOpening> found,
                                            const Point3& first_scanner, const OpeningParams& p,
                                            OpeningsReport& rep) {
  const Eigen::Vector3d s0(first_scanner.x, first_scanner.y, first_scanner.z);
  // The rectangle's extent along u (horizontal, in the wall) and z.
  auto extent = [](const DetectedOpening& o, const Eigen::Vector3d& u) {
    double lo = std::numeric_limits<double>::max(), hi = -lo;
    for (const Eigen::Vector3d& c : o.corners) {
      lo = std::min(lo, c.dot(u));
      hi = std::max(hi, c.dot(u));
    }
    return std::pair<double, double>(lo, hi);
  };
  const double parallel = std::cos(2 * p.max_normal_tilt_deg * M_PI / 180.0);
  std::vector<bool> dropped(found.size(), false);
  for (std::size_t i = 0; i < found.size(); ++i)
    for (std::size_t j = i + 1; j < found.size(); ++j) {
      const DetectedOpening &a = found[i], &b = found[j];
      if (dropped[i] || dropped[j] || a.kind != b.kind) continue;
      if (std::abs(a.wall_normal.dot(b.wall_normal)) < parallel) continue;
      const Eigen::Vector3d ca = a.centre(), cb = b.centre();
      if (std::abs((cb - ca).dot(a.wall_normal)) > p.max_wall_thickness) continue;
      const Eigen::Vector3d u(-a.wall_normal.y(), a.wall_normal.x(), 0.0);
      const auto [au0, au1] = extent(a, u);
      const auto [bu0, bu1] = extent(b, u);
      const auto [az0, az1] = extent(a, Eigen::Vector3d::UnitZ());
      const auto [bz0, bz1] = extent(b, Eigen::Vector3d::UnitZ());
      const double w = std::min(au1, bu1) - std::max(au0, bu0);
      const double h = std::min(az1, bz1) - std::max(az0, bz0);
      if (w <= 0 || h <= 0) continue;
      const double both = w * h;
      const double iou = both / ((au1 - au0) * (az1 - az0) + (bu1 - bu0) * (bz1 - bz0) - both);
      if (iou < 0.5) continue;
      const bool a_nearer =
          std::abs((s0 - ca).dot(a.wall_normal)) <= std::abs((s0 - cb).dot(b.wall_normal));
      dropped[a_nearer ? j : i] = true;
      ++rep.far_faces;
    }
  std::vector<DetectedOpening> kept;
  for (std::size_t i = 0; i < found.size(); ++i)
    if (!dropped[i]) kept.push_back(std::move(found[i]));
  return kept;
}

}  // namespace

std::vector<DetectedOpening> detect_openings(const Cloud& levelled, double ceiling_height,
                                             const SemiOcTree& tree,
                                             const std::vector<Point3>& scanner_positions,
                                             const OpeningParams& params, OpeningsReport* report) {
  std::vector<ScannerView> views;
  for (const Point3& s : scanner_positions) {
    ScannerView v(s);
    v.min_range = 0;
    v.max_range = std::numeric_limits<double>::infinity();
    v.elevation_min_deg = -90;
    v.elevation_max_deg = 90;
    views.push_back(v);
  }
  return detect_openings(levelled, ceiling_height, tree, views, params, report);
}

std::vector<DetectedOpening> detect_openings(const Cloud& levelled, double ceiling_height,
                                             const SemiOcTree& tree,
                                             const std::vector<ScannerView>& scanners,
                                             const OpeningParams& p, OpeningsReport* report) {
  std::vector<Point3> scanner_positions;
  for (const ScannerView& v : scanners) scanner_positions.push_back(v.position);
  OpeningsReport local_report;
  OpeningsReport& rep = report ? *report : local_report;
  rep = OpeningsReport{};
  std::vector<DetectedOpening> result;
  const double cell = p.cell > 0 ? p.cell : tree.leaf_size();
  const double margin = p.los_end_margin_leaves * tree.leaf_size();
  LosTest los_test{
      tree,        scanners, {}, margin, p.los_min_scanner_off_wall, 0.5 * p.los_min_fraction,
      rep.los_rays};
  for (const ScannerView& v : scanners) los_test.limits.emplace_back(v);
  const int rows = int(std::ceil(ceiling_height / cell - 1e-9));
  if (rows <= 0 || scanner_positions.empty()) return result;

  // Walls live between floor and ceiling; points outside (the ground seen
  // through a window, a roof) would only tilt the planes.
  Cloud::Ptr remaining(new Cloud);
  remaining->reserve(levelled.size());
  for (const auto& q : levelled)
    if (std::isfinite(q.x) && q.z >= 0 && q.z < ceiling_height) remaining->push_back(q);

  detail::PlaneSegmentation seg;       // PCL's, counting lanes at a time
  seg.setOptimizeCoefficients(false);  // refitted below on all inliers
  seg.setModelType(pcl::SACMODEL_PARALLEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(Eigen::Vector3f::UnitZ());
  seg.setEpsAngle(p.max_normal_tilt_deg * M_PI / 180.0);
  seg.setDistanceThreshold(p.ransac_distance);
  seg.setMaxIterations(p.ransac_iterations);
  constexpr std::uint64_t kSampleSeed = 20240505;

  const Point3& s0 = scanner_positions.front();
  // What each round leaves for the next: two buffers taking turns (a fresh cloud of the
  // map's size a round faulted its pages in every time).
  Cloud::Ptr rest(new Cloud);
  rest->reserve(remaining->size());
  for (int round = 0; round < p.max_planes && remaining->size() >= p.min_plane_points; ++round) {
    // RANSAC on a random subset: the big planes are found as well and the cost
    // does not grow with the cloud.
    const Cloud::Ptr sample =
        detail::random_subset(*remaining, p.ransac_sample, kSampleSeed + std::uint64_t(round));
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coeffs;
    seg.setInputCloud(sample);
    seg.segment(inliers, coeffs);
    if (inliers.indices.size() < 3) break;
    VerticalPlane plane = fit_vertical_plane(*sample, inliers.indices);

    // Inliers of the whole remaining cloud; the rest goes on to the next round.
    std::vector<int> in;
    rest->clear();
    for (int i = 0; i < int(remaining->size()); ++i) {
      if (std::abs(plane.distance((*remaining)[i])) <= p.ransac_distance)
        in.push_back(i);
      else
        rest->push_back((*remaining)[i]);
    }
    if (in.size() < p.min_plane_points) break;
    plane = fit_vertical_plane(*remaining, in);  // exact frame from all inliers
    // The normal faces the first scanner, so "near" and "far" are the same on
    // every run and the LOS margin pulls towards the room.
    if (plane.n.x() * s0.x + plane.n.y() * s0.y + plane.d < 0) {
      plane.n = -plane.n;
      plane.d = -plane.d;
    }
    WallFrame frame;
    frame.plane = plane;
    frame.normal = Eigen::Vector3d(plane.n.x(), plane.n.y(), 0);
    frame.u_axis = Eigen::Vector3d(-plane.n.y(), plane.n.x(), 0);

    std::vector<double> u(in.size());
    double u_min = std::numeric_limits<double>::max(), u_max = -u_min;
    for (std::size_t k = 0; k < in.size(); ++k) {
      const auto& q = (*remaining)[in[k]];
      u[k] = frame.u_axis.x() * q.x + frame.u_axis.y() * q.y;
      u_min = std::min(u_min, u[k]);
      u_max = std::max(u_max, u[k]);
    }
    const int all_cols = int(std::floor((u_max - u_min) / cell)) + 1;
    // The floor's and the ceiling's cuts leave some of their returns, a few cm
    // from them, all along the plane: through open space (a hall the plane
    // crosses, a room beyond the wall's end) they would join stray points in
    // line with the wall into one segment, whose fill they dilute. Those bands
    // are what floor_tolerance and min_lintel allow for; points between them
    // show where the wall stands.
    std::vector<std::size_t> col_points(std::size_t(all_cols), 0);
    for (std::size_t k = 0; k < in.size(); ++k) {
      const double z = (*remaining)[in[k]].z;
      if (z >= p.floor_tolerance && z < ceiling_height - p.min_lintel)
        ++col_points[std::size_t(std::min(all_cols - 1, int((u[k] - u_min) / cell)))];
    }

    for (const auto& [c0, c1] : column_runs(col_points, int(p.wall_split_gap / cell))) {
      WallGrid g;
      g.cell = cell;
      g.u0 = u_min + c0 * cell;
      g.cols = c1 - c0 + 1;
      g.rows = rows;
      if (g.cols * cell < p.min_wall_length) continue;
      std::vector<int> counts(std::size_t(g.cols) * rows, 0);
      double z_lo = ceiling_height, z_hi = 0;
      std::size_t points = 0;
      for (std::size_t k = 0; k < in.size(); ++k) {
        const int c = int((u[k] - g.u0) / cell);
        if (c < 0 || c >= g.cols) continue;
        const double z = (*remaining)[in[k]].z;
        const int r = std::min(rows - 1, int(z / cell));
        ++counts[std::size_t(r) * g.cols + c];
        z_lo = std::min(z_lo, z);
        z_hi = std::max(z_hi, z);
        ++points;
      }
      // Furniture faces are vertical planes too, but they do not span the room
      // from floor to ceiling.
      if (z_hi - z_lo < p.min_wall_height_fraction * ceiling_height) continue;
      g.occupied.assign(counts.size(), 0);
      for (std::size_t i = 0; i < counts.size(); ++i)
        g.occupied[i] = counts[i] >= p.min_cell_points ? 1 : 0;
      // A single empty cell between two wall cells is sampling sparsity on a
      // far or grazing wall, not a hole; filling it keeps hole rectangles from
      // leaking into the wall through such pinholes.
      const std::vector<std::uint8_t> raw = g.occupied;
      auto raw_occ = [&](int c, int r) { return raw[std::size_t(r) * g.cols + c] != 0; };
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < g.cols; ++c) {
          if (raw_occ(c, r)) continue;
          const bool h = c > 0 && c + 1 < g.cols && raw_occ(c - 1, r) && raw_occ(c + 1, r);
          const bool v = r > 0 && r + 1 < rows && raw_occ(c, r - 1) && raw_occ(c, r + 1);
          if (h || v) g.occupied[std::size_t(r) * g.cols + c] = 1;
        }
      const auto filled = std::size_t(std::count(g.occupied.begin(), g.occupied.end(), 1));
      if (double(filled) < p.min_wall_fill * double(g.occupied.size())) continue;
      g.scanners = scanner_positions.size();
      g.los.assign(g.occupied.size() * g.scanners, -1);

      const int wall_index = int(rep.walls.size());
      DetectedWall w;
      w.normal = frame.normal;
      w.offset = plane.d;
      w.u_axis = frame.u_axis;
      w.u_min = g.u0;
      w.u_max = g.u0 + g.cols * cell;
      w.points = points;
      rep.walls.push_back(w);

      std::vector<CellRect> cands = find_hole_candidates(g, ceiling_height, p);
      rep.candidates += cands.size();
      // Largest first: where a true opening and a shadow beside it form both a
      // small and a large rectangle, the LOS test decides which one survives.
      std::stable_sort(cands.begin(), cands.end(),
                       [](const CellRect& a, const CellRect& b) { return a.area() > b.area(); });
      std::vector<CellRect> kept;
      for (const CellRect& r : cands) {
        bool overlaps = false;
        for (const CellRect& k : kept) overlaps = overlaps || k.overlaps(r);
        if (overlaps) continue;
        const HoleSight sight = hole_sight(g, frame, r, los_test);
        const double los = sight.fraction;
        const bool confirmed =
            los + 1e-12 >= p.los_min_fraction ||
            (p.partly_hidden_min_los > 0 && los + 1e-12 >= p.partly_hidden_min_los &&
             seen_region_spans_rect(sight, r));
        if (confirmed) {
          kept.push_back(r);
          result.push_back(make_opening(g, frame, r, los, wall_index));
        } else {
          rep.rejected.push_back(make_opening(g, frame, r, los, wall_index));
        }
      }
    }
    std::swap(remaining, rest);
  }
  return drop_far_faces(std::move(result), scanner_positions.front(), p, rep);
}

std::optional<double> map_ceiling_height(const SemiOcTree& tree, double min_height) {
  const double r = tree.leaf_size();
  std::map<std::int64_t, std::size_t> per_layer;  // leaf layer (z key) → occupied leaves
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() == Label::kOccupied) ++per_layer[leaf_cell(o.key.k[2])];
  });
  auto centre_of = [r](std::int64_t layer) { return (double(layer) + 0.5) * r; };
  std::size_t floor = 0;
  for (const auto& [layer, n] : per_layer)
    if (std::abs(centre_of(layer)) < r) floor = std::max(floor, n);
  std::optional<double> best;
  std::size_t most = 0;
  for (const auto& [layer, n] : per_layer)
    if (centre_of(layer) > min_height && n > most) most = n, best = centre_of(layer);
  if (floor == 0 || 4 * most < floor) return std::nullopt;
  return best;
}

std::vector<DetectedOpening> detect_openings_in_map(const SemiOcTree& tree, double ceiling_height,
                                                    const std::vector<Point3>& scanner_positions,
                                                    const OpeningParams& params,
                                                    OpeningsReport* report) {
  const double r = tree.leaf_size();
  // Leaf layers (z key) whose centre is more than a leaf above the floor and
  // below the ceiling; in layer units, with a margin, so that a layer exactly a
  // leaf from a ceiling found by map_ceiling_height is always left out.
  const double top = ceiling_height / r - 1.5 - 1e-6;
  Cloud centres;
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccupied) return;
    const std::int64_t layer = leaf_cell(o.key.k[2]);
    if (layer >= 1 && double(layer) < top)
      centres.push_back(pcl::PointXYZ{float(o.center.x), float(o.center.y), float(o.center.z)});
  });
  // A surface near a leaf boundary leaves two layers of occupied leaves, whose
  // centres lie a leaf apart: one wall, not two parallel ones.
  OpeningParams p = params;
  p.ransac_distance = std::max(p.ransac_distance, 1.01 * r);
  return detect_openings(centres, ceiling_height, tree, scanner_positions, p, report);
}

double share_carved_behind(const DetectedOpening& o, const octomap::OcTree& map,
                           const std::vector<Point3>& scanner_positions) {
  const double r = map.getResolution();
  const Eigen::Vector3d along = o.corners[1] - o.corners[0];
  const Eigen::Vector3d up = o.corners[3] - o.corners[0];
  const Eigen::Vector3d centre = o.centre();
  // Beyond: the side of the plane with fewer scanners (the room is where they stand).
  Eigen::Vector3d beyond = o.wall_normal;
  int facing = 0;
  for (const Point3& s : scanner_positions)
    facing += (Eigen::Vector3d(s.x, s.y, s.z) - centre).dot(beyond) > 0 ? 1 : -1;
  if (facing > 0) beyond = -beyond;
  const double step = 0.5 * r;
  const int nu = std::max(1, int(std::ceil(along.norm() / step)));
  const int nv = std::max(1, int(std::ceil(up.norm() / step)));
  std::size_t carved = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Eigen::Vector3d q = o.corners[0] + along * ((i + 0.5) / nu) + up * ((j + 0.5) / nv);
      bool free = false;
      for (double depth : {1.5 * r, 2.5 * r}) {
        const Eigen::Vector3d b = q + depth * beyond;
        const octomap::OcTreeNode* n = map.search(b.x(), b.y(), b.z());
        free = free || (n && !map.isNodeOccupied(n));
      }
      carved += free;
    }
  return double(carved) / double(nu * nv);
}

std::size_t label_openings(SemiOcTree& tree, const std::vector<DetectedOpening>& openings) {
  std::set<std::tuple<unsigned, unsigned, unsigned>> done;
  std::size_t labelled = 0;
  // Half-leaf sampling of the rectangle reaches every leaf the plane passes
  // through, also where the wall is not aligned with the grid.
  const double step = 0.5 * tree.leaf_size();
  for (const DetectedOpening& o : openings) {
    const Eigen::Vector3d along = o.corners[1] - o.corners[0];
    const Eigen::Vector3d up = o.corners[3] - o.corners[0];
    const int nu = std::max(1, int(std::ceil(along.norm() / step)));
    const int nv = std::max(1, int(std::ceil(up.norm() / step)));
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const Eigen::Vector3d q = o.corners[0] + along * ((i + 0.5) / nu) + up * ((j + 0.5) / nv);
        octomap::OcTreeKey key;
        if (!tree.key_of(Point3(q.x(), q.y(), q.z()), key)) continue;
        if (!done.insert({key[0], key[1], key[2]}).second) continue;
        const auto oct = tree.find_octant(key);
        if (oct && oct->label() == Label::kOccupied) continue;
        tree.set_label(key, tree.leaf_level(), label_of(o.kind));
        ++labelled;
      }
  }
  return labelled;
}

}  // namespace semioctree
