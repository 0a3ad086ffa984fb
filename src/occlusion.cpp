#include "semioctree/occlusion.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

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

struct Candidate {
  octomap::OcTreeKey key;
  unsigned level;
};

// What the samples of one octant say: uniform visibility, or split.
struct Verdict {
  bool uniform = true;
  Visibility visibility = Visibility::kHidden;
  std::size_t segments = 0;
};

Verdict judge(const SemiOcTree& tree, const std::vector<ScannerView>& views,
              const OcclusionParams& p, const Candidate& c) {
  Verdict v;
  auto see = [&](const Point3& q) {
    Visibility best = Visibility::kHidden;
    for (const ScannerView& view : views) {
      ++v.segments;
      best = std::max(best, segment_visibility(tree, view, q));
      if (best == Visibility::kDirect) break;
    }
    return best;
  };
  const Octant o = tree.make_octant(c.key, c.level, nullptr);
  v.visibility = see(o.center);
  if (c.level < tree.coarse_level()) {
    const double h = 0.5 * o.size * (1.0 - 2.0 * p.corner_inset);
    for (int k = 0; k < 8 && v.uniform; ++k) {
      const Point3 q(o.center.x + ((k & 1) ? h : -h), o.center.y + ((k & 2) ? h : -h),
                     o.center.z + ((k & 4) ? h : -h));
      v.uniform = see(q) == v.visibility;
    }
  }
  return v;
}

}  // namespace

Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p) {
  Visibility best = Visibility::kHidden;
  for (const ScannerView& v : views) best = std::max(best, segment_visibility(tree, v, p));
  return best;
}

OcclusionReport study_occlusion(SemiOcTree& tree, const std::vector<ScannerView>& views,
                                const OcclusionParams& params) {
  // Level by level: judge every candidate from its sample points in parallel
  // (ray casting only reads the tree: the labels set here never block a ray),
  // then apply the verdicts; octants whose samples disagree are split and
  // their children judged in the next round. The result does not depend on
  // the number of threads.
  std::vector<Candidate> todo;
  tree.for_each_octant([&](const Octant& o) {
    if (candidate(o.label(), params.only_occluded)) todo.push_back({o.key, o.level});
  });
  OcclusionReport report;
  const unsigned threads = params.threads > 0
                               ? params.threads
                               : std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  std::vector<Verdict> verdicts;
  while (!todo.empty()) {
    verdicts.assign(todo.size(), Verdict{});
    std::atomic<std::size_t> next{0};
    auto work = [&] {
      for (std::size_t i; (i = next.fetch_add(64)) < todo.size();)
        for (std::size_t j = i; j < std::min(i + 64, todo.size()); ++j)
          verdicts[j] = judge(tree, views, params, todo[j]);
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();

    std::vector<Candidate> children;
    for (std::size_t i = 0; i < todo.size(); ++i) {
      const Candidate& c = todo[i];
      const Verdict& v = verdicts[i];
      ++report.octants_tested;
      report.segments += v.segments;
      if (v.uniform) {
        const Label l = label_for(v.visibility);
        tree.set_label(c.key, c.level, l);
        report.empty += l == Label::kEmpty;
        report.occluded += l == Label::kOccluded;
        report.out += l == Label::kOut;
        continue;
      }
      tree.split(c.key, c.level);  // partly visible
      ++report.octants_split;
      const unsigned half = 1u << (tree.coarse_level() - c.level - 1);
      for (unsigned k = 0; k < 8; ++k) {
        octomap::OcTreeKey ck = c.key;
        for (int a = 0; a < 3; ++a)
          if (k & (1u << a)) ck.k[a] = static_cast<octomap::key_type>(ck.k[a] + half);
        children.push_back({ck, c.level + 1});
      }
    }
    todo.swap(children);
  }
  return report;
}

}  // namespace semioctree
