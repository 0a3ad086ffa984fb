#include "semioctree/global_registration.h"

#include <pcl/common/transforms.h>
#include <pcl/features/normal_3d.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "parallel_for.h"
#include "semioctree/preprocess.h"
#include "semioctree/timing.h"

namespace semioctree {

namespace {

// `facing` for the source placed by `placement` (its viewpoint moved along); empty
// without one.
SurfaceFacing facing_at(const SurfaceFacing* facing, const Eigen::Isometry3d& placement) {
  if (!facing) return {};
  SurfaceFacing placed = *facing;
  placed.source_viewpoint = placement * facing->source_viewpoint;
  return placed;
}

constexpr double kDeg = 180.0 / M_PI;

// The (x, y) of the points on vertical surfaces: the cloud thinned to `spacing`
// (decimate), normals by PCL from the neighbours within 2.5 spacings.
std::vector<Eigen::Vector2d> vertical_surface_points(const Cloud& in, double spacing,
                                                     double max_normal_z) {
  const Cloud::Ptr thin = decimate(in, spacing);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setInputCloud(thin);
  estimation.setSearchMethod(pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
  estimation.setRadiusSearch(2.5 * spacing);
  pcl::PointCloud<pcl::Normal> normals;
  estimation.compute(normals);
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < thin->size(); ++i) {
    const pcl::Normal& n = normals[i];
    if (!std::isfinite(n.normal_z) || std::fabs(n.normal_z) > max_normal_z) continue;
    out.emplace_back((*thin)[i].x, (*thin)[i].y);
  }
  return out;
}

struct Cell {
  std::int64_t x, y;
  bool operator<(const Cell& o) const { return x < o.x || (x == o.x && y < o.y); }
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
};

std::vector<Cell> cells_of(const std::vector<Eigen::Vector2d>& points, double cell) {
  std::vector<Cell> out;
  out.reserve(points.size());
  for (const auto& p : points)
    out.push_back({std::int64_t(std::floor(p.x() / cell)), std::int64_t(std::floor(p.y() / cell))});
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

Eigen::Vector2d centroid_of(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : points) c += p;
  return c / double(points.size());
}

// A peak of the search: the source, turned by yaw about its centroid, has its
// centroid at `at` in the target frame.
struct Peak {
  double votes;
  std::size_t yaw_index;
  Eigen::Vector2d at;
};

Eigen::Isometry3d placement(double yaw_deg, const Eigen::Vector2d& source_centroid,
                            const Eigen::Vector2d& at) {
  const Eigen::Rotation2Dd r(yaw_deg / kDeg);
  const Eigen::Vector2d t = at - (r * source_centroid);
  return planar_pose(t.x(), t.y(), yaw_deg);
}

// Mean distance the points move between two placements.
double mean_displacement(const std::vector<Eigen::Vector2d>& points, const Eigen::Isometry3d& a,
                         const Eigen::Isometry3d& b) {
  double sum = 0;
  for (const auto& p : points) {
    const Eigen::Vector3d q(p.x(), p.y(), 0.0);
    sum += (a * q - b * q).head<2>().norm();
  }
  return points.empty() ? 0.0 : sum / double(points.size());
}

double yaw_of(const Eigen::Isometry3d& t) {
  const Eigen::Vector3d x = t.rotation().col(0);
  return std::atan2(x.y(), x.x()) * kDeg;
}

std::string describe_hypothesis(const GlobalHypothesis& h) {
  std::ostringstream m;
  const Eigen::Vector3d t = h.screened.translation();
  m << "(" << t.x() << ", " << t.y() << " m, " << yaw_of(h.screened) << "°) overlap " << h.overlap;
  return m.str();
}

}  // namespace

GlobalAlignResult global_align(const Cloud& source, const Cloud& target,
                               const RegistrationParams& reg, const GlobalAlignParams& p,
                               const SurfaceFacing* facing) {
  const auto t0 = Clock::now();
  if (!(p.cell > 0) || !(reg.max_correspondence > p.cell) || p.hypotheses < 1 ||
      !(p.ambiguity_ratio >= 0 && p.ambiguity_ratio <= 1) ||
      !(p.max_vertical_normal_z > 0 && p.max_vertical_normal_z < 1))
    throw std::invalid_argument(
        "global alignment parameters: need 0 < cell < max_correspondence, hypotheses >= 1, "
        "0 <= ambiguity_ratio <= 1 and 0 < max_vertical_normal_z < 1");
  GlobalAlignResult r;

  // 1. The vertical surfaces of both clouds, projected on a grid of `cell`.
  const double spacing = p.cell / 2;
  const std::vector<Eigen::Vector2d> src =
      vertical_surface_points(source, spacing, p.max_vertical_normal_z);
  const std::vector<Eigen::Vector2d> tgt =
      vertical_surface_points(target, spacing, p.max_vertical_normal_z);
  const std::vector<Cell> target_cells = cells_of(tgt, p.cell);
  r.target_cells = target_cells.size();
  const std::size_t min_cells = std::max<std::size_t>(10, reg.min_points / 10);
  {
    const std::size_t source_cells = cells_of(src, p.cell).size();
    if (source_cells < min_cells || r.target_cells < min_cells) {
      std::ostringstream m;
      m << "global alignment: too few points on vertical surfaces (walls, furniture sides) ("
        << source_cells << " source and " << r.target_cells << " target cells of " << p.cell
        << " m; need at least " << min_cells << " each)";
      throw RegistrationError(m.str());
    }
  }
  const Eigen::Vector2d source_centroid = centroid_of(src);
  // The source's reach about its centroid (90th percentile): a yaw step whose half
  // moves a point this far by half a cell keeps every guess within a cell.
  std::vector<double> radii;
  radii.reserve(src.size());
  for (const auto& q : src) radii.push_back((q - source_centroid).norm());
  std::nth_element(radii.begin(), radii.begin() + std::ptrdiff_t(radii.size() * 9 / 10),
                   radii.end());
  const double reach = std::max(p.cell, radii[radii.size() * 9 / 10]);
  r.yaw_steps = std::size_t(std::ceil(360.0 / (2.0 * std::atan(p.cell / (2.0 * reach)) * kDeg)));
  r.yaw_step_deg = 360.0 / double(r.yaw_steps);

  // 2. For every yaw, every pair (source wall cell, target wall cell) votes for the
  // translation that lays one on the other; a 3 × 3 box sum of the votes counts the
  // target cells within a cell of each source cell (the correlation of the two wall
  // images, the target dilated by a cell). The best peaks of every yaw are kept.
  std::int64_t tx0 = std::numeric_limits<std::int64_t>::max(), ty0 = tx0, tx1 = -tx0, ty1 = -tx0;
  for (const Cell& c : target_cells) {
    tx0 = std::min(tx0, c.x), tx1 = std::max(tx1, c.x);
    ty0 = std::min(ty0, c.y), ty1 = std::max(ty1, c.y);
  }
  // Source cells are about the source centroid, so within ±reach_cells.
  double max_radius = 0;
  for (const auto& q : src) max_radius = std::max(max_radius, (q - source_centroid).norm());
  const std::int64_t reach_cells = std::int64_t(std::ceil(max_radius / p.cell)) + 1;
  // Offsets o = target cell − source cell, with a margin of one for the box sum.
  const std::int64_t ox0 = tx0 - reach_cells - 1, oy0 = ty0 - reach_cells - 1;
  const std::int64_t width = tx1 - tx0 + 2 * reach_cells + 3;
  const std::int64_t height = ty1 - ty0 + 2 * reach_cells + 3;
  // One vote grid per yaw in flight: refuse spans that would not fit in memory
  // (2.5 · 10⁷ cells of 0.2 m: 1 km on a side).
  if (double(width) * double(height) > 2.5e7) {
    std::ostringstream m;
    m << "global alignment: the clouds' wall points span " << double(width) * p.cell << " × "
      << double(height) * p.cell << " m of translations, too far to search with " << p.cell
      << " m cells";
    throw RegistrationError(m.str());
  }
  std::vector<std::int64_t> target_index;
  target_index.reserve(target_cells.size());
  for (const Cell& c : target_cells) target_index.push_back((c.x - ox0) * height + (c.y - oy0));
  const std::int64_t suppress = std::int64_t(std::ceil(reg.max_correspondence / p.cell));
  // The target's wall cells dilated by one cell (3 × 3), over its bounding box plus one.
  const std::int64_t dx0 = tx0 - 1, dy0 = ty0 - 1, dw = tx1 - tx0 + 3, dh = ty1 - ty0 + 3;
  std::vector<char> near_wall(std::size_t(dw * dh), 0);
  for (const Cell& c : target_cells)
    for (std::int64_t a = -1; a <= 1; ++a)
      for (std::int64_t b = -1; b <= 1; ++b)
        near_wall[std::size_t((c.x + a - dx0) * dh + (c.y + b - dy0))] = 1;
  // Share of source wall cells that offset o lays within a cell of a target wall cell.
  auto share_near_wall = [&](const std::vector<Cell>& cells, std::int64_t ox, std::int64_t oy) {
    std::size_t n = 0;
    for (const Cell& c : cells) {
      const std::int64_t a = c.x + ox - dx0, b = c.y + oy - dy0;
      if (a >= 0 && a < dw && b >= 0 && b < dh && near_wall[std::size_t(a * dh + b)]) ++n;
    }
    return double(n) / double(cells.size());
  };
  // The vote sums favour source cells over dense target clutter; the best peaks of
  // each yaw are therefore ranked again by share_near_wall, which counts every
  // source cell once.
  constexpr std::size_t kPeaksPerYaw = 10;

  std::vector<std::vector<Peak>> peaks(r.yaw_steps);
  std::vector<std::size_t> source_cell_count(r.yaw_steps);
  detail::parallel_for(r.yaw_steps, 0, 1, [&](std::size_t k, unsigned) {
    const double yaw = double(k) * r.yaw_step_deg;
    const Eigen::Rotation2Dd rot(yaw / kDeg);
    std::vector<Eigen::Vector2d> turned;
    turned.reserve(src.size());
    for (const auto& q : src) turned.push_back(rot * (q - source_centroid));
    const std::vector<Cell> cells = cells_of(turned, p.cell);
    source_cell_count[k] = cells.size();
    std::vector<std::int32_t> votes(std::size_t(width * height), 0);
    for (const Cell& s : cells) {
      const std::int64_t shift = s.x * height + s.y;
      for (const std::int64_t t : target_index) ++votes[std::size_t(t - shift)];
    }
    // 3 × 3 box sum (interior only: the margin keeps every vote inside).
    std::vector<std::int32_t> box(votes.size(), 0);
    for (std::int64_t i = 1; i + 1 < width; ++i)
      for (std::int64_t j = 1; j + 1 < height; ++j) {
        std::int32_t s = 0;
        for (std::int64_t di = -1; di <= 1; ++di)
          for (std::int64_t dj = -1; dj <= 1; ++dj)
            s += votes[std::size_t((i + di) * height + j + dj)];
        box[std::size_t(i * height + j)] = s;
      }
    for (std::size_t n = 0; n < kPeaksPerYaw; ++n) {
      const auto best = std::max_element(box.begin(), box.end());
      if (*best <= 0) break;
      const std::int64_t at = best - box.begin(), i = at / height, j = at % height;
      // Offset o lays source cell s on target cell s + o: a translation of o
      // cells (the cells of both share the grid's corners), which takes the
      // source centroid (the origin of the turned cells) to o · cell.
      const Eigen::Vector2d centre(double(i + ox0) * p.cell, double(j + oy0) * p.cell);
      peaks[k].push_back({share_near_wall(cells, i + ox0, j + oy0), k, centre});
      for (std::int64_t a = std::max<std::int64_t>(0, i - suppress);
           a <= std::min<std::int64_t>(width - 1, i + suppress); ++a)
        for (std::int64_t b = std::max<std::int64_t>(0, j - suppress);
             b <= std::min<std::int64_t>(height - 1, j + suppress); ++b)
          box[std::size_t(a * height + b)] = 0;
    }
  });
  r.source_cells = *std::max_element(source_cell_count.begin(), source_cell_count.end());

  // 3. Distinct peaks, best first: a peak within ICP's reach of a better one (its
  // centroid within max_correspondence, its yaw within the angle that moves the
  // source's reach by max_correspondence) is the same placement.
  std::vector<Peak> all;
  for (const auto& v : peaks) all.insert(all.end(), v.begin(), v.end());
  std::stable_sort(all.begin(), all.end(),
                   [](const Peak& a, const Peak& b) { return a.votes > b.votes; });
  const double same_yaw_deg = std::atan(reg.max_correspondence / reach) * kDeg;
  auto same_placement = [&](double yaw_a, const Eigen::Vector2d& at_a, double yaw_b,
                            const Eigen::Vector2d& at_b) {
    return std::fabs(std::remainder(yaw_a - yaw_b, 360.0)) <= same_yaw_deg &&
           (at_a - at_b).norm() <= reg.max_correspondence;
  };
  std::vector<Peak> distinct;
  for (const Peak& c : all) {
    bool same = false;
    for (const Peak& d : distinct)
      same = same || same_placement(double(c.yaw_index) * r.yaw_step_deg, c.at,
                                    double(d.yaw_index) * r.yaw_step_deg, d.at);
    if (!same) distinct.push_back(c);
  }
  r.candidates = distinct.size();
  r.seconds_search = seconds_since(t0);

  // 4. Screening: a coarse ICP (twice the voxel and final correspondence of
  // registration, at most 20 iterations a stage, no bounds) from the best peaks in turn, until
  // `hypotheses` placements are screened; a peak within reach of a placement already screened (ICP
  // brought an earlier peak there) is skipped. The screened overlap ranks them.
  const auto t_screen = Clock::now();
  RegistrationParams coarse = reg;
  coarse.voxel = 2 * reg.voxel;
  coarse.final_correspondence = std::min(reg.max_correspondence, 2 * reg.final_correspondence);
  coarse.max_fitness = std::numeric_limits<double>::infinity();
  coarse.min_overlap = 0;
  // Screening only ranks: from a guess within a cell and half a yaw step, the
  // right placement settles in about ten iterations a stage; one that needs more
  // than 20 is far from any fit, and is not worth the time.
  coarse.max_iterations = std::min(reg.max_iterations, 20);
  const Cloud::Ptr source_thin = decimate(source, coarse.voxel);
  const Cloud::Ptr target_thin = decimate(target, coarse.voxel);
  const Eigen::Vector3d centroid3(source_centroid.x(), source_centroid.y(), 0.0);
  for (std::size_t rank = 0; rank < distinct.size() && r.screened.size() < p.hypotheses; ++rank) {
    const Peak& c = distinct[rank];
    const double yaw = double(c.yaw_index) * r.yaw_step_deg;
    bool reached = false;
    for (const GlobalHypothesis& h : r.screened)
      reached = reached ||
                same_placement(yaw, c.at, yaw_of(h.screened), (h.screened * centroid3).head<2>());
    if (reached) continue;
    GlobalHypothesis h;
    const Eigen::Isometry3d guess = placement(yaw, source_centroid, c.at);
    const Eigen::Vector3d t = guess.translation();
    h.x = t.x(), h.y = t.y(), h.yaw_deg = yaw, h.votes = c.votes;
    h.rank = rank;
    h.screened = guess;
    Cloud placed;
    pcl::transformPointCloud(*source_thin, placed, guess.matrix().cast<float>());
    try {
      const SurfaceFacing placed_facing = facing_at(facing, guess);
      const RegistrationResult icp =
          register_scan(placed, *target_thin, coarse, facing ? &placed_facing : nullptr);
      h.screened = icp.correction * guess;
      h.overlap = icp.overlap;
    } catch (const RegistrationError&) {
      h.overlap = 0;  // ICP lost every correspondence: no placement here
    }
    r.screened.push_back(h);
  }
  std::stable_sort(
      r.screened.begin(), r.screened.end(),
      [](const GlobalHypothesis& a, const GlobalHypothesis& b) { return a.overlap > b.overlap; });
  r.seconds_screen = seconds_since(t_screen);

  // 5. Verification: register_scan, with its failure bounds, from the screened
  // placements in turn until one passes (the others are at most as good: they need
  // min_overlap within the coarser distance already). The best distinct placement
  // after it is refined too when it might fit as well: if it passes with an overlap
  // of at least ambiguity_ratio of the chosen one's, the scan is ambiguous.
  const auto t_verify = Clock::now();
  std::ostringstream figures;
  figures << r.yaw_steps << " yaws of " << r.yaw_step_deg << "°, " << r.candidates
          << " distinct placements, " << r.screened.size() << " screened by ICP";
  auto refine = [&](const GlobalHypothesis& h) {
    Cloud placed;
    pcl::transformPointCloud(source, placed, h.screened.matrix().cast<float>());
    ++r.verified;
    const SurfaceFacing placed_facing = facing_at(facing, h.screened);
    return register_scan(placed, target, reg, facing ? &placed_facing : nullptr);
  };
  std::string first_failure;
  bool found = false;
  for (std::size_t i = 0; i < r.screened.size() && !found; ++i) {
    if (r.screened[i].overlap < reg.min_overlap) break;
    try {
      r.icp = refine(r.screened[i]);
      r.chosen = i;
      found = true;
    } catch (const RegistrationError& e) {
      if (first_failure.empty()) first_failure = e.what();
    }
  }
  if (!found) {
    std::ostringstream m;
    m << "global alignment found no placement that passes the bounds (" << figures.str()
      << "; best screened overlap " << (r.screened.empty() ? 0.0 : r.screened.front().overlap)
      << " within " << coarse.final_correspondence << " m, bound " << reg.min_overlap << ")";
    if (!first_failure.empty()) m << "; the best one refined: " << first_failure;
    m << "; the scans do not overlap enough";
    throw RegistrationError(m.str());
  }
  const GlobalHypothesis& best = r.screened[r.chosen];
  r.chosen_overlap = best.overlap;
  r.guess = best.screened;
  r.transform = r.icp.correction * r.guess;
  for (std::size_t i = r.chosen + 1; i < r.screened.size(); ++i) {
    const GlobalHypothesis& h = r.screened[i];
    if (mean_displacement(src, h.screened, best.screened) <= coarse.final_correspondence)
      continue;  // the same placement, screened twice
    r.runner_up_overlap = h.overlap;
    if (h.overlap >= reg.min_overlap) {
      std::optional<RegistrationResult> other;
      try {
        other = refine(h);
      } catch (const RegistrationError&) {
        // The runner-up fails the bounds: no rival.
      }
      if (other) r.runner_up_refined_overlap = other->overlap;
      if (other && other->overlap >= p.ambiguity_ratio * r.icp.overlap) {
        std::ostringstream m;
        m << "global alignment is ambiguous: two placements pass the bounds about equally "
             "well, "
          << describe_hypothesis(best) << " (refined overlap " << r.icp.overlap << ") and "
          << describe_hypothesis(h) << " (refined overlap " << other->overlap
          << "; the runner-up must stay below " << p.ambiguity_ratio << " × the best; "
          << figures.str()
          << "): the room looks alike from both, as a symmetric one does; give the scan's pose";
        throw RegistrationError(m.str());
      }
    }
    break;
  }
  r.seconds_verify = seconds_since(t_verify);
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace semioctree
