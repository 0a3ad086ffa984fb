#include "semioctree/sim_platform/opening_match.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace semioctree::sim_platform {

namespace {

using Vec3 = Eigen::Vector3d;

// Extent along the unit horizontal direction `u` and in z.
struct WallRect {
  double u0, u1, z0, z1;
};

WallRect rect_along(const std::array<Vec3, 4>& corners, const Vec3& u) {
  WallRect r{1e18, -1e18, 1e18, -1e18};
  for (const Vec3& c : corners) {
    r.u0 = std::min(r.u0, c.dot(u));
    r.u1 = std::max(r.u1, c.dot(u));
    r.z0 = std::min(r.z0, c.z());
    r.z1 = std::max(r.z1, c.z());
  }
  return r;
}

double iou(const WallRect& a, const WallRect& b) {
  const double w = std::max(0.0, std::min(a.u1, b.u1) - std::max(a.u0, b.u0));
  const double h = std::max(0.0, std::min(a.z1, b.z1) - std::max(a.z0, b.z0));
  const double inter = w * h;
  const double uni = (a.u1 - a.u0) * (a.z1 - a.z0) + (b.u1 - b.u0) * (b.z1 - b.z0) - inter;
  return uni > 0 ? inter / uni : 0.0;
}

Vec3 centre(const std::array<Vec3, 4>& c) {
  return 0.25 * (c[0] + c[1] + c[2] + c[3]);
}

}  // namespace

double opening_iou(const DetectedOpening& d, const sim::OpeningRect& g,
                   const Eigen::Isometry3d& world_to_detection) {
  const bool same_kind = (d.kind == OpeningKind::kDoor) == (g.kind == sim::OpeningKind::door);
  const Vec3 normal = world_to_detection.linear() * g.normal;
  if (!same_kind || std::abs(d.wall_normal.dot(normal)) < 0.95) return 0.0;
  std::array<Vec3, 4> gl;
  for (int k = 0; k < 4; ++k) gl[k] = world_to_detection * g.corners[k];
  if (std::abs((centre(d.corners) - centre(gl)).dot(normal)) > 0.3) return 0.0;  // another wall
  const Vec3 u = (gl[1] - gl[0]).normalized();
  return iou(rect_along(d.corners, u), rect_along(gl, u));
}

OpeningsMatch match_openings(const std::vector<DetectedOpening>& detected,
                             const std::vector<sim::OpeningRect>& truths,
                             const Eigen::Isometry3d& world_to_detection, double min_iou) {
  OpeningsMatch m;
  m.detections = detected.size();
  m.truths = truths.size();
  m.truth_iou.assign(truths.size(), 0.0);
  m.detection_iou.assign(detected.size(), 0.0);
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;  // IoU, detection, truth
  for (std::size_t i = 0; i < detected.size(); ++i)
    for (std::size_t j = 0; j < truths.size(); ++j) {
      const double v = opening_iou(detected[i], truths[j], world_to_detection);
      if (v >= min_iou) pairs.emplace_back(v, i, j);
    }
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return std::get<0>(a) != std::get<0>(b) ? std::get<0>(a) > std::get<0>(b) : a < b;
  });
  for (const auto& [v, i, j] : pairs) {
    if (m.detection_iou[i] > 0 || m.truth_iou[j] > 0) continue;
    m.detection_iou[i] = m.truth_iou[j] = v;
    ++m.matched;
  }
  if (m.detections) m.precision = double(m.matched) / double(m.detections);
  if (m.truths) m.recall = double(m.matched) / double(m.truths);
  return m;
}

std::vector<sim::OpeningRect> openings_of_room(const sim::GroundTruth& truth,
                                               const sim::FloorPlan& plan, int room) {
  std::vector<sim::OpeningRect> out;
  for (const sim::OpeningRect& o : truth.openings()) {
    const double beyond =
        0.5 * truth.scene().walls.at(static_cast<std::size_t>(o.wall)).thickness + 0.1;
    const Vec3 c = centre(o.corners);
    const Eigen::Vector2d left = (c + beyond * o.normal).head<2>(),
                          right = (c - beyond * o.normal).head<2>();
    if (plan.room_at(left) == room || plan.room_at(right) == room) out.push_back(o);
  }
  return out;
}

}  // namespace semioctree::sim_platform
