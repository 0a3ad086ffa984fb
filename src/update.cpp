#include "semioctree/update.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>
#include <utility>
#include <vector>

#include "nbv/label_roles.h"
#include "scanner_limits.h"
#include "semioctree/preprocess.h"
#include "semioctree/timing.h"

namespace semioctree {

Cloud::Ptr within_limits(const Cloud::Ptr& scan, const ScannerView& limits, std::size_t* dropped) {
  // Coordinates are floats: a return on a limit itself (the synthetic
  // scanner's lowest beam row) must survive the rounding.
  constexpr double kRangeTolerance = 1e-4, kElevationTolerance = 1e-3;  // m, degrees
  // The limits on the squared range, and the elevation limits as limits of z / range, the
  // sine of the elevation (increasing with it), compared as squares: no square root or
  // division per return.
  const double range_min = limits.min_range - kRangeTolerance;
  const double range_max = limits.max_range + kRangeTolerance;
  const double range2_min = range_min > 0 ? range_min * range_min : 0.0;
  const double range2_max = range_max * range_max;
  auto sine_of = [](double deg) { return std::sin(std::clamp(deg, -90.0, 90.0) * M_PI / 180.0); };
  const double sin_min = limits.elevation_min_deg - kElevationTolerance <= -90.0
                             ? -2.0
                             : sine_of(limits.elevation_min_deg - kElevationTolerance);
  const double sin_max = limits.elevation_max_deg + kElevationTolerance >= 90.0
                             ? 2.0
                             : sine_of(limits.elevation_max_deg + kElevationTolerance);
  // (A return with a coordinate not a number is kept: preprocessing skips it.)
  auto within = [&](const pcl::PointXYZ& p) {
    const double x = p.x, y = p.y, z = p.z;
    const double range2 = x * x + y * y + z * z;
    if (range2 < range2_min || range2 > range2_max) return false;
    return !(range2 > 0) || (detail::ScannerLimits::at_least(z, sin_min, range2) &&
                             detail::ScannerLimits::at_least(-z, -sin_max, range2));
  };
  // Most scans lose none: the scan itself, unless a return lies outside.
  std::size_t first_out = 0;
  while (first_out < scan->size() && within((*scan)[first_out])) ++first_out;
  if (first_out == scan->size()) {
    if (dropped) *dropped = 0;
    return scan;
  }
  std::size_t kept = first_out;
  for (std::size_t i = first_out + 1; i < scan->size(); ++i) kept += within((*scan)[i]);
  if (dropped) *dropped = scan->size() - kept;
  Cloud::Ptr out(new Cloud);
  out->reserve(kept);
  out->insert(out->end(), scan->begin(), scan->begin() + std::ptrdiff_t(first_out));
  for (std::size_t i = first_out + 1; i < scan->size(); ++i)
    if (within((*scan)[i])) out->push_back((*scan)[i]);
  return out;
}

SurveyMap::SurveyMap(const SurveyMapParams& params) : params_(params), merged_(new Cloud) {
  SemiOcTree::leaf_level_for(params.grid.leaf, params.grid.coarse);  // validates
}

std::vector<ScannerView> SurveyMap::views() const {
  return scanner_views(scanners_, params_.limits, returns_);
}

namespace {
// A leaf octant of the map and its label.
struct LabelledOctant {
  octomap::OcTreeKey key;
  unsigned level;
  Label label;
};

constexpr std::uint32_t label_bit(Label l) {
  return 1u << unsigned(l);
}
constexpr std::uint32_t kOpeningLabels = label_bit(Label::kDoor) | label_bit(Label::kWindow);

// The leaf octants whose label is in `labels` (bit 1 << label).
std::vector<LabelledOctant> octants_labelled(const SemiOcTree& tree, std::uint32_t labels) {
  std::vector<LabelledOctant> out;
  tree.for_each_octant([&](const Octant& o) {
    if (labels & label_bit(o.label())) out.push_back({o.key, o.level, o.label()});
  });
  return out;
}

void relabel(SemiOcTree& tree, const std::vector<LabelledOctant>& octants, Label label) {
  for (const LabelledOctant& o : octants) tree.set_label(o.key, o.level, label);
}

std::uint64_t pack_octant(const octomap::OcTreeKey& k, unsigned level, Label label) {
  return (std::uint64_t(label) << 56) | pack_octant_key(k, level);
}

struct OpeningChange {
  std::size_t dropped = 0;  // earlier opening octants no longer wholly of their label
  // The opening octants now that lie in no earlier opening octant of their label.
  std::vector<std::pair<octomap::OcTreeKey, unsigned>> added;
};

// Compares the map's door and window octants with those it had `before`.
OpeningChange compare_openings(const SemiOcTree& tree, const std::vector<LabelledOctant>& before) {
  OpeningChange change;
  const unsigned leaf = tree.leaf_level();
  std::unordered_set<std::uint64_t> earlier;
  for (const LabelledOctant& o : before) {
    earlier.insert(pack_octant(o.key, o.level, o.label));
    // Every leaf cell of the octant still has its label (openings are a leaf
    // or two thick: an octant holds a few cells at most).
    const unsigned side = 1u << (leaf - o.level);
    bool kept = true;
    for (unsigned i = 0; i < side && kept; ++i)
      for (unsigned j = 0; j < side && kept; ++j)
        for (unsigned k = 0; k < side && kept; ++k) {
          const octomap::OcTreeKey cell(static_cast<octomap::key_type>(o.key[0] + i),
                                        static_cast<octomap::key_type>(o.key[1] + j),
                                        static_cast<octomap::key_type>(o.key[2] + k));
          const std::optional<Octant> now = tree.find_octant(cell);
          kept = now && now->label() == o.label;
        }
    change.dropped += !kept;
  }
  for (const LabelledOctant& o : octants_labelled(tree, kOpeningLabels)) {
    bool known = false;
    for (unsigned level = o.level + 1; level-- > 0 && !known;) {
      const unsigned shift = leaf - level;
      octomap::OcTreeKey k;
      for (int a = 0; a < 3; ++a)
        k[a] = static_cast<octomap::key_type>((o.key[a] >> shift) << shift);
      known = earlier.count(pack_octant(k, level, o.label)) != 0;
    }
    if (!known) change.added.emplace_back(o.key, o.level);
  }
  return change;
}

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

int SurveyMap::seen_side(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) const {
  if (!tree_) return 0;
  const Eigen::Vector3d n = tree_->leaf_size() * normal.normalized();
  auto seen_free = [&](const Eigen::Vector3d& p) {
    const std::optional<Octant> o = tree_->find_octant(Point3(p.x(), p.y(), p.z()));
    return o && nbv_detail::passable(o->label());
  };
  // Free a leaf and a half away and three and a half: a wall's inside may read free
  // just behind its face (docs/registration.md, "The two faces of a wall").
  auto side_free = [&](double sign) {
    return seen_free(point + sign * 1.5 * n) && seen_free(point + sign * 3.5 * n);
  };
  const bool ahead = side_free(1.0), behind = side_free(-1.0);
  return ahead == behind ? 0 : (ahead ? 1 : -1);
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
  auto t0 = Clock::now();
  // The openings the map held before this scan (its points may fill some).
  const std::vector<LabelledOctant> openings_before =
      first ? std::vector<LabelledOctant>{} : octants_labelled(*tree_, kOpeningLabels);
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
  if (params_.merged_spacing > 0) {
    // decimate(merged + points) in place, with a table of the new points' cells only (a
    // table of every cell kept from scan to scan saved 0.1 s a lab scan and raised the
    // survey's peak memory by 50 MB; one of the union, built afresh, took 0.06-0.26 s).
    CellThinning thinning(params_.merged_spacing);
    thinning.reserve(points.size());  // (a cell at most a point)
    thinning.add(points);
    thinning.release_after(*merged_);
  } else {
    *merged_ += points;
  }
  rep.seconds_occupancy = seconds_since(t0);

  t0 = Clock::now();
  openings_ =
      detect_openings(merged_cloud(), ceiling_, *tree_, views(), params_.openings, &rep.openings);
  // The map's doors and windows are the openings found now: earlier labels go
  // (unknown: re-decided below) and the openings label their leaves afresh.
  relabel(*tree_, octants_labelled(*tree_, kOpeningLabels), Label::kUnknown);
  label_openings(*tree_, openings_);
  rep.openings_found = openings_.size();
  const OpeningChange change = compare_openings(*tree_, openings_before);
  rep.opening_octants_dropped = change.dropped;
  rep.opening_leaves_added = !change.added.empty() && !first;
  rep.seconds_openings = seconds_since(t0);

  t0 = Clock::now();
  OcclusionParams op;
  op.threads = params_.threads;
  op.exact_octants = params_.exact_octants;
  const std::vector<ScannerView> all = views();
  if (first) {
    rep.retest = study_occlusion(*tree_, all, op);
  } else {
    // Space seen through a door or window that is gone may now be seen
    // directly, or not at all: out is decided again from every position.
    if (change.dropped > 0)
      relabel(*tree_, octants_labelled(*tree_, label_bit(Label::kOut)), Label::kUnknown);
    op.scope = OcclusionScope::kUnknown;
    rep.new_space = study_occlusion(*tree_, all, op);
    op.scope = OcclusionScope::kNewViews;
    rep.retest = study_occlusion(*tree_, {all.back()}, op);
    // Empty space that the earlier positions saw through what is only now
    // an opening lies beyond it: out, unless some position sees it directly.
    // Only what a segment reaches through the new opening leaves can change.
    if (rep.opening_leaves_added) {
      op.scope = OcclusionScope::kFreeThroughOpenings;
      op.changed_octants = change.added;
      rep.through_openings = study_occlusion(*tree_, all, op);
    }
  }
  rep.seconds_occlusion = seconds_since(t0);
  return rep;
}

}  // namespace semioctree
