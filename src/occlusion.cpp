#include "semioctree/occlusion.h"

#include <algorithm>
#include <cmath>

namespace semioctree {

namespace {

Visibility segment_visibility(const SemiOcTree& tree, const ScannerView& v, const Point3& p) {
  const double dx = p.x - v.position.x, dy = p.y - v.position.y, dz = p.z - v.position.z;
  const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (range < v.min_range || range > v.max_range) return Visibility::kHidden;
  const double elevation = std::asin(std::clamp(dz / range, -1.0, 1.0)) * 180.0 / M_PI;
  if (elevation < v.elevation_min_deg || elevation > v.elevation_max_deg)
    return Visibility::kHidden;
  bool through_opening = false, blocked = false;
  tree.traverse(v.position, p, [&](const RayStep& s) {
    const Label l = s.label();
    // The scanner's own octant never hides anything (noise can put a point in it).
    if (l == Label::kOccupied && s.t_enter > 0.0) {
      blocked = true;
      return false;
    }
    through_opening |= (l == Label::kDoor || l == Label::kWindow);
    return true;
  });
  if (blocked) return Visibility::kHidden;
  return through_opening ? Visibility::kThroughOpening : Visibility::kDirect;
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

bool candidate(Label l, bool only_occluded) {
  if (only_occluded) return l == Label::kOccluded;
  return l == Label::kEmpty || l == Label::kOccluded || l == Label::kOut;
}

class Study {
 public:
  Study(SemiOcTree& tree, const std::vector<ScannerView>& views, const OcclusionParams& p)
      : tree_(tree), views_(views), p_(p) {}

  Visibility see(const Point3& q) {
    Visibility best = Visibility::kHidden;
    for (const ScannerView& v : views_) {
      ++report.segments;
      best = std::max(best, segment_visibility(tree_, v, q));
      if (best == Visibility::kDirect) break;
    }
    return best;
  }

  // Classifies the octant (key, level); splits it where its samples disagree.
  void classify(const octomap::OcTreeKey& key, unsigned level) {
    ++report.octants_tested;
    const Octant o = tree_.make_octant(key, level, nullptr);
    const Visibility centre = see(o.center);
    bool uniform = true;
    if (level < tree_.coarse_level()) {
      const double h = 0.5 * o.size * (1.0 - 2.0 * p_.corner_inset);
      for (int c = 0; c < 8 && uniform; ++c) {
        const Point3 q(o.center.x + ((c & 1) ? h : -h), o.center.y + ((c & 2) ? h : -h),
                       o.center.z + ((c & 4) ? h : -h));
        uniform = see(q) == centre;
      }
    }
    if (uniform) {
      tree_.set_label(o.key, level, label_for(centre));
      count(label_for(centre));
      return;
    }
    // Partly visible: split and classify each child.
    tree_.split(o.key, level);
    ++report.octants_split;
    const unsigned half = 1u << (tree_.coarse_level() - level - 1);
    for (unsigned i = 0; i < 8; ++i) {
      octomap::OcTreeKey ck = o.key;
      for (int a = 0; a < 3; ++a)
        if (i & (1u << a)) ck.k[a] = static_cast<octomap::key_type>(ck.k[a] + half);
      classify(ck, level + 1);
    }
  }

  void count(Label l) {
    if (l == Label::kEmpty) ++report.empty;
    if (l == Label::kOccluded) ++report.occluded;
    if (l == Label::kOut) ++report.out;
  }

  OcclusionReport report;

 private:
  SemiOcTree& tree_;
  const std::vector<ScannerView>& views_;
  const OcclusionParams& p_;
};

}  // namespace

Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p) {
  Visibility best = Visibility::kHidden;
  for (const ScannerView& v : views) best = std::max(best, segment_visibility(tree, v, p));
  return best;
}

OcclusionReport study_occlusion(SemiOcTree& tree, const std::vector<ScannerView>& views,
                                const OcclusionParams& params) {
  // Collect the candidates first: classifying splits octants and edits the tree.
  std::vector<std::pair<octomap::OcTreeKey, unsigned>> todo;
  tree.for_each_octant([&](const Octant& o) {
    if (candidate(o.label(), params.only_occluded)) todo.emplace_back(o.key, o.level);
  });
  Study study(tree, views, params);
  for (const auto& [key, level] : todo) study.classify(key, level);
  return study.report;
}

}  // namespace semioctree
