#include "semioctree/occlusion.h"

#include <algorithm>
#include <cmath>

#include "parallel_for.h"
#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree {

ReturnDirections::ReturnDirections()
    : bins_(std::size_t(kAzimuthBins) * std::size_t(kElevationBins), 0) {}

std::size_t ReturnDirections::bin_of(double dx, double dy, double dz) {
  const double az = std::atan2(dy, dx) * (180.0 / M_PI) + 180.0;                 // [0, 360]
  const double el = std::atan2(dz, std::hypot(dx, dy)) * (180.0 / M_PI) + 90.0;  // [0, 180]
  const int a = std::clamp(int(az), 0, kAzimuthBins - 1);
  const int e = std::clamp(int(el), 0, kElevationBins - 1);
  return std::size_t(e) * kAzimuthBins + std::size_t(a);
}

void ReturnDirections::add(const Eigen::Vector3d& d) {
  if (d.x() == 0 && d.y() == 0 && d.z() == 0) return;
  bins_[bin_of(d.x(), d.y(), d.z())] = 1;
}

void ReturnDirections::close_gaps() {
  std::vector<std::uint8_t> grown(bins_);
  for (int e = 0; e < kElevationBins; ++e)
    for (int a = 0; a < kAzimuthBins; ++a) {
      if (!bins_[std::size_t(e) * kAzimuthBins + a]) continue;
      for (int de = -1; de <= 1; ++de) {
        const int ee = e + de;
        if (ee < 0 || ee >= kElevationBins) continue;
        for (int da = -1; da <= 1; ++da) {
          const int aa = (a + da + kAzimuthBins) % kAzimuthBins;  // azimuth wraps around
          grown[std::size_t(ee) * kAzimuthBins + aa] = 1;
        }
      }
    }
  bins_.swap(grown);
}

bool ReturnDirections::has(double dx, double dy, double dz) const {
  return bins_[bin_of(dx, dy, dz)] != 0;
}

std::size_t ReturnDirections::bins_with_returns() const {
  return std::size_t(std::count(bins_.begin(), bins_.end(), std::uint8_t(1)));
}

std::shared_ptr<const ReturnDirections> return_directions(const Cloud& scan,
                                                          const Eigen::Matrix3d& scanner_to_map) {
  auto r = std::make_shared<ReturnDirections>();
  for (const auto& p : scan) {
    const Eigen::Vector3d d(p.x, p.y, p.z);
    if (d.allFinite()) r->add(scanner_to_map * d);
  }
  r->close_gaps();
  return r;
}

namespace {

// Per-view constants: the elevation limits as bounds on dz / range, so that a
// segment needs no trigonometry.
// A scan taken in a doorway (as surveyors do to link rooms) stands in the door:
// that door is where it stands, not one it looks through, so the door's leaves
// do not make what it sees `out` (counted, everything that scan alone saw, on
// either side, was out). A view stands in a door when a door leaf lies within
// kDoorwayReach of its optical centre; it then ignores the door leaves within
// kOwnDoorReach of it (a door is at most 2.5 m wide and 2.6 m high), however
// obliquely its lines cross them. Windows do not count: nobody scans from one.
constexpr double kDoorwayReach = 0.3;  // m
constexpr double kOwnDoorReach = 3.0;  // m

bool stands_in_a_door(const SemiOcTree& tree, const Point3& c) {
  const double r = tree.leaf_size();
  const int n = int(std::ceil(kDoorwayReach / r)) + 1;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const std::optional<Octant> o =
            tree.find_octant(Point3(c.x + i * r, c.y + j * r, c.z + k * r));
        if (!o || o->label() != Label::kDoor) continue;
        // Distance from the optical centre to the leaf's box.
        const double h = o->size / 2;
        const double dx = std::max(0.0, std::abs(c.x - o->center.x) - h);
        const double dy = std::max(0.0, std::abs(c.y - o->center.y) - h);
        const double dz = std::max(0.0, std::abs(c.z - o->center.z) - h);
        if (dx * dx + dy * dy + dz * dz <= kDoorwayReach * kDoorwayReach) return true;
      }
  return false;
}

struct ViewLimits {
  const ScannerView* view;
  double min_range2, max_range2, sin_min, sin_max;
  bool in_doorway;
};

ViewLimits limits_of(const SemiOcTree& tree, const ScannerView& v) {
  auto sine = [](double deg) { return std::sin(std::clamp(deg, -90.0, 90.0) * M_PI / 180.0); };
  return {&v,
          v.min_range * v.min_range,
          v.max_range * v.max_range,
          sine(v.elevation_min_deg),
          sine(v.elevation_max_deg),
          stands_in_a_door(tree, v.position)};
}

// Occupied octants entered at the very end of a segment only touch its end
// point (a sample on a lattice corner shared with them): they hide nothing.
constexpr double kEndTolerance = 1e-9;

// kMarked: the tree's marks are fresh (study_occlusion), so refined space
// without blockers can be crossed in one step.
template <bool kMarked>
Visibility segment_visibility(const SemiOcTree& tree, const ViewLimits& lim, const Point3& p) {
  const Point3& o = lim.view->position;
  const double dx = p.x - o.x, dy = p.y - o.y, dz = p.z - o.z;
  const double range2 = dx * dx + dy * dy + dz * dz;
  if (range2 < lim.min_range2 || range2 > lim.max_range2) return Visibility::kHidden;
  const double range = std::sqrt(range2);
  if (dz < lim.sin_min * range || dz > lim.sin_max * range) return Visibility::kHidden;
  if (lim.view->returns && !lim.view->returns->has(dx, dy, dz)) return Visibility::kHidden;
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
    through_opening |=
        l == Label::kWindow ||
        (l == Label::kDoor && !(lim.in_doorway && s.t_enter * range < kOwnDoorReach));
    return true;
  };
  if (kMarked)
    tree.traverse_marked(o, p, visit);
  else
    tree.traverse(o, p, visit);
  if (blocked) return Visibility::kHidden;
  return through_opening ? Visibility::kThroughOpening : Visibility::kDirect;
}

template <bool kMarked>
Visibility best_visibility(const SemiOcTree& tree, const std::vector<ViewLimits>& views,
                           const Point3& p, std::size_t& segments) {
  Visibility best = Visibility::kHidden;
  for (const ViewLimits& v : views) {
    ++segments;
    best = std::max(best, segment_visibility<kMarked>(tree, v, p));
    if (best == Visibility::kDirect) break;
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

struct Candidate {
  octomap::OcTreeKey key;
  unsigned level;
  SemiOcTreeNode* node;  // a leaf octant of the tree
};

// Sample points live on the lattice of half leaves: coordinate u (per axis)
// is the point (u / 2 − 32768)·r. Corners of octants are even, leaf centres
// odd, and the centre of an octant is a corner of its children, so the
// samples of neighbouring octants and of successive levels coincide and each
// is cast once.
using LatticePoint = std::uint64_t;

LatticePoint pack(std::uint32_t u, std::uint32_t v, std::uint32_t w) {
  return (std::uint64_t(u) << 42) | (std::uint64_t(v) << 21) | std::uint64_t(w);
}

Point3 unpack(LatticePoint p, double leaf) {
  auto coord = [leaf](std::uint64_t u) { return (0.5 * double(u) - 32768.0) * leaf; };
  return {coord(p >> 42), coord((p >> 21) & 0x1fffff), coord(p & 0x1fffff)};
}

// The centre (index 0) and the 8 corners of an octant; a leaf has only its centre.
int samples_of(const Candidate& c, unsigned coarse_level, LatticePoint out[9]) {
  const std::uint32_t size = 1u << (coarse_level - c.level);  // in leaves
  const std::uint32_t x = 2u * c.key.k[0], y = 2u * c.key.k[1], z = 2u * c.key.k[2];
  out[0] = pack(x + size, y + size, z + size);
  if (c.level == coarse_level) return 1;
  for (int k = 0; k < 8; ++k)
    out[k + 1] = pack(x + ((k & 1) ? 2 * size : 0), y + ((k & 2) ? 2 * size : 0),
                      z + ((k & 4) ? 2 * size : 0));
  return 9;
}

}  // namespace

std::vector<ScannerView> scanner_views(const std::vector<Point3>& positions,
                                       const ScannerView& limits) {
  std::vector<ScannerView> out(positions.size(), limits);
  for (std::size_t i = 0; i < positions.size(); ++i) out[i].position = positions[i];
  return out;
}

Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p) {
  std::vector<ViewLimits> limits;
  for (const ScannerView& v : views) limits.push_back(limits_of(tree, v));
  std::size_t segments = 0;
  return best_visibility<false>(tree, limits, p, segments);
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
      todo.push_back({o.key, o.level, const_cast<SemiOcTreeNode*>(o.node)});
  });
  OcclusionReport report;
  const unsigned threads = detail::thread_count(params.threads);
  const unsigned leaf = tree.coarse_level();
  const double leaf_size = tree.leaf_size();
  PackedKeyMap<std::uint32_t> index;     // lattice point → sample id
  std::vector<LatticePoint> points;      // by sample id
  std::vector<std::uint8_t> visibility;  // by sample id
  std::vector<std::uint32_t> samples;    // ids of each candidate's samples, 9 per candidate
  std::vector<std::size_t> segments;
  while (!todo.empty()) {
    const std::size_t first_new = points.size();
    samples.resize(9 * todo.size());
    for (std::size_t c = 0; c < todo.size(); ++c) {
      LatticePoint s[9];
      const int n = samples_of(todo[c], leaf, s);
      if (c + 8 < todo.size() && todo[c + 8].level < leaf) {  // hide the probes' cache misses
        LatticePoint ahead[9];
        for (int i = 0, m = samples_of(todo[c + 8], leaf, ahead); i < m; ++i)
          index.prefetch(ahead[i]);
      }
      if (n == 1) {  // a leaf's centre (odd lattice point) is no other octant's sample
        samples[9 * c] = static_cast<std::uint32_t>(points.size());
        points.push_back(s[0]);
        continue;
      }
      for (int i = 0; i < n; ++i) {
        const auto next = static_cast<std::uint32_t>(points.size());
        const std::uint32_t id = *index.try_emplace(s[i], next).first;
        if (id == next) points.push_back(s[i]);
        samples[9 * c + i] = id;
      }
    }
    visibility.resize(points.size());
    segments.assign(points.size() - first_new, 0);
    detail::parallel_for(points.size() - first_new, threads, 64, [&](std::size_t i, unsigned) {
      const std::size_t id = first_new + i;
      visibility[id] = std::uint8_t(
          best_visibility<true>(tree, limits, unpack(points[id], leaf_size), segments[i]));
    });
    for (std::size_t n : segments) report.segments += n;

    std::vector<Candidate> children;
    for (std::size_t c = 0; c < todo.size(); ++c) {
      const Candidate& o = todo[c];
      const std::uint32_t* id = &samples[9 * c];
      const auto known = std::uint8_t(known_visibility(o.node->label(), params.scope));
      auto verdict = [&](std::uint32_t sample) {
        return label_for(Visibility(std::max(known, visibility[sample])), params.scope);
      };
      const Label l = verdict(id[0]);
      bool uniform = true;
      if (o.level < leaf)
        for (int i = 1; i < 9 && uniform; ++i) uniform = verdict(id[i]) == l;
      ++report.octants_tested;
      if (uniform) {
        // A leaf of the tree: relabel in place.
        o.node->set_label(l);
        o.node->setLogOdds(tree.log_odds_for(l));
        report.empty += l == Label::kEmpty;
        report.occluded += l == Label::kOccluded;
        report.out += l == Label::kOut;
        continue;
      }
      tree.expandNode(o.node);  // partly visible: 8 children with its label
      ++report.octants_split;
      const unsigned half = 1u << (leaf - o.level - 1);
      for (unsigned k = 0; k < 8; ++k) {  // child index: bit 0 x, bit 1 y, bit 2 z (OctoMap's)
        octomap::OcTreeKey ck = o.key;
        for (int a = 0; a < 3; ++a)
          if (k & (1u << a)) ck.k[a] = static_cast<octomap::key_type>(ck.k[a] + half);
        children.push_back({ck, o.level + 1, tree.getNodeChild(o.node, k)});
      }
    }
    todo.swap(children);
  }
  if (params.prune) tree.prune();
  return report;
}

}  // namespace semioctree
