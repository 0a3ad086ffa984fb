#include "semioctree/update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "semioctree/preprocess.h"

namespace semioctree {

namespace {
double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

Cloud::Ptr within_limits(const Cloud& scan, const ScannerView& limits, std::size_t* dropped) {
  // Coordinates are floats: a return on a limit itself (the synthetic
  // scanner's lowest beam row) must survive the rounding.
  constexpr double kRangeTolerance = 1e-4, kElevationTolerance = 1e-3;  // m, degrees
  Cloud::Ptr out(new Cloud);
  out->reserve(scan.size());
  for (const auto& p : scan) {
    const double x = p.x, y = p.y, z = p.z;
    const double range = std::sqrt(x * x + y * y + z * z);
    if (range < limits.min_range - kRangeTolerance || range > limits.max_range + kRangeTolerance)
      continue;
    if (range > 0) {
      const double elevation = std::asin(std::clamp(z / range, -1.0, 1.0)) * 180.0 / M_PI;
      if (elevation < limits.elevation_min_deg - kElevationTolerance ||
          elevation > limits.elevation_max_deg + kElevationTolerance)
        continue;
    }
    out->push_back(p);
  }
  if (dropped) *dropped = scan.size() - out->size();
  return out;
}

SurveyMap::SurveyMap(const SurveyMapParams& params) : params_(params), merged_(new Cloud) {
  SemiOcTree::coarse_level_for(params.grid.leaf, params.grid.coarse);  // validates
}

std::vector<ScannerView> SurveyMap::views() const {
  return scanner_views(scanners_, params_.limits, returns_);
}

namespace {
void require_a_scan(bool empty) {
  if (empty) throw std::logic_error("SurveyMap: no scan added yet (call add_scan first)");
}
}  // namespace

const SemiOcTree& SurveyMap::tree() const {
  require_a_scan(empty());
  return *tree_;
}

SemiOcTree& SurveyMap::tree() {
  require_a_scan(empty());
  return *tree_;
}

const Cloud& SurveyMap::merged_cloud() const {
  require_a_scan(empty());
  return *merged_;
}

ScanUpdateReport SurveyMap::add_scan(const Cloud& points, const Point3& scanner,
                                     double ceiling_height,
                                     std::shared_ptr<const ReturnDirections> returns) {
  ScanUpdateReport rep;
  rep.scan_index = scanners_.size();
  const bool first = !tree_;
  auto t0 = std::chrono::steady_clock::now();
  if (first) {
    ceiling_ = ceiling_height;
    DiscretizeReport dr;
    tree_ = discretize(points, ceiling_, params_.grid, &dr);
    rep.new_coarse_voxels = tree_->coarse_count();
    rep.occupied_leaves = dr.occupied_leaves;
  } else {
    // New ground is unknown until classified; the scan's leaves are occupied.
    rep.new_coarse_voxels =
        extend_coarse_grid(*tree_, points, ceiling_, params_.grid.extent_snap, Label::kUnknown);
    rep.occupied_leaves = mark_occupied(*tree_, points, ceiling_);
  }
  scanners_.push_back(scanner);
  returns_.push_back(std::move(returns));
  *merged_ += points;
  if (params_.merged_spacing > 0) merged_ = decimate(*merged_, params_.merged_spacing);
  rep.seconds_occupancy = since(t0);

  t0 = std::chrono::steady_clock::now();
  openings_ =
      detect_openings(*merged_, ceiling_, *tree_, scanners_, params_.openings, &rep.openings);
  label_openings(*tree_, openings_);
  rep.openings_found = openings_.size();
  rep.seconds_openings = since(t0);

  t0 = std::chrono::steady_clock::now();
  OcclusionParams op;
  op.threads = params_.threads;
  const std::vector<ScannerView> all = views();
  if (first) {
    rep.retest = study_occlusion(*tree_, all, op);
  } else {
    op.scope = OcclusionScope::kUnknown;
    rep.new_space = study_occlusion(*tree_, all, op);
    op.scope = OcclusionScope::kNewViews;
    rep.retest = study_occlusion(*tree_, {all.back()}, op);
  }
  rep.seconds_occlusion = since(t0);
  return rep;
}

}  // namespace semioctree
