#include "semioctree/nbv/overlap.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "../parallel_for.h"
#include "label_roles.h"

namespace semioctree {

namespace {

enum class RayEnd { kNoReturn, kMapped, kUnmapped };

struct RayResult {
  RayEnd end = RayEnd::kNoReturn;
  double range = 0;  // m, where it returned (unmapped: where it entered unseen space)
};

// The segment from `a` along unit direction `d`, up to `max_range` or until it leaves
// the band floor_z < z < top_z; false when it leaves the band at once.
bool clipped_end(const Point3& a, const Eigen::Vector3d& d, double max_range, double floor_z,
                 double top_z, double& length) {
  length = max_range;
  if (d.z() > 0) length = std::min(length, (top_z - a.z) / d.z());
  if (d.z() < 0) length = std::min(length, (floor_z - a.z) / d.z());
  return length > 0;
}

RayResult cast(const SemiOcTree& tree, const Point3& a, const Eigen::Vector3d& d,
               const ScannerView& limits, double floor_z, double top_z, double tolerance) {
  RayResult r;
  double length = 0;
  if (!clipped_end(a, d, limits.max_range, floor_z, top_z, length)) return r;
  const Point3 b(a.x + length * d.x(), a.y + length * d.y(), a.z + length * d.z());
  double unseen_from = -1;  // range where the ray entered unseen space (< 0: not in it)
  auto deep = [&](double range) { return unseen_from >= 0 && range - unseen_from > tolerance; };
  const TraversalEnd end = tree.traverse(a, b, [&](const RayStep& s) {
    const Label l = s.label();
    const double range = s.t_enter * length;
    // Reached through unseen space deeper than the tolerance, a surface or space the map
    // holds nothing of: the surface facing the ray lies somewhere in that space, and no
    // scan has seen it.
    if ((l == Label::kOccupied || !s.node) && deep(range)) {
      r = {RayEnd::kUnmapped, unseen_from};
      return false;
    }
    if (l == Label::kOccupied) {
      if (range >= limits.min_range) r = {RayEnd::kMapped, range};
      return false;
    }
    if (nbv_detail::passable(l))
      unseen_from = -1;  // unseen space the ray came out of was air on its line
    else if (unseen_from < 0)
      unseen_from = range;
    return true;
  });
  if (end == TraversalEnd::kOutOfRange) return {};
  // Out of the band through unseen space: a return outside the room (the ground below a
  // window, a building above the map's top), from nothing the map holds.
  if (r.end == RayEnd::kNoReturn && deep(length)) r = {RayEnd::kUnmapped, length};
  if (r.end == RayEnd::kUnmapped) r.range = std::max(r.range, limits.min_range);
  return r;
}

}  // namespace

namespace {
// The rays of a prediction: rows of equal elevation, step_deg apart; each row's azimuths
// step_deg apart on the sphere, so that every ray stands for about the same solid angle.
struct RayRows {
  double el_min = 0, step_deg = 1;
  int rows = 1;
  double elevation(int row) const {
    return (el_min + (double(row) + 0.5) * step_deg) * M_PI / 180.0;
  }
  int azimuths(int row) const {
    return std::max(1, static_cast<int>(std::lround(360.0 * std::cos(elevation(row)) / step_deg)));
  }
};
RayRows ray_rows(const ScannerView& limits, double step_deg) {
  RayRows g;
  g.el_min = std::clamp(limits.elevation_min_deg, -90.0, 90.0);
  const double el_max = std::clamp(limits.elevation_max_deg, -90.0, 90.0);
  g.step_deg = step_deg;
  g.rows = std::max(1, static_cast<int>(std::lround((el_max - g.el_min) / step_deg)));
  return g;
}
}  // namespace

std::size_t prediction_rays(const NbvParams& params) {
  if (!(params.overlap_ray_step_deg > 0)) return 0;
  const RayRows g = ray_rows(params.limits, params.overlap_ray_step_deg);
  std::size_t n = 0;
  for (int row = 0; row < g.rows; ++row) n += std::size_t(g.azimuths(row));
  return n;
}

OverlapPrediction predict_overlap(const SemiOcTree& tree, const Point3& scanner,
                                  const ScannerView& limits, double floor_z, double top_z,
                                  double tolerance, double step_deg, unsigned threads) {
  if (!(step_deg > 0)) throw std::invalid_argument("predict_overlap: the ray step must be > 0");
  if (!(top_z > floor_z))
    throw std::invalid_argument("predict_overlap: the band's top must lie above its floor");
  const RayRows grid = ray_rows(limits, step_deg);
  const int rows = grid.rows;
  struct RowSum {
    double mapped = 0, total = 0;
    std::size_t rays = 0, n_mapped = 0, n_unmapped = 0;
  };
  std::vector<RowSum> sums(static_cast<std::size_t>(rows));
  detail::parallel_for(
      sums.size(), detail::thread_count(threads), 1, [&](std::size_t row, unsigned) {
        const double el = grid.elevation(int(row));
        const int n = grid.azimuths(int(row));
        RowSum& s = sums[row];
        for (int i = 0; i < n; ++i) {
          const double az = (double(i) + 0.5) * 2 * M_PI / n;
          const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                  std::sin(el));
          const RayResult r = cast(tree, scanner, d, limits, floor_z, top_z, tolerance);
          ++s.rays;
          if (r.end == RayEnd::kNoReturn) continue;
          const double w = r.range * r.range;
          s.total += w;
          if (r.end == RayEnd::kMapped) {
            s.mapped += w;
            ++s.n_mapped;
          } else {
            ++s.n_unmapped;
          }
        }
      });
  OverlapPrediction p;
  double mapped = 0, total = 0;
  for (const RowSum& s : sums) {
    mapped += s.mapped, total += s.total;
    p.rays += s.rays, p.mapped += s.n_mapped, p.unmapped += s.n_unmapped;
  }
  if (total > 0) p.share = mapped / total;
  if (p.mapped + p.unmapped > 0)
    p.unweighted_share = double(p.mapped) / double(p.mapped + p.unmapped);
  return p;
}

OverlapPrediction predict_overlap(const SemiOcTree& tree, const Point3& scanner,
                                  const NbvParams& params) {
  if (!params.overlap_top)
    throw std::invalid_argument("predict_overlap: NbvParams::overlap_top is not set");
  return predict_overlap(tree, scanner, params.limits, 0.0, *params.overlap_top,
                         2 * tree.leaf_size(), params.overlap_ray_step_deg, params.threads);
}

}  // namespace semioctree
