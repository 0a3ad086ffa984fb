#include "semioctree/occlusion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "direction_angles.h"
#include "parallel_for.h"
#include "polynomial_atan2.h"
#include "scanner_limits.h"
#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree {

namespace {

// Bins of directions seen from an optical centre: 180·k rows of 1/k degree of
// elevation, row r holding about 360·k·cos(elevation) bins of azimuth (at least one), so
// that every bin spans about (1/k)° × (1/k)°. ReturnDirections' bins have k = 1; its
// depths (ReturnDirections::add_scan) a finer k.
struct DirectionBins {
  static constexpr int kMaxPerDegree = 8;
  int per_degree = 1, rows = 180;
  std::vector<int> count, first;
  int total = 0;
  // Per row edge r (0 … rows): the cosine and sine of row_edge(r); per row: of the azimuth
  // step 2π / count[r] from one column's edge to the next.
  std::vector<double> edge_cos, edge_sin, step_cos, step_sin;
  explicit DirectionBins(int k) : per_degree(k), rows(180 * k), count(rows), first(rows) {
    for (int r = 0; r < rows; ++r) {
      count[r] = std::max(1, int(std::lround(360.0 * k * std::cos(row_elevation(r)))));
      first[r] = total;
      total += count[r];
      step_cos.push_back(std::cos(2 * M_PI / count[r]));
      step_sin.push_back(std::sin(2 * M_PI / count[r]));
    }
    for (int r = 0; r <= rows; ++r) {
      edge_cos.push_back(std::cos(row_edge(r)));
      edge_sin.push_back(std::sin(row_edge(r)));
    }
  }
  // A direction as the bins index it: elevation in degrees above −90° (0–180), the
  // azimuth's fraction of the full turn from −180°, and the vector's length.
  struct Direction {
    double elevation = 0, fraction = 0, length = 0;
  };
  // False for a zero or non-finite vector (a zero vector lies in the horizon's bin of
  // azimuth 0).
  static bool direction(double dx, double dy, double dz, Direction& d) {
    // (sqrt, not hypot: the lengths of a scan's returns neither overflow nor underflow,
    // and hypot's care costs a third of a scan's pass over its returns.)
    const double horizontal2 = dx * dx + dy * dy, horizontal = std::sqrt(horizontal2);
    d.length = std::sqrt(horizontal2 + dz * dz);
    d.elevation = elevation_of(std::atan2(dz, horizontal));
    d.fraction = fraction(dx, dy);
    return std::isfinite(d.length) && d.length > 0;
  }
  int bin(const Direction& d) const {
    const int r = row(d.elevation);
    return first[r] + column(r, d.fraction);
  }
  // A return's vector with its angles from polynomial_atan2 (Angles::of), which bin_of
  // maps to bins of any k: one computation of the angles serves several binnings.
  struct Angles {
    double dx = 0, dy = 0, dz = 0, horizontal = 0, length = 0, up = 0, around = 0;
    // False as direction().
    static bool of(double x, double y, double z, Angles& a) {
      const double horizontal2 = x * x + y * y;
      a.dx = x, a.dy = y, a.dz = z;
      a.horizontal = std::sqrt(horizontal2);
      a.length = std::sqrt(horizontal2 + z * z);
      if (!(std::isfinite(a.length) && a.length > 0)) return false;
      a.up = detail::polynomial_atan2(z, a.horizontal);
      a.around = detail::polynomial_atan2(y, x);
      return true;
    }
  };
  // Angles::of for up to kSize vectors at once, lanes at a time (direction_angles): the
  // same values, bit for bit.
  struct AngleBatch {
    static constexpr std::size_t kSize = 256;
    double x[kSize], y[kSize], z[kSize];  // the vectors, set by the caller
    double horizontal[kSize], length[kSize], up[kSize], around[kSize];
    void compute(std::size_t n) {
      detail::direction_angles(n, x, y, z, horizontal, length, up, around);
    }
    // Whether vector j has angles (Angles::of's test).
    bool valid(std::size_t j) const { return std::isfinite(length[j]) && length[j] > 0; }
    // Vector j's angles; false as Angles::of.
    bool get(std::size_t j, Angles& a) const {
      if (!valid(j)) return false;
      a.dx = x[j], a.dy = y[j], a.dz = z[j];
      a.horizontal = horizontal[j], a.length = length[j], a.up = up[j], a.around = around[j];
      return true;
    }
  };
  // bin_of for the first n angles of a batch, lanes at a time (detail::direction_bins); a
  // lane whose margin straddles an edge, or whose vector has no angles, is worked out
  // alone (an invalid one's bin is not to be used).
  void bins_of(const AngleBatch& b, std::size_t n, int* bin) const {
    std::uint8_t edge[AngleBatch::kSize];
    detail::direction_bins(n, b.up, b.around, per_degree, rows, count.data(), first.data(), bin,
                           edge);
    Angles a;
    for (std::size_t j = 0; j < n; ++j)
      if (edge[j] && b.get(j, a)) bin[j] = bin_of(a);
  }
  // bin(d) of direction(dx, dy, dz, d) from the polynomial angles: their value ± their
  // error bound maps to one row (one column) whenever std::atan2's would give the same one
  // (the maps below only round and scale: they never decrease), so only where that margin
  // straddles an edge is std::atan2 asked.
  int bin_of(const Angles& a) const {
    constexpr double e = detail::kPolynomialAtan2Error;
    int r = row(elevation_of(a.up - e));
    if (r != row(elevation_of(a.up + e))) r = row(elevation_of(std::atan2(a.dz, a.horizontal)));
    int c = column(r, fraction_of(a.around - e));
    if (c != column(r, fraction_of(a.around + e))) c = column(r, fraction(a.dx, a.dy));
    return first[r] + c;
  }
  // The bin of a direction given as a vector (not zero).
  int bin_of(double dx, double dy, double dz) const {
    Direction d;
    direction(dx, dy, dz, d);
    return bin(d);
  }
  // The bin of row r holding azimuth fraction f ∈ [0, 1] (of the full turn from −180°).
  int column(int r, double f) const { return detail::direction_column(f, count[r]); }
  int row(double elevation) const { return detail::direction_row(elevation, per_degree, rows); }
  static double fraction(double dx, double dy) { return fraction_of(std::atan2(dy, dx)); }
  // An azimuth (radians, −π..π) as the fraction of the turn from −π; an elevation
  // (radians) as degrees above −90°.
  static double fraction_of(double azimuth) { return detail::turn_fraction(azimuth); }
  static double elevation_of(double up) { return detail::elevation_degrees(up); }
  // The centre elevation of row r (radians), and the centre azimuth fraction of its bin i.
  double row_elevation(int r) const { return ((r + 0.5) / per_degree - 90.0) * M_PI / 180.0; }
  double centre_fraction(int r, int i) const { return (i + 0.5) / count[r]; }
  // The edges of the bins: row r spans the elevations [row_edge(r), row_edge(r + 1)]
  // (radians), and its bin i the azimuths [column_edge(r, i), column_edge(r, i + 1)].
  double row_edge(int r) const { return (double(r) / per_degree - 90.0) * (M_PI / 180.0); }
  double column_edge(int r, int i) const { return -M_PI + (2 * M_PI / count[r]) * i; }
  // The centre direction of bin i of row r (unit length).
  Eigen::Vector3d centre(int r, int i) const {
    const double el = row_elevation(r), az = -M_PI + 2 * M_PI * centre_fraction(r, i);
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }
};

// The bins of k per degree, 1 ≤ k ≤ kMaxPerDegree.
const DirectionBins& direction_bins(int per_degree = 1) {
  static const std::vector<DirectionBins> bins = [] {
    std::vector<DirectionBins> all;
    for (int k = 1; k <= DirectionBins::kMaxPerDegree; ++k) all.emplace_back(k);
    return all;
  }();
  return bins[std::size_t(std::clamp(per_degree, 1, DirectionBins::kMaxPerDegree) - 1)];
}

// The directions and distances of a box's points seen from the optical centre, the box
// given by its corners lo ≤ hi relative to it: elevations in degrees above −90° and
// azimuth fractions as DirectionBins index them, bounds that hold for every point.
struct BoxDirections {
  double nearest = 0, farthest = 0;           // m; nearest 0: the box holds the centre
  double sin_lo = 0, sin_hi = 0;              // sines of the lowest and highest elevations
  double elevation_lo = 0, elevation_hi = 0;  // degrees above −90° (with angles)
  bool full_turn = true;                      // every azimuth (the box surrounds the vertical)
  double fraction_lo = 0, fraction_hi = 1;    // fraction_lo > fraction_hi: across −180°
};

// `angles` false: distances and sines only (no trigonometry).
BoxDirections box_directions(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                             bool angles = true) {
  BoxDirections d;
  const auto nearest = [](double l, double h) { return l > 0 ? l : (h < 0 ? -h : 0.0); };
  const auto farthest = [](double l, double h) { return std::max(std::abs(l), std::abs(h)); };
  const double nx = nearest(lo.x(), hi.x()), ny = nearest(lo.y(), hi.y());
  const double nz = nearest(lo.z(), hi.z());
  const double fx = farthest(lo.x(), hi.x()), fy = farthest(lo.y(), hi.y());
  const double fz = farthest(lo.z(), hi.z());
  d.nearest = std::sqrt(nx * nx + ny * ny + nz * nz);
  d.farthest = std::sqrt(fx * fx + fy * fy + fz * fz);
  // The lowest elevation is at the box's lowest z, seen from as far (above the centre)
  // or as near (below it) as the box reaches horizontally; the highest likewise.
  const double near_h = std::sqrt(nx * nx + ny * ny), far_h = std::sqrt(fx * fx + fy * fy);
  const auto sine = [](double z, double h) {
    const double r = std::sqrt(z * z + h * h);
    return r > 0 ? z / r : 0.0;
  };
  const double h_lo = lo.z() >= 0 ? far_h : near_h, h_hi = hi.z() >= 0 ? near_h : far_h;
  d.sin_lo = sine(lo.z(), h_lo);
  d.sin_hi = sine(hi.z(), h_hi);
  if (!angles) return d;
  constexpr double kDegrees = 180.0 / M_PI;
  d.elevation_lo = std::atan2(lo.z(), h_lo) * kDegrees + 90.0;
  d.elevation_hi = std::atan2(hi.z(), h_hi) * kDegrees + 90.0;
  if (near_h == 0) return d;  // the box's footprint holds the centre's: every azimuth
  // Otherwise the footprint lies within a half-plane through the centre: its corners'
  // azimuths about its middle's span less than a half turn.
  const double middle = std::atan2(0.5 * (lo.y() + hi.y()), 0.5 * (lo.x() + hi.x()));
  double from = 0, to = 0;
  for (const double x : {lo.x(), hi.x()})
    for (const double y : {lo.y(), hi.y()}) {
      const double a = std::remainder(std::atan2(y, x) - middle, 2 * M_PI);
      from = std::min(from, a);
      to = std::max(to, a);
    }
  const auto fraction = [](double azimuth) {
    const double f = (azimuth + M_PI) / (2 * M_PI);
    return f - std::floor(f);
  };
  d.full_turn = false;
  d.fraction_lo = fraction(middle + from);
  d.fraction_hi = fraction(middle + to);
  return d;
}

// f(r, i0, i1) for every row r of `b` that directions of `d` fall in, with the columns
// i0 ≤ i ≤ i1 they fall in (i1 ≥ count[r] across −180°: column i % count[r]), until f
// returns false.
template <class F>
void for_each_row_of(const DirectionBins& b, const BoxDirections& d, F&& f) {
  const int r0 = std::clamp(int(d.elevation_lo * b.per_degree), 0, b.rows - 1);
  const int r1 = std::clamp(int(d.elevation_hi * b.per_degree), 0, b.rows - 1);
  for (int r = r0; r <= r1; ++r) {
    const int n = b.count[r];
    int i0 = 0, i1 = n - 1;
    if (!d.full_turn) {
      i0 = b.column(r, d.fraction_lo);
      i1 = b.column(r, d.fraction_hi);
      if (i1 < i0) i1 += n;  // across −180°
    }
    if (!f(r, i0, i1)) return;
  }
}

// f(bin) for every bin of `b` that directions of `d` fall in, until f returns false.
template <class F>
void for_each_bin_of(const DirectionBins& b, const BoxDirections& d, F&& f) {
  for_each_row_of(b, d, [&](int r, int i0, int i1) {
    for (int i = i0; i <= i1; ++i)
      if (!f(b.first[r] + i % b.count[r])) return false;
    return true;
  });
}

// The range [lo, hi] of one component of the unit directions of a bin.
struct Range {
  double lo = -1, hi = 1;
};

// Bounds on the distance of a box's points that lie in a bin's directions, from the
// ranges of their components over the bin: a point p = t·u of the box with
// lo_a ≤ p_a ≤ hi_a on axis a and u_a > 0 has t ≥ lo_a / max u_a and t ≤ hi_a / min u_a
// (mirrored for u_a < 0). The bounds hold on each axis, so their tightest one holds.
struct BinDistance {
  double entry = 0;                                       // no point of it in the bin is nearer
  double exit = std::numeric_limits<double>::infinity();  // nor farther
  bool empty = false;  // no point of the box lies in the bin's directions
  void axis(double lo, double hi, const Range& u) {
    if ((lo > 0 && u.hi <= 0) || (hi < 0 && u.lo >= 0) || (hi <= 0 && u.lo > 0) ||
        (lo >= 0 && u.hi < 0))
      empty = true;
    if (lo > 0 && u.hi > 0) entry = std::max(entry, lo / u.hi);
    if (hi < 0 && u.lo < 0) entry = std::max(entry, hi / u.lo);
    if (u.lo > 0) exit = std::min(exit, hi / u.lo);
    if (u.hi < 0) exit = std::min(exit, lo / u.hi);
  }
};

// Margin on the components' ranges: far above the rounding of the angles that decide
// the bin of a direction, and of the rotations that step from column to column.
constexpr double kRangeMargin = 1e-9;

// The range of cos·a over elevations with cos ∈ c (c.lo ≥ 0) and a ∈ a.
Range times(const Range& c, const Range& a) {
  return {(a.lo < 0 ? c.hi : c.lo) * a.lo - kRangeMargin,
          (a.hi < 0 ? c.lo : c.hi) * a.hi + kRangeMargin};
}

// Whether a point at distance² `length2` lies more than `tolerance` beyond `cm`, a depth
// in centimetres (0 or the largest value: none).
bool beyond_depth(std::uint16_t cm, double length2, double tolerance) {
  if (cm == 0 || cm == 65535) return false;
  const double limit = 0.01 * cm + tolerance;
  return length2 > limit * limit;
}

}  // namespace

ReturnDirections::ReturnDirections() : bins_(std::size_t(direction_bins().total), 0) {}

void ReturnDirections::add(const Eigen::Vector3d& d) {
  DirectionBins::Direction dir;
  if (DirectionBins::direction(d.x(), d.y(), d.z(), dir))
    bins_[std::size_t(direction_bins().bin(dir))] = 1;
}

void ReturnDirections::close_gaps() {
  const DirectionBins& b = direction_bins();
  std::vector<std::uint8_t> grown(bins_);
  for (int r = 0; r < b.rows; ++r)
    for (int i = 0; i < b.count[r]; ++i) {
      if (!bins_[std::size_t(b.first[r] + i)]) continue;
      const double f = b.centre_fraction(r, i);
      for (int rr = std::max(0, r - 1); rr <= std::min(b.rows - 1, r + 1); ++rr) {
        const int n = b.count[rr], j = b.column(rr, f);
        for (int dj = -1; dj <= 1; ++dj)  // azimuth wraps around
          grown[std::size_t(b.first[rr] + (j + dj + n) % n)] = 1;
      }
    }
  bins_.swap(grown);
}

void ReturnDirections::open_above() {
  // Rows from the zenith down to the horizon; `covered` says, per degree of azimuth,
  // whether a row above (or this one) had returns there. A bin spans the degrees its
  // azimuth range touches; it opens when none of them is covered from above.
  const DirectionBins& b = direction_bins();
  constexpr int kSectors = 360;
  std::vector<std::uint8_t> covered(kSectors, 0);
  for (int r = b.rows - 1; r >= b.rows / 2; --r) {
    const int n = b.count[r];
    std::vector<std::uint8_t> covered_below(covered);
    for (int i = 0; i < n; ++i) {
      const int s0 = int(std::floor(double(i) * kSectors / n));
      const int s1 = std::min(kSectors, int(std::ceil(double(i + 1) * kSectors / n)));
      std::uint8_t& bin = bins_[std::size_t(b.first[r] + i)];
      if (bin) {
        std::fill(covered_below.begin() + s0, covered_below.begin() + s1, std::uint8_t(1));
      } else if (std::none_of(covered.begin() + s0, covered.begin() + s1,
                              [](std::uint8_t c) { return c != 0; })) {
        bin = 1;
      }
    }
    covered.swap(covered_below);
  }
}

void ReturnDirections::open_within(const PlatformBody& body, double min_range) {
  if (!(body.radius > 0) || !(min_range > 0)) return;
  const DirectionBins& b = direction_bins();
  for (int r = 0; r < b.rows; ++r) {
    // Row r spans elevations [lo, hi]; the body is convex and holds the optical centre,
    // so a segment lies inside it when its far end does, for every elevation of the row.
    const double lo = (r - 90.0) * M_PI / 180.0, hi = lo + M_PI / 180.0;
    const double widest = (lo <= 0 && hi >= 0) ? 1.0 : std::max(std::cos(lo), std::cos(hi));
    const bool inside = min_range * widest <= body.radius &&
                        min_range * std::sin(hi) <= body.above &&
                        -min_range * std::sin(lo) <= body.below;
    if (inside) std::fill_n(bins_.begin() + b.first[r], b.count[r], std::uint8_t(1));
  }
}

void ReturnDirections::open_where_free(const SemiOcTree& map, const Point3& optical_centre,
                                       double min_range) {
  if (!(min_range > 0) || map.coarse_count() == 0) return;
  const DirectionBins& b = direction_bins();
  auto seen_free = [](Label l) {
    return l == Label::kEmpty || l == Label::kScan || l == Label::kNbv || l == Label::kOut ||
           l == Label::kDoor || l == Label::kWindow;
  };
  for (int r = 0; r < b.rows; ++r)
    for (int i = 0; i < b.count[r]; ++i) {
      std::uint8_t& bin = bins_[std::size_t(b.first[r] + i)];
      if (bin) continue;
      const Eigen::Vector3d d = min_range * b.centre(r, i);
      const Point3 end(optical_centre.x + d.x(), optical_centre.y + d.y(),
                       optical_centre.z + d.z());
      const TraversalEnd e = map.traverse(optical_centre, end, [&](const RayStep& step) {
        return step.node && seen_free(step.label());
      });
      if (e == TraversalEnd::kReachedEnd) bin = 1;
    }
}

void ReturnDirections::open_far_edged_holes(double min_range, double elevation_min_deg,
                                            double elevation_max_deg) {
  if (!(min_range > 0) || nearest_cm_.empty()) return;
  const DirectionBins& b = direction_bins();
  const auto none = [&](int bin) { return nearest_cm_[std::size_t(bin)] == 0; };
  // Rows wholly within the elevation limits (row r spans [r − 90°, r − 89°]).
  const int row_lo = int(std::ceil(elevation_min_deg + 90.0));
  const int row_hi = int(std::floor(elevation_max_deg + 90.0)) - 1;
  std::vector<int> row_of(std::size_t(b.total));
  for (int r = 0; r < b.rows; ++r) std::fill_n(row_of.begin() + b.first[r], b.count[r], r);
  // f(neighbour bin) for the bins beside `bin` in its row (azimuth wraps around) and
  // those of the rows above and below whose azimuths overlap it.
  const auto for_each_neighbour = [&](int bin, auto&& f) {
    const int r = row_of[std::size_t(bin)], i = bin - b.first[r], n = b.count[r];
    f(b.first[r] + (i + 1) % n);
    f(b.first[r] + (i + n - 1) % n);
    const double f0 = double(i) / n, f1 = double(i + 1) / n;
    for (const int rr : {r - 1, r + 1}) {
      if (rr < 0 || rr >= b.rows) continue;
      const int j1 = std::min(b.count[rr] - 1, int(std::ceil(f1 * b.count[rr])) - 1);
      for (int j = b.column(rr, f0); j <= j1; ++j) f(b.first[rr] + j);
    }
  };
  std::vector<std::uint8_t> visited(std::size_t(b.total), 0);
  std::vector<int> hole, todo;
  for (int start = 0; start < b.total; ++start) {
    if (visited[std::size_t(start)] || !none(start)) continue;
    // The hole holding `start`: its bins, its nearest edge return, whether it leaves the
    // rows within the elevation limits.
    hole.clear();
    todo.assign(1, start);
    visited[std::size_t(start)] = 1;
    std::uint16_t edge_cm = 0;  // 0: no edge yet
    bool within_limits = true;
    while (!todo.empty()) {
      const int bin = todo.back();
      todo.pop_back();
      hole.push_back(bin);
      const int r = row_of[std::size_t(bin)];
      within_limits &= r >= row_lo && r <= row_hi;
      for_each_neighbour(bin, [&](int m) {
        if (!none(m)) {
          const std::uint16_t cm = nearest_cm_[std::size_t(m)];
          edge_cm = edge_cm == 0 ? cm : std::min(edge_cm, cm);
        } else if (!visited[std::size_t(m)]) {
          visited[std::size_t(m)] = 1;
          todo.push_back(m);
        }
      });
    }
    // (A hole with no edge at all is every direction: a scan without returns.)
    if (within_limits && edge_cm != 0 && 0.01 * edge_cm >= 2.0 * min_range)
      for (const int bin : hole) bins_[std::size_t(bin)] = 1;
  }
}

bool ReturnDirections::has(double dx, double dy, double dz) const {
  return bins_[std::size_t(direction_bins().bin_of(dx, dy, dz))] != 0;
}

void ReturnDirections::add_scan(const Cloud& scan, const Eigen::Matrix3d& scanner_to_map,
                                unsigned threads, int expected_depth_bins_per_degree) {
  depth_per_degree_ = 0;
  depth_cm_.clear();
  depth_runs_.clear();
  degree_depths_.clear();
  first_depth_run_.clear();
  const unsigned workers = detail::thread_count(threads);
  const std::size_t chunk = 1 << 16, chunks = (scan.size() + chunk - 1) / chunk;
  // f(batch, n) for the returns of chunk c, in the map frame, a batch of n at a time, their
  // angles computed (Angles::of's values; AngleBatch::get tells the returns with angles).
  auto each_batch = [&](std::size_t c, auto&& f) {
    DirectionBins::AngleBatch batch;
    for (std::size_t i = c * chunk, end = std::min(scan.size(), i + chunk); i < end;) {
      const std::size_t n = std::min(end - i, DirectionBins::AngleBatch::kSize);
      for (std::size_t j = 0; j < n; ++j, ++i) {
        const Eigen::Vector3d v = scanner_to_map * Eigen::Vector3d(scan[i].x, scan[i].y, scan[i].z);
        batch.x[j] = v.x(), batch.y[j] = v.y(), batch.z[j] = v.z();
      }
      batch.compute(n);
      f(batch, n);
    }
  };
  // The depths, per bin of k a degree: the nearest and farthest return and their count
  // (sized for the bins once, by a worker's first chunk).
  struct Depths {
    std::vector<float> nearest, farthest;
    std::vector<std::uint8_t> count;
    void size_for(const DirectionBins& bins) {
      if (!count.empty()) return;
      nearest.assign(std::size_t(bins.total), std::numeric_limits<float>::infinity());
      farthest.assign(std::size_t(bins.total), 0.0f);
      count.assign(std::size_t(bins.total), 0);
    }
    // The returns of a batch with angles, their bins in `bins` (as bins_of gives them).
    void add(const DirectionBins::AngleBatch& batch, std::size_t n, const int* bins) {
      for (std::size_t j = 0; j < n; ++j) {
        if (!batch.valid(j)) continue;
        const auto b = std::size_t(bins[j]);
        const auto range = float(batch.length[j]);
        nearest[b] = std::min(nearest[b], range);
        farthest[b] = std::max(farthest[b], range);
        if (count[b] < 255) ++count[b];
      }
    }
  };
  // Pass 1: the 1° bins with returns, and how many returns they hold. With the depths'
  // k expected (the scan before's, say), their depths are gathered in the same pass from
  // the same angles; pass 2 reads the returns again only if k turns out otherwise.
  const DirectionBins& degree = direction_bins(1);
  const int expected_k = expected_depth_bins_per_degree;
  const bool gather_depths = expected_k >= 1 && expected_k <= DirectionBins::kMaxPerDegree;
  const DirectionBins& expected_bins = direction_bins(gather_depths ? expected_k : 1);
  constexpr float kNone = std::numeric_limits<float>::infinity();
  std::vector<std::vector<float>> nearest(workers);
  std::vector<std::size_t> returns(workers, 0);
  std::vector<Depths> per_worker(workers);
  detail::parallel_for(chunks, workers, 1, [&](std::size_t c, unsigned w) {
    if (nearest[w].empty()) nearest[w].assign(std::size_t(degree.total), kNone);
    if (gather_depths) per_worker[w].size_for(expected_bins);
    // Counted here, added once a chunk: the workers' counts share a cache line.
    std::size_t chunk_returns = 0;
    each_batch(c, [&](const DirectionBins::AngleBatch& batch, std::size_t n) {
      int bins[DirectionBins::AngleBatch::kSize];
      degree.bins_of(batch, n, bins);
      for (std::size_t j = 0; j < n; ++j) {
        if (!batch.valid(j)) continue;
        float& near = nearest[w][std::size_t(bins[j])];
        near = std::min(near, float(batch.length[j]));
        ++chunk_returns;
      }
      if (gather_depths) {
        expected_bins.bins_of(batch, n, bins);
        per_worker[w].add(batch, n, bins);
      }
    });
    returns[w] += chunk_returns;
  });
  std::size_t total_returns = 0;
  for (unsigned w = 0; w < workers; ++w) total_returns += returns[w];
  nearest_cm_.assign(std::size_t(degree.total), 0);
  std::size_t hit_bins = 0;
  for (std::size_t b = 0; b < nearest_cm_.size(); ++b) {
    float n = kNone;
    for (const std::vector<float>& v : nearest)
      if (!v.empty()) n = std::min(n, v[b]);
    if (n == kNone) continue;
    nearest_cm_[b] = std::uint16_t(std::clamp(std::floor(100.0 * double(n)), 1.0, 65535.0));
    bins_[b] = 1;
    ++hit_bins;
  }
  if (hit_bins == 0) return;
  // Pass 2 (unless gathered above): the depths, in bins holding about 4 returns each (two
  // beams along each axis).
  const int k =
      std::clamp(int(std::floor(std::sqrt(double(total_returns) / double(hit_bins) / 4.0))), 1,
                 DirectionBins::kMaxPerDegree);
  const DirectionBins& bins = direction_bins(k);
  if (!gather_depths || k != expected_k) {
    per_worker.assign(workers, Depths{});
    detail::parallel_for(chunks, workers, 1, [&](std::size_t c, unsigned w) {
      per_worker[w].size_for(bins);
      each_batch(c, [&](const DirectionBins::AngleBatch& batch, std::size_t n) {
        int at[DirectionBins::AngleBatch::kSize];
        bins.bins_of(batch, n, at);
        per_worker[w].add(batch, n, at);
      });
    });
  }
  constexpr int kMinReturns = 4;
  depth_cm_.assign(std::size_t(bins.total), 0);
  for (std::size_t b = 0; b < depth_cm_.size(); ++b) {
    float nearest = std::numeric_limits<float>::infinity(), farthest = 0;
    int count = 0;
    for (const Depths& d : per_worker) {
      if (d.count.empty()) continue;
      nearest = std::min(nearest, d.nearest[b]);
      farthest = std::max(farthest, d.farthest[b]);
      count += d.count[b];
    }
    if (count < kMinReturns) continue;
    const double depth = 2.0 * double(farthest) - double(nearest);
    depth_cm_[b] = std::uint16_t(std::clamp(std::ceil(100.0 * depth), 1.0, 65535.0));
  }
  depth_per_degree_ = k;
  first_depth_run_.resize(std::size_t(bins.rows));
  for (int r = 0; r < bins.rows; ++r) {
    first_depth_run_[std::size_t(r)] = static_cast<std::uint32_t>(depth_runs_.size());
    for (int c = 0; c < bins.count[r]; c += kDepthRun) {
      DepthSummary run;
      for (int i = c, end = std::min(bins.count[r], c + kDepthRun); i < end; ++i)
        run.add(depth_cm_[std::size_t(bins.first[r] + i)]);
      depth_runs_.push_back(run);
    }
  }
  summarize_degree_depths();
}

void ReturnDirections::summarize_degree_depths() {
  // A direction of 1° row R lies at an elevation e in [R, R + 1) degrees, so in depth row
  // ⌊e·k⌋, one of R·k … R·k + k − 1; of column c of n, its azimuth fraction f lies in
  // [c / n, (c + 1) / n), so in depth column ⌊f·m⌋ of the depth row's m, one of
  // ⌊c·m / n⌋ … ⌈(c + 1)·m / n⌉ − 1. One more row and column on each side cover the
  // rounding at the edges.
  const DirectionBins& degree = direction_bins(1);
  const DirectionBins& fine = direction_bins(depth_per_degree_);
  const int k = depth_per_degree_;
  degree_depths_.assign(std::size_t(degree.total), DepthSummary{});
  for (int big = 0; big < degree.rows; ++big) {
    const std::int64_t n = degree.count[std::size_t(big)];
    DepthSummary* out = &degree_depths_[std::size_t(degree.first[std::size_t(big)])];
    for (int r = std::max(0, big * k - 1); r <= std::min(fine.rows - 1, big * k + k); ++r) {
      const std::int64_t m = fine.count[std::size_t(r)];
      const std::uint16_t* row = &depth_cm_[std::size_t(fine.first[std::size_t(r)])];
      const auto at = [&](std::int64_t i) {  // −1 ≤ i ≤ m + 1
        if (i < 0) i += m;
        while (i >= m) i -= m;
        return row[i];
      };
      // Column c: the depth columns [⌊c·m / n⌋, ⌊(c + 1)·m / n⌋) one after the other, then
      // the one before, ⌊(c + 1)·m / n⌋ and, when (c + 1)·m / n is not whole, the next.
      std::int64_t i = 0;
      for (std::int64_t c = 0; c < n; ++c) {
        const std::int64_t from = c * m / n, to = (c + 1) * m / n;
        DepthSummary s;
        for (; i < to; ++i) s.add(row[i]);
        s.add(at(from - 1));
        s.add(at(to));
        if ((c + 1) * m % n != 0) s.add(at(to + 1));
        out[c].add(s);
      }
    }
  }
}

void ReturnDirections::summarize_depths(const std::uint16_t* row, const DepthSummary* runs, int c0,
                                        int c1, DepthSummary& s) {
  // The columns before the first whole run and after the last, bin by bin (without a
  // branch on each); the whole runs between, a summary at a time.
  const auto bins = [&](int from, int to) {  // columns [from, to)
    DepthSummary part;                       // (a local the row's reads cannot alias)
    for (int c = from; c < to; ++c) part.add(row[c]);
    s.add(part);
  };
  int run = (c0 + kDepthRun - 1) / kDepthRun;  // the first run starting at or after c0
  if ((run + 1) * kDepthRun - 1 > c1) {        // no whole run
    bins(c0, c1 + 1);
    return;
  }
  bins(c0, run * kDepthRun);
  for (; (run + 1) * kDepthRun - 1 <= c1; ++run) s.add(runs[run]);
  bins(run * kDepthRun, c1 + 1);
}

ReturnDirections::BoxSight ReturnDirections::may_see_box(const Eigen::Vector3d& lo,
                                                         const Eigen::Vector3d& hi,
                                                         double tolerance) const {
  const BoxDirections d = box_directions(lo, hi);
  if (!(d.nearest > 0)) return {};
  // Returns per 1° bin; depths per depth bin (a coarser reading of the depths would take
  // a surface seen obliquely for nearer than it is over much of a degree).
  bool all_have = true, none_has = true;
  DepthSummary by_degree;  // a bound on the box's depths (see degree_depths_)
  const bool depths_recorded = !depth_cm_.empty();
  for_each_bin_of(direction_bins(), d, [&](int bin) {
    const bool has = bins_[std::size_t(bin)] != 0;
    all_have &= has;
    none_has &= !has;
    if (depths_recorded) by_degree.add(degree_depths_[std::size_t(bin)]);
    return all_have || none_has;
  });
  if (none_has) return {false, true};
  if (!all_have || !depths_recorded) return {all_have, false};
  // (At most one of the two holds; what holds of the bound holds of the depths.)
  if (by_degree.greatest == 0 || !beyond_depth(by_degree.least, d.farthest * d.farthest, tolerance))
    return {true, false};
  if (!by_degree.some_missing && beyond_depth(by_degree.greatest, d.nearest * d.nearest, tolerance))
    return {false, true};
  // First each depth bin against the whole box's nearest and farthest points (cheap);
  // where that proves neither, each bin against the distances of the box's points in
  // its own directions (BinDistance): a box before a wall seen obliquely, or behind one,
  // spans bins whose depths differ by more than the box is deep.
  // (beyond_depth grows with the depth: the least depth decides whether every bin's is
  // beyond the farthest point, the greatest whether the nearest is beyond every one.)
  const DirectionBins& b = direction_bins(depth_per_degree_);
  DepthSummary depths;
  for_each_row_of(b, d, [&](int r, int i0, int i1) {
    const int n = b.count[std::size_t(r)];
    const std::uint16_t* row = &depth_cm_[std::size_t(b.first[std::size_t(r)])];
    const DepthSummary* runs = &depth_runs_[first_depth_run_[std::size_t(r)]];
    summarize_depths(row, runs, i0, std::min(i1, n - 1), depths);
    if (i1 >= n) summarize_depths(row, runs, 0, i1 - n, depths);  // across −180°
    return true;
  });
  bool all_before =
      depths.greatest == 0 || !beyond_depth(depths.least, d.farthest * d.farthest, tolerance);
  bool all_behind =
      !depths.some_missing && beyond_depth(depths.greatest, d.nearest * d.nearest, tolerance);
  if (all_before || all_behind) return {all_before, all_behind};
  all_before = all_behind = true;
  const double farthest2 = d.farthest * d.farthest, nearest2 = d.nearest * d.nearest;
  for_each_row_of(b, d, [&](int r, int i0, int i1) {
    const double el0 = b.row_edge(r), el1 = b.row_edge(r + 1);
    const double c0 = b.edge_cos[std::size_t(r)], c1 = b.edge_cos[std::size_t(r) + 1];
    const Range cos_el{std::max(0.0, std::min(c0, c1) - kRangeMargin),
                       (el0 <= 0 && el1 >= 0 ? 1.0 : std::max(c0, c1)) + kRangeMargin};
    const Range uz{b.edge_sin[std::size_t(r)] - kRangeMargin,
                   b.edge_sin[std::size_t(r) + 1] + kRangeMargin};
    const int n = b.count[r];
    // Each column's first edge, stepped from column to column by a rotation.
    const double step_cos = b.step_cos[std::size_t(r)], step_sin = b.step_sin[std::size_t(r)];
    const double first_edge = b.column_edge(r, i0);
    double az_cos = std::cos(first_edge), az_sin = std::sin(first_edge);
    for (int i = i0; i <= i1; ++i) {
      const double next_cos = az_cos * step_cos - az_sin * step_sin;
      const double next_sin = az_sin * step_cos + az_cos * step_sin;
      Range cos_az, sin_az;  // [-1, 1] for the polar rows' wide bins
      if (n >= 4) {
        cos_az = {std::min(az_cos, next_cos), std::max(az_cos, next_cos)};
        sin_az = {std::min(az_sin, next_sin), std::max(az_sin, next_sin)};
        if (az_sin <= 0 && next_sin >= 0 && az_cos + next_cos > 0) cos_az.hi = 1;   // 0
        if (az_sin >= 0 && next_sin <= 0 && az_cos + next_cos < 0) cos_az.lo = -1;  // ±π
        if (az_cos >= 0 && next_cos <= 0 && az_sin + next_sin > 0) sin_az.hi = 1;   // π/2
        if (az_cos <= 0 && next_cos >= 0 && az_sin + next_sin < 0) sin_az.lo = -1;  // −π/2
      }
      // The whole box's bounds first: only a bin they leave undecided needs its own.
      const std::uint16_t cm = depth_cm_[std::size_t(b.first[r] + i % n)];
      const bool check_before = all_before && beyond_depth(cm, farthest2, tolerance);
      const bool check_behind = all_behind && !beyond_depth(cm, nearest2, tolerance);
      if (check_before || check_behind) {
        BinDistance t;
        t.axis(lo.x(), hi.x(), times(cos_el, cos_az));
        t.axis(lo.y(), hi.y(), times(cos_el, sin_az));
        t.axis(lo.z(), hi.z(), uz);
        if (!t.empty) {
          const double before = std::min(t.exit, d.farthest);
          const double behind = std::max(t.entry, d.nearest);
          if (check_before) all_before = !beyond_depth(cm, before * before, tolerance);
          if (check_behind) all_behind = beyond_depth(cm, behind * behind, tolerance);
          if (!(all_before || all_behind)) return false;
        }
      }
      az_cos = next_cos;
      az_sin = next_sin;
    }
    return true;
  });
  return {all_before, all_behind};
}

bool ReturnDirections::behind_surface(double dx, double dy, double dz, double tolerance) const {
  if (depth_cm_.empty()) return false;
  return beyond_depth(depth_cm_[std::size_t(direction_bins(depth_per_degree_).bin_of(dx, dy, dz))],
                      dx * dx + dy * dy + dz * dz, tolerance);
}

bool ReturnDirections::may_see(double dx, double dy, double dz, double tolerance) const {
  // The polynomial angles (the bins std::atan2's give, at a fraction of the cost: the
  // occlusion study asks this for every segment).
  DirectionBins::Angles a;
  if (!DirectionBins::Angles::of(dx, dy, dz, a)) return true;
  if (!bins_[std::size_t(direction_bins().bin_of(a))]) return false;
  return depth_cm_.empty() ||
         within_depth(direction_bins(depth_per_degree_).bin_of(a), a.length, tolerance);
}

bool ReturnDirections::within_depth(int depth_bin, double length, double tolerance) const {
  return !beyond_depth(depth_cm_[std::size_t(depth_bin)], length * length, tolerance);
}

void ReturnDirections::may_see_each(std::size_t n, const double* dx, const double* dy,
                                    const double* dz, double tolerance, std::uint8_t* out) const {
  constexpr std::size_t kSize = DirectionBins::AngleBatch::kSize;
  const DirectionBins& degree = direction_bins();
  const DirectionBins* depth = depth_cm_.empty() ? nullptr : &direction_bins(depth_per_degree_);
  DirectionBins::AngleBatch batch;
  int bins[kSize], depth_bins[kSize];
  for (std::size_t start = 0; start < n; start += kSize) {
    const std::size_t m = std::min(kSize, n - start);
    std::copy_n(dx + start, m, batch.x);
    std::copy_n(dy + start, m, batch.y);
    std::copy_n(dz + start, m, batch.z);
    batch.compute(m);
    degree.bins_of(batch, m, bins);
    if (depth) depth->bins_of(batch, m, depth_bins);
    for (std::size_t j = 0; j < m; ++j) {
      bool may = true;  // (no angles: the optical centre itself)
      if (batch.valid(j))
        may = bins_[std::size_t(bins[j])] &&
              (!depth || within_depth(depth_bins[j], batch.length[j], tolerance));
      out[start + j] = may;
    }
  }
}

std::size_t ReturnDirections::bins_with_returns() const {
  return std::size_t(std::count(bins_.begin(), bins_.end(), std::uint8_t(1)));
}

std::shared_ptr<const ReturnDirections> return_directions(const Cloud& scan,
                                                          const Eigen::Matrix3d& scanner_to_map,
                                                          const ReturnDirectionsOptions& options) {
  auto r = std::make_shared<ReturnDirections>();
  r->add_scan(scan, scanner_to_map, options.threads, options.expected_depth_bins_per_degree);
  r->close_gaps();
  if (options.open_above) r->open_above();
  r->open_within(options.body, options.min_range);
  if (options.map) r->open_where_free(*options.map, options.optical_centre, options.min_range);
  if (options.open_far_edged_holes)
    r->open_far_edged_holes(options.min_range, options.elevation_min_deg,
                            options.elevation_max_deg);
  return r;
}

std::shared_ptr<const ReturnDirections> return_directions_in_map(const octomap::OcTree& map,
                                                                 const Point3& optical_centre,
                                                                 const ScannerView& limits,
                                                                 unsigned threads,
                                                                 MapReturnsReport* report) {
  MapReturnsReport rep;
  auto out = std::make_shared<ReturnDirections>();
  const octomap::point3d origin(float(optical_centre.x), float(optical_centre.y),
                                float(optical_centre.z));
  const octomap::OcTreeNode* own = map.search(origin);
  rep.origin_free = own && !map.isNodeOccupied(own);
  const DirectionBins& b = direction_bins();
  // Rows overlapping the elevation limits (a row is 1°, from −90°).
  const int row_lo = std::clamp(int(std::floor(limits.elevation_min_deg + 90.0)), 0, b.rows - 1);
  const int row_hi = std::clamp(int(std::ceil(limits.elevation_max_deg + 90.0)) - 1, 0, b.rows - 1);
  std::vector<std::uint8_t> reached(std::size_t(b.total), 0);
  if (rep.origin_free && row_lo <= row_hi) {
    detail::parallel_for(std::size_t(row_hi - row_lo + 1), detail::thread_count(threads), 1,
                         [&](std::size_t k, unsigned) {
                           const int r = row_lo + int(k);
                           for (int i = 0; i < b.count[r]; ++i) {
                             const Eigen::Vector3f d = b.centre(r, i).cast<float>();
                             octomap::point3d end;
                             if (map.castRay(origin, octomap::point3d(d.x(), d.y(), d.z()), end,
                                             false, limits.max_range))
                               reached[std::size_t(b.first[r] + i)] = 1;
                           }
                         });
  }
  for (int r = row_lo; r <= row_hi; ++r) {
    rep.bins_tested += std::size_t(b.count[r]);
    for (int i = 0; i < b.count[r]; ++i) {
      if (!reached[std::size_t(b.first[r] + i)]) continue;
      ++rep.bins_reached;
      out->add(b.centre(r, i));
    }
  }
  out->close_gaps();
  if (report) *report = rep;
  return out;
}

namespace {

// A scan taken in a doorway (as surveyors do to link rooms) stands in the door:
// that door is where it stands, not one it looks through, so its leaves do not
// make what the scan sees `out` (counted, everything that scan alone saw, on
// either side, was out). A view stands in a door when a door leaf lies within
// kDoorwayReach of its optical centre; that door is those leaves and the door
// leaves connected to them, and only they are exempt: another door seen from
// the doorway still leads out. Windows do not count: nobody scans from one.
constexpr double kDoorwayReach = 0.3;  // m
// A door is at most 2.5 × 2.6 m; a region of door leaves far larger than that
// at the finest leaf is not one door, and the search stops there.
constexpr std::size_t kMaxDoorCells = 200000;

// Door octants (min-corner key and level, packed) of the door the view stands in.
using DoorSet = std::unordered_set<std::uint64_t>;

DoorSet own_door(const SemiOcTree& tree, const Point3& c) {
  DoorSet door;
  const double r = tree.leaf_size();
  octomap::OcTreeKey centre;
  if (!tree.key_of(c, centre)) return door;
  auto door_at = [&](const octomap::OcTreeKey& k) -> std::optional<Octant> {
    const std::optional<Octant> o = tree.find_octant(k);
    if (o && o->label() == Label::kDoor) return o;
    return std::nullopt;
  };
  // Leaf cells (keys) to visit, seeded with the door leaves within reach.
  std::vector<octomap::OcTreeKey> todo;
  octomap::KeySet seen;
  const int n = int(std::ceil(kDoorwayReach / r)) + 1;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const octomap::OcTreeKey q(centre[0] + i, centre[1] + j, centre[2] + k);
        const std::optional<Octant> o = door_at(q);
        if (!o) continue;
        // Distance from the optical centre to the door octant's box.
        const double h = o->size / 2;
        const double dx = std::max(0.0, std::abs(c.x - o->center.x) - h);
        const double dy = std::max(0.0, std::abs(c.y - o->center.y) - h);
        const double dz = std::max(0.0, std::abs(c.z - o->center.z) - h);
        if (dx * dx + dy * dy + dz * dz <= kDoorwayReach * kDoorwayReach && seen.insert(q).second)
          todo.push_back(q);
      }
  // The connected door leaves (26-neighbours), at leaf resolution.
  while (!todo.empty() && seen.size() < kMaxDoorCells) {
    const octomap::OcTreeKey q = todo.back();
    todo.pop_back();
    const std::optional<Octant> o = door_at(q);
    if (!o) continue;
    door.insert(pack_octant_key(o->key, o->level));
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k) {
          const octomap::OcTreeKey m(q[0] + i, q[1] + j, q[2] + k);
          if (!seen.count(m) && door_at(m)) {
            seen.insert(m);
            todo.push_back(m);
          }
        }
  }
  return door;
}

// Per-view constants: the elevation limits as bounds on dz / range, so that a
// segment needs no trigonometry, and the door the view stands in (if any).
struct ViewLimits {
  const ScannerView* view;
  detail::ScannerLimits range_and_elevation;
  DoorSet own_door;  // empty: the view stands in no door
};

ViewLimits limits_of(const SemiOcTree& tree, const ScannerView& v) {
  return {&v, detail::ScannerLimits(v), own_door(tree, v.position)};
}

// The best a segment from the view that crosses an octant labelled `l` can be seen: an
// occupied octant hides, a window or a door the view does not stand in leaves it seen
// through an opening, anything else lets it be seen directly.
Visibility best_across(const ViewLimits& lim, Label l, const octomap::OcTreeKey& key,
                       unsigned level) {
  if (l == Label::kOccupied) return Visibility::kHidden;
  if (l == Label::kWindow ||
      (l == Label::kDoor && !lim.own_door.count(pack_octant_key(key, level))))
    return Visibility::kThroughOpening;
  return Visibility::kDirect;
}

// Occupied octants entered at the very end of a segment only touch its end
// point (a sample on a lattice corner shared with them): they hide nothing.
constexpr double kEndTolerance = 1e-9;

// kMarked: the tree's marks are fresh (study_occlusion), so refined space
// without blockers can be crossed in one step. `direct_or_not`: only whether p is seen
// directly matters; a segment that crosses an opening then ends there, as kThroughOpening
// whatever lies beyond (it can no longer be direct).
// `returns_asked`: the caller found that the view's returns may see p.
template <bool kMarked>
Visibility segment_visibility(const SemiOcTree& tree, const ViewLimits& lim, const Point3& p,
                              bool direct_or_not = false, bool returns_asked = false) {
  const Point3& o = lim.view->position;
  const double dx = p.x - o.x, dy = p.y - o.y, dz = p.z - o.z;
  if (!lim.range_and_elevation.in_view(o, p)) return Visibility::kHidden;
  if (!returns_asked && lim.view->returns &&
      !lim.view->returns->may_see(dx, dy, dz, tree.leaf_size()))
    return Visibility::kHidden;
  bool through_opening = false, blocked = false;
  auto visit = [&](const RayStep& s) {
    if (s.t_enter >= 1.0 - kEndTolerance) return false;
    if (s.summary) return true;  // no occupied, door or window octant inside
    const Label l = s.label();
    // The scanner's own octant never hides anything (noise can put a point in it).
    if (l == Label::kOccupied && s.t_enter > 0.0) {
      blocked = true;
      return false;
    }
    through_opening |= best_across(lim, l, s.key, s.level) == Visibility::kThroughOpening;
    return !(through_opening && direct_or_not);
  };
  if (kMarked)
    tree.traverse_marked(o, p, visit);
  else
    tree.traverse(o, p, visit);
  if (blocked) return Visibility::kHidden;
  return through_opening ? Visibility::kThroughOpening : Visibility::kDirect;
}

// The better of `floor` and the best visibility of p from `views`, and in `view` the first
// view giving it if better than `floor` (else 0). Once p is known seen through an opening,
// a view can only do better by seeing it directly, so its segment stops at the first
// opening it crosses (the result is the same). `may_see`: bit i (i < 64) clear when view
// i's returns cannot see p, set when they may (ReturnDirections::may_see_each); null: ask.
template <bool kMarked>
Visibility best_visibility(const SemiOcTree& tree, const std::vector<ViewLimits>& views,
                           const Point3& p, std::size_t& segments, std::uint32_t& view,
                           Visibility floor = Visibility::kHidden,
                           const std::uint64_t* may_see = nullptr) {
  Visibility best = floor;
  view = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    ++segments;
    const bool asked = may_see && i < 64;
    if (asked && !((*may_see >> i) & 1u)) continue;  // hidden
    const Visibility v =
        segment_visibility<kMarked>(tree, views[i], p, best == Visibility::kThroughOpening, asked);
    if (v > best) {
      best = v;
      view = std::uint32_t(i);
      if (best == Visibility::kDirect) break;
    }
  }
  return best;
}

std::uint32_t label_bit(Label l) {
  return 1u << unsigned(l);
}

Label label_for(Visibility v) {
  switch (v) {
    case Visibility::kDirect:
      return Label::kEmpty;
    case Visibility::kThroughOpening:
      return Label::kOut;
    default:
      return Label::kOccluded;
  }
}

// The label a study gives an octant seen so: for kFreeThroughOpenings only
// the view through an opening changes anything (the map says the rest is free).
Label label_for(Visibility v, OcclusionScope scope) {
  if (scope == OcclusionScope::kFreeThroughOpenings)
    return v == Visibility::kThroughOpening ? Label::kOut : Label::kEmpty;
  return label_for(v);
}

bool candidate(Label l, OcclusionScope scope) {
  switch (scope) {
    case OcclusionScope::kUnknown:
      return l == Label::kUnknown;
    case OcclusionScope::kFreeThroughOpenings:
      return l == Label::kEmpty;
    case OcclusionScope::kNewViews:
      return l == Label::kOccluded || l == Label::kOut;
    default:
      return l == Label::kEmpty || l == Label::kOccluded || l == Label::kOut ||
             l == Label::kUnknown;
  }
}

// What an octant's label already says of its visibility from earlier views
// (OcclusionScope::kNewViews); hidden for the other scopes.
Visibility known_visibility(Label l, OcclusionScope scope) {
  if (scope != OcclusionScope::kNewViews) return Visibility::kHidden;
  return l == Label::kOut ? Visibility::kThroughOpening : Visibility::kHidden;
}

// What is proven of every point of an octant (exact octants), from the proofs of the
// octant it was split from: each point is seen at least `floor`, and the views of bits
// `settled` (view i < 64: bit i) see none better than `floor`.
struct ProvenSight {
  Visibility floor = Visibility::kHidden;
  std::uint64_t settled = 0;
};

struct Candidate {
  octomap::OcTreeKey key;
  unsigned level;
  SemiOcTreeNode* node;  // a leaf octant of the tree
  ProvenSight proven;    // inherited by its children when it is split
};

// Sample points live on the lattice of half leaves: coordinate u (per axis)
// is the point (u / 2 − kKeyOrigin)·r. Corners of octants are even, leaf centres
// odd, and the centre of an octant is a corner of its children, so the
// samples of neighbouring octants and of successive levels coincide and each
// is cast once.
using LatticePoint = std::uint64_t;

Point3 unpack(LatticePoint p, double leaf) {
  auto coord = [leaf, p](int axis) {
    return (0.5 * double(unpack_cell_part(p, axis)) - double(kKeyOrigin)) * leaf;
  };
  return {coord(0), coord(1), coord(2)};
}

// The centre (index 0) and the 8 corners of an octant; a leaf has only its centre. With
// `leaf_centres` (an octant of 2 × 2 × 2 leaves, exact octants: what its leaves judged alone
// say, without a proof), its leaves' centres instead, in the order of its children. Only
// corners (9 samples) are shared with other octants.
int samples_of(const Candidate& c, unsigned leaf_level, bool leaf_centres, LatticePoint out[9]) {
  const std::uint32_t size = 1u << (leaf_level - c.level);  // in leaves
  const std::uint32_t x = 2u * c.key.k[0], y = 2u * c.key.k[1], z = 2u * c.key.k[2];
  if (leaf_centres) {
    for (int k = 0; k < 8; ++k)  // child index: bit 0 x, bit 1 y, bit 2 z (OctoMap's)
      out[k] = pack_cell_parts(x + ((k & 1) ? 3 : 1), y + ((k & 2) ? 3 : 1), z + ((k & 4) ? 3 : 1));
    return 8;
  }
  out[0] = pack_cell_parts(x + size, y + size, z + size);
  if (c.level == leaf_level) return 1;
  for (int k = 0; k < 8; ++k)
    out[k + 1] = pack_cell_parts(x + ((k & 1) ? 2 * size : 0), y + ((k & 2) ? 2 * size : 0),
                                 z + ((k & 4) ? 2 * size : 0));
  return 9;
}

// Proofs that what an octant's samples agree on holds for every point of it
// (OcclusionParams::exact_octants; docs/occlusion.md, "Exact octants"). Each test is
// sufficient, not necessary: an octant it cannot prove is split. Needs the tree's marks
// on occupied, door and window octants (study_occlusion sets them).
class OctantProof {
 public:
  OctantProof(const SemiOcTree& tree, const std::vector<ViewLimits>& views)
      : tree_(tree), views_(views), leaf_(tree.leaf_size()) {}

  // Whether every point of `c` is seen `v` by the best of the views, given that its
  // samples all are and that `known` (at least c.proven.floor) is a lower bound from its
  // label and its proven sight; `hint` is the view that sees its centre so. Views settled
  // in c.proven are not asked again. `proven`: what holds of c as far as the proofs went
  // (for its children if it is split).
  bool holds(const Candidate& c, Visibility v, Visibility known, std::uint32_t hint,
             ProvenSight& proven) const {
    proven = c.proven;
    if (v > known && !seen_all(views_[hint], c, v)) return false;
    // Every point is seen at least v: views settled at the floor (≤ v) see none better.
    proven.floor = v;
    if (v == Visibility::kDirect) return true;
    for (std::size_t i = 0; i < views_.size(); ++i) {
      const std::uint64_t bit = i < 64 ? std::uint64_t(1) << i : 0;
      if (proven.settled & bit) continue;
      if (!seen_at_most(views_[i], c, v)) return false;
      proven.settled |= bit;
    }
    return true;
  }

 private:
  struct Box {
    Point3 lo, hi;
  };
  Box key_box(const octomap::OcTreeKey& key, unsigned level) const {
    const double size = leaf_ * double(1u << (tree_.leaf_level() - level));
    const Point3 lo((double(key.k[0]) - double(kKeyOrigin)) * leaf_,
                    (double(key.k[1]) - double(kKeyOrigin)) * leaf_,
                    (double(key.k[2]) - double(kKeyOrigin)) * leaf_);
    return {lo, Point3(lo.x + size, lo.y + size, lo.z + size)};
  }
  Box box_of(const Candidate& c) const { return key_box(c.key, c.level); }
  static std::pair<Eigen::Vector3d, Eigen::Vector3d> relative(const Box& b, const Point3& o) {
    return {{b.lo.x - o.x, b.lo.y - o.y, b.lo.z - o.z}, {b.hi.x - o.x, b.hi.y - o.y, b.hi.z - o.z}};
  }
  static bool holds_point(const Box& b, const Point3& p) {
    return p.x >= b.lo.x && p.x < b.hi.x && p.y >= b.lo.y && p.y < b.hi.y && p.z >= b.lo.z &&
           p.z < b.hi.z;
  }
  // Whether a segment from the view that crosses the octant is seen no better than `v`.
  static bool caps_at(const ViewLimits& view, const Octant& o, Visibility v) {
    return best_across(view, o.label(), o.key, o.level) <= v;
  }

  // Every point of c within the view's limits, where its scan got returns, and the
  // segments to it crossing nothing that stops them being seen `v` (v ≥ through).
  bool seen_all(const ViewLimits& view, const Candidate& c, Visibility v) const {
    const ScannerView& sv = *view.view;
    const auto [lo, hi] = relative(box_of(c), sv.position);
    const BoxDirections d = box_directions(lo, hi, false);
    const detail::ScannerLimits& limits = view.range_and_elevation;
    if (!(d.nearest > 0 && d.nearest * d.nearest >= limits.min_range2 &&
          d.farthest * d.farthest <= limits.max_range2 && d.sin_lo >= limits.sin_min &&
          d.sin_hi <= limits.sin_max))
      return false;
    if (sv.returns && !sv.returns->may_see_box(lo, hi, leaf_).all) return false;
    return tree_.for_each_marked_in_hull(sv.position, c.key, c.level, [&](const Octant& o) {
      // The scanner's own octant never hides anything (as for one segment).
      if (o.label() == Label::kOccupied) return holds_point(key_box(o.key, o.level), sv.position);
      // Doors and windows: a direct view must cross none (but the door it stands in).
      return best_across(view, o.label(), o.key, o.level) >= v;
    });
  }

  // No point of c seen better than `v` (hidden or through an opening) from the view:
  // wholly beyond its limits, where its scan got no returns, or behind a layer of octants
  // that stop every segment to it.
  bool seen_at_most(const ViewLimits& view, const Candidate& c, Visibility v) const {
    const ScannerView& sv = *view.view;
    const Box box = box_of(c);
    const auto [lo, hi] = relative(box, sv.position);
    const BoxDirections d = box_directions(lo, hi, false);
    const detail::ScannerLimits& limits = view.range_and_elevation;
    if (d.farthest * d.farthest < limits.min_range2 || d.nearest * d.nearest > limits.max_range2 ||
        d.sin_hi < limits.sin_min || d.sin_lo > limits.sin_max)
      return true;
    if (sv.returns && sv.returns->may_see_box(lo, hi, leaf_).none) return true;
    // The layers: where the segment to the centre meets such octants, the last before
    // the box (a wall behind furniture; walked back from the centre), then, for what is
    // seen through an opening, the first (walked from the view: the room's wall with the
    // door). Neither is the scanner's own octant.
    const Point3 centre(0.5 * (box.lo.x + box.hi.x), 0.5 * (box.lo.y + box.hi.y),
                        0.5 * (box.lo.z + box.hi.z));
    const auto stops = [&](const RayStep& s) {
      return !s.summary && s.t_enter > 0.0 && s.node &&
             best_across(view, s.node->label(), s.key, s.level) <= v;
    };
    std::optional<octomap::OcTreeKey> first, last;
    tree_.traverse_marked(centre, sv.position, [&](const RayStep& s) {
      if (!stops(s)) return true;
      if (!holds_point(key_box(s.key, s.level), sv.position)) last = s.key;
      return false;
    });
    if (!last) return false;
    if (behind_layer(view, box, *last, v)) return true;
    if (v == Visibility::kHidden) return false;
    tree_.traverse_marked(sv.position, centre, [&](const RayStep& s) {
      if (!stops(s)) return true;
      first = s.key;
      return false;
    });
    return first && !(*first == *last) && behind_layer(view, box, *first, v);
  }

  // Whether two layers of leaf cells next to the cell `at`, across an axis that separates
  // the view from the box, stop every segment to the box: each segment crosses the plane
  // between the two layers in some column and passes through both cells of that column
  // on either side of it, so one blocking cell per column in the hull's cross-section
  // stops them all.
  bool behind_layer(const ViewLimits& view, const Box& box, const octomap::OcTreeKey& at,
                    Visibility v) const {
    const Point3& o = view.view->position;
    const double a[3] = {o.x / leaf_, o.y / leaf_, o.z / leaf_};
    double lo[3], hi[3];
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::round(box.lo[i] / leaf_);
      hi[i] = std::round(box.hi[i] / leaf_);
    }
    constexpr std::int64_t kMaxColumns = 4096;
    for (int axis = 0; axis < 3; ++axis) {
      const auto q = double(std::int64_t(at.k[axis]) - kKeyOrigin);
      for (const double s0 : {q - 1, q}) {
        // The slab [s0, s0 + 2] lies strictly between the view and the box along `axis`.
        const bool ahead = a[axis] < s0 && s0 + 2 <= lo[axis];
        const bool behind = a[axis] > s0 + 2 && hi[axis] <= s0;
        if (!ahead && !behind) continue;
        double low[2], high[2];
        if (!detail::wedge_across_slab(a, lo, hi, axis, s0, s0 + 2, low, high)) continue;
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        std::int64_t from[2], to[2];
        for (int j = 0; j < 2; ++j) {
          from[j] = std::int64_t(std::floor(low[j]));
          to[j] = std::max(from[j], std::int64_t(std::ceil(high[j])) - 1);
        }
        if ((to[0] - from[0] + 1) * (to[1] - from[1] + 1) > kMaxColumns) continue;
        const auto blocking = [&](std::int64_t along, std::int64_t cu, std::int64_t cw) {
          std::int64_t cell[3];
          cell[axis] = along;
          cell[u] = cu;
          cell[w] = cw;
          octomap::OcTreeKey key;
          for (int i = 0; i < 3; ++i) {
            const std::int64_t k = cell[i] + kKeyOrigin;
            if (k < 0 || k > 65535) return false;
            key.k[i] = octomap::key_type(k);
          }
          const std::optional<Octant> found = tree_.find_octant(key);
          return found && found->node && caps_at(view, *found, v);
        };
        const auto s = std::int64_t(s0);
        bool all = true;
        for (std::int64_t cu = from[0]; cu <= to[0] && all; ++cu)
          for (std::int64_t cw = from[1]; cw <= to[1] && all; ++cw)
            all = blocking(s, cu, cw) || blocking(s + 1, cu, cw);
        if (all) return true;
      }
    }
    return false;
  }

  const SemiOcTree& tree_;
  const std::vector<ViewLimits>& views_;
  double leaf_;
};

// Keeps in `todo` the candidates that a segment from some view may reach through one of
// the `changed` octants: those whose hull with a view meets a changed octant's box. In
// leaf-cell units (cell i spans [i, i + 1)), the changed octants of each coarse voxel as one
// box, grown by a hair so that a segment along a face counts; a candidate is tested only
// against the (view, box) pairs its coarse voxel's hull meets.
void keep_reaching_through(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                           const std::vector<std::pair<octomap::OcTreeKey, unsigned>>& changed,
                           std::vector<Candidate>& todo) {
  struct CellBox {
    double lo[3], hi[3];
  };
  const unsigned leaf = tree.leaf_level();
  const auto cell_box = [&](const octomap::OcTreeKey& key, unsigned level, double grow) {
    CellBox b;
    const double size = double(1u << (leaf - level));
    for (int i = 0; i < 3; ++i) {
      b.lo[i] = double(std::int64_t(key.k[i]) - kKeyOrigin) - grow;
      b.hi[i] = b.lo[i] + size + 2 * grow;
    }
    return b;
  };
  // The min-corner key of the coarse voxel holding `key`.
  const auto coarse_of = [&](const octomap::OcTreeKey& key) {
    return tree.coarse_key(tree.coarse_index(key));
  };
  std::unordered_map<std::uint64_t, CellBox> by_coarse;  // by the coarse voxel's packed key
  for (const auto& [key, level] : changed) {
    if (level > leaf)
      throw std::invalid_argument("OcclusionParams::changed_octants: level " +
                                  std::to_string(level) + " is below the leaf level " +
                                  std::to_string(leaf));
    const CellBox b = cell_box(key, level, 1e-6);
    const auto [it, added] = by_coarse.emplace(pack_octant_key(coarse_of(key)), b);
    for (int i = 0; i < 3 && !added; ++i) {
      it->second.lo[i] = std::min(it->second.lo[i], b.lo[i]);
      it->second.hi[i] = std::max(it->second.hi[i], b.hi[i]);
    }
  }
  std::vector<CellBox> boxes;
  for (const auto& entry : by_coarse) boxes.push_back(entry.second);
  std::vector<std::array<double, 3>> apex;
  const double inv = 1.0 / tree.leaf_size();
  for (const ScannerView& v : views)
    apex.push_back({v.position.x * inv, v.position.y * inv, v.position.z * inv});
  std::optional<octomap::OcTreeKey> coarse;                // of the last candidate
  std::vector<std::pair<std::size_t, std::size_t>> pairs;  // (view, box) the coarse hull meets
  std::size_t kept = 0;
  for (const Candidate& c : todo) {
    if (const octomap::OcTreeKey min_corner = coarse_of(c.key);
        !(coarse && *coarse == min_corner)) {
      coarse = min_corner;
      const CellBox voxel = cell_box(min_corner, 0, 0.0);
      pairs.clear();
      for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t b = 0; b < boxes.size(); ++b)
          if (detail::hull_meets_box(apex[v].data(), voxel.lo, voxel.hi, boxes[b].lo, boxes[b].hi))
            pairs.emplace_back(v, b);
    }
    const CellBox octant = cell_box(c.key, c.level, 0.0);
    for (const auto& [v, b] : pairs)
      if (detail::hull_meets_box(apex[v].data(), octant.lo, octant.hi, boxes[b].lo, boxes[b].hi)) {
        todo[kept++] = c;
        break;
      }
  }
  todo.resize(kept);
}

}  // namespace

std::vector<ScannerView> scanner_views(
    const std::vector<Point3>& positions, const ScannerView& limits,
    const std::vector<std::shared_ptr<const ReturnDirections>>& returns) {
  std::vector<ScannerView> out(positions.size(), limits);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    out[i].position = positions[i];
    out[i].returns = i < returns.size() ? returns[i] : nullptr;
  }
  return out;
}

Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p) {
  std::vector<ViewLimits> limits;
  for (const ScannerView& v : views) limits.push_back(limits_of(tree, v));
  std::size_t segments = 0;
  std::uint32_t view = 0;
  return best_visibility<false>(tree, limits, p, segments, view);
}

OcclusionReport study_occlusion(SemiOcTree& tree, const std::vector<ScannerView>& views,
                                const OcclusionParams& params) {
  // Level by level: the sample points of every candidate octant (centre and
  // corners) are cast in parallel — once each, through a lattice cache — then
  // the verdicts are applied; octants whose samples disagree are split and
  // their children judged in the next round. Ray casting only reads the tree
  // (the labels set here never block a ray), so the result does not depend on
  // the number of threads.
  std::vector<ViewLimits> limits;
  for (const ScannerView& v : views) limits.push_back(limits_of(tree, v));
  // Rays care only about these labels: refined space without them is one step.
  tree.mark_subtrees(label_bit(Label::kOccupied) | label_bit(Label::kDoor) |
                     label_bit(Label::kWindow));
  std::vector<Candidate> todo;
  tree.for_each_octant([&](const Octant& o) {
    if (candidate(o.label(), params.scope))
      todo.push_back({o.key, o.level, const_cast<SemiOcTreeNode*>(o.node), {}});
  });
  if (!params.changed_octants.empty())
    keep_reaching_through(tree, views, params.changed_octants, todo);
  OcclusionReport report;
  const unsigned threads = detail::thread_count(params.threads);
  const unsigned leaf = tree.leaf_level();
  const double leaf_size = tree.leaf_size();
  // Exact octants: an octant of 2 × 2 × 2 leaves is judged by its leaves' centres (a proof
  // would cost more than their segments, and fail for a quarter of them).
  const auto by_leaf_centres = [&](const Candidate& c) {
    return params.exact_octants && c.level + 1 == leaf;
  };
  PackedKeyMap<std::uint32_t> index;     // lattice point → sample id
  std::vector<LatticePoint> points;      // by sample id
  std::vector<std::uint8_t> visibility;  // by sample id
  std::vector<std::uint32_t> best_view;  // by sample id: the first view giving it
  // By sample id: the least visibility the labels of the candidates holding it already
  // know (each takes the better of its own and the sample's, so the sample's visibility
  // need only be found above it); a later candidate that knows less casts it again.
  std::vector<std::uint8_t> known_floor;
  // By sample id: views known to see it no better than its known floor (a candidate's
  // settled views, for the samples no other candidate shares); none past its end (it stays
  // empty until a sample has some).
  std::vector<std::uint64_t> settled;
  const auto settle_last_point = [&](std::uint64_t views_settled) {
    if (views_settled == 0 && settled.empty()) return;
    settled.resize(points.size() - 1, 0);
    settled.push_back(views_settled);
  };
  // What a candidate's label and proven sight say of every point of it.
  const auto known_of = [&](const Candidate& c) {
    return std::max(known_visibility(c.node->label(), params.scope), c.proven.floor);
  };
  const OctantProof proof(tree, limits);
  std::vector<std::uint32_t> samples;  // ids of each candidate's samples, 9 per candidate
  std::vector<std::size_t> segments;
  while (!todo.empty()) {
    const std::size_t first_new = points.size();
    samples.resize(9 * todo.size());
    points.reserve(first_new + 9 * todo.size());  // (at most 9 new samples a candidate)
    known_floor.reserve(first_new + 9 * todo.size());
    for (std::size_t c = 0; c < todo.size(); ++c) {
      LatticePoint s[9];
      const int n = samples_of(todo[c], leaf, by_leaf_centres(todo[c]), s);
      const auto known = std::uint8_t(known_of(todo[c]));
      if (c + 8 < todo.size() && todo[c + 8].level < leaf) {  // hide the probes' cache misses
        LatticePoint ahead[9];
        if (samples_of(todo[c + 8], leaf, by_leaf_centres(todo[c + 8]), ahead) == 9)
          for (const LatticePoint& p : ahead) index.prefetch(p);
      }
      if (n < 9) {  // leaves' centres (odd lattice points) are no other octant's samples
        for (int i = 0; i < n; ++i) {
          samples[9 * c + i] = static_cast<std::uint32_t>(points.size());
          points.push_back(s[i]);
          known_floor.push_back(known);
          settle_last_point(todo[c].proven.settled);
        }
        continue;
      }
      for (int i = 0; i < n; ++i) {
        const auto next = static_cast<std::uint32_t>(points.size());
        std::uint32_t* id = index.try_emplace(s[i], next).first;
        if (*id != next && known < known_floor[*id]) {
          if (*id >= first_new)
            known_floor[*id] = known;  // not cast yet
          else
            *id = next;  // cast above what this candidate knows: cast it again
        }
        if (*id == next) {
          points.push_back(s[i]);
          known_floor.push_back(known);
        }
        samples[9 * c + i] = *id;
      }
    }
    visibility.resize(points.size());
    best_view.resize(points.size());
    segments.assign(points.size() - first_new, 0);
    // A batch of samples at a time: first whether each view's returns may see each of them
    // (lanes at a time), then their segments.
    constexpr std::size_t kBatch = 256;
    const std::size_t batches = (points.size() - first_new + kBatch - 1) / kBatch;
    detail::parallel_for(batches, threads, 1, [&](std::size_t b, unsigned) {
      const std::size_t begin = first_new + b * kBatch;
      const std::size_t n = std::min(kBatch, points.size() - begin);
      Point3 p[kBatch];
      std::uint64_t may_see[kBatch];
      for (std::size_t i = 0; i < n; ++i) {
        p[i] = unpack(points[begin + i], leaf_size);
        // A settled view cannot raise its floor.
        may_see[i] = begin + i < settled.size() ? ~settled[begin + i] : ~std::uint64_t(0);
      }
      double dx[kBatch], dy[kBatch], dz[kBatch];
      std::uint8_t may[kBatch];
      for (std::size_t v = 0; v < std::min<std::size_t>(views.size(), 64); ++v) {
        if (!views[v].returns) continue;
        const Point3& o = views[v].position;
        for (std::size_t i = 0; i < n; ++i)
          dx[i] = p[i].x - o.x, dy[i] = p[i].y - o.y, dz[i] = p[i].z - o.z;
        views[v].returns->may_see_each(n, dx, dy, dz, leaf_size, may);
        for (std::size_t i = 0; i < n; ++i)
          if (!may[i]) may_see[i] &= ~(std::uint64_t(1) << v);
      }
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t id = begin + i;
        visibility[id] = std::uint8_t(
            best_visibility<true>(tree, limits, p[i], segments[id - first_new], best_view[id],
                                  Visibility(known_floor[id]), &may_see[i]));
      }
    });
    for (std::size_t n : segments) report.segments += n;

    // Per candidate: its label, or kSplit.
    constexpr auto kSplit = std::uint8_t(0xff);
    std::vector<std::uint8_t> decision(todo.size());
    std::vector<ProvenSight> proven(todo.size());  // per candidate split: for its children
    std::vector<std::size_t> unproven(threads, 0);
    detail::parallel_for(todo.size(), threads, 16, [&](std::size_t c, unsigned worker) {
      const Candidate& o = todo[c];
      const std::uint32_t* id = &samples[9 * c];
      const auto known = std::uint8_t(known_of(o));
      proven[c] = o.proven;
      const auto seen = [&](std::uint32_t sample) { return std::max(known, visibility[sample]); };
      const Label l = label_for(Visibility(seen(id[0])), params.scope);
      bool uniform = true;
      if (by_leaf_centres(o)) {
        for (int i = 1; i < 8 && uniform; ++i)
          uniform = label_for(Visibility(seen(id[i])), params.scope) == l;
      } else if (o.level < leaf) {
        // Exact: the same visibility, not just the same label, then proven for all of it.
        for (int i = 1; i < 9 && uniform; ++i)
          uniform = params.exact_octants ? seen(id[i]) == seen(id[0])
                                         : label_for(Visibility(seen(id[i])), params.scope) == l;
        if (uniform && params.exact_octants &&
            !proof.holds(o, Visibility(seen(id[0])), Visibility(known), best_view[id[0]],
                         proven[c])) {
          uniform = false;
          ++unproven[worker];
        }
      }
      decision[c] = uniform ? std::uint8_t(l) : kSplit;
    });
    for (std::size_t n : unproven) report.octants_unproven += n;

    std::vector<Candidate> children;
    // A leaf of the tree (or a tested child) labelled in place.
    const auto relabel = [&](SemiOcTreeNode* node, Label l) {
      ++report.octants_tested;
      node->set_label(l);
      node->setLogOdds(tree.log_odds_for(l));
      report.empty += l == Label::kEmpty;
      report.occluded += l == Label::kOccluded;
      report.out += l == Label::kOut;
    };
    for (std::size_t c = 0; c < todo.size(); ++c) {
      const Candidate& o = todo[c];
      if (decision[c] != kSplit) {
        relabel(o.node, Label(decision[c]));
        continue;
      }
      ++report.octants_tested;
      tree.expandNode(o.node);  // partly visible: 8 children with its label
      ++report.octants_split;
      if (by_leaf_centres(o)) {  // its leaves were tested with it
        const Visibility known = known_of(o);
        for (unsigned k = 0; k < 8; ++k)
          relabel(
              tree.getNodeChild(o.node, k),
              label_for(std::max(known, Visibility(visibility[samples[9 * c + k]])), params.scope));
        continue;
      }
      const unsigned half = 1u << (leaf - o.level - 1);
      for (unsigned k = 0; k < 8; ++k) {  // child index: bit 0 x, bit 1 y, bit 2 z (OctoMap's)
        octomap::OcTreeKey ck = o.key;
        for (int a = 0; a < 3; ++a)
          if (k & (1u << a)) ck.k[a] = static_cast<octomap::key_type>(ck.k[a] + half);
        children.push_back({ck, o.level + 1, tree.getNodeChild(o.node, k), proven[c]});
      }
    }
    todo.swap(children);
  }
  if (params.prune) tree.prune();
  return report;
}

}  // namespace semioctree
