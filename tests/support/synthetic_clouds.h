// Point clouds with a known answer, built directly (no scanner).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/scan_io.h"

namespace semioctree::testing {

// A w × d × h room: points on floor (z = 0), ceiling (z = h; none without
// `ceiling`), four walls and a box (a table), with Gaussian noise, seen from
// (sx, sy, scanner_height). Points are in the scanner frame: the room is
// shifted by −scanner position.
inline Cloud::Ptr synthetic_room(double w = 8.0, double d = 6.0, double h = 3.0,
                                 double spacing = 0.03, double noise = 0.002, unsigned seed = 1,
                                 double sx = 3.0, double sy = 2.5, double scanner_height = 1.5,
                                 bool ceiling = true) {
  Cloud::Ptr c(new Cloud);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  auto add = [&](double x, double y, double z) {
    c->push_back(pcl::PointXYZ{float(x - sx + n(rng)), float(y - sy + n(rng)),
                               float(z - scanner_height + n(rng))});
  };
  for (double x = 0; x <= w; x += spacing)
    for (double y = 0; y <= d; y += spacing) {
      add(x, y, 0.0);
      if (ceiling) add(x, y, h);
    }
  for (double z = spacing; z < h; z += spacing) {
    for (double x = 0; x <= w; x += spacing) {
      add(x, 0.0, z);
      add(x, d, z);
    }
    for (double y = 0; y <= d; y += spacing) {
      add(0.0, y, z);
      add(w, y, z);
    }
  }
  // A 1.6 × 0.8 table top at 0.75 m and its sides.
  for (double x = 5.0; x <= 6.6; x += spacing)
    for (double y = 1.0; y <= 1.8; y += spacing) add(x, y, 0.75);
  return c;
}

// A scan of an empty w × d room with walls h high and no ceiling, by a scanner at
// (sx, sy, scanner_height) that steps `step_deg` in azimuth and elevation between
// elevation_min_deg and +90°: each ray's first hit on the floor or a wall, in the scanner
// frame. Unlike synthetic_room, its density falls with range as a real scan's does: the
// walls beside the scanner are dense, the floor beyond the lowest elevation sparse.
inline Cloud::Ptr scanned_open_room(double w, double d, double h, double sx, double sy,
                                    double scanner_height, double elevation_min_deg,
                                    double step_deg) {
  Cloud::Ptr c(new Cloud);
  const double to_rad = M_PI / 180.0;
  for (double el = elevation_min_deg; el <= 90.0; el += step_deg)
    for (double az = -180.0; az < 180.0; az += step_deg) {
      const Eigen::Vector3d v(std::cos(el * to_rad) * std::cos(az * to_rad),
                              std::cos(el * to_rad) * std::sin(az * to_rad), std::sin(el * to_rad));
      double t = std::numeric_limits<double>::infinity();
      if (v.z() < 0) t = std::min(t, -scanner_height / v.z());  // the floor
      if (v.x() > 0) t = std::min(t, (w - sx) / v.x());         // the walls
      if (v.x() < 0) t = std::min(t, -sx / v.x());
      if (v.y() > 0) t = std::min(t, (d - sy) / v.y());
      if (v.y() < 0) t = std::min(t, -sy / v.y());
      if (!std::isfinite(t) || scanner_height + t * v.z() > h) continue;  // over the walls
      const Eigen::Vector3d q = t * v;
      c->push_back(pcl::PointXYZ{float(q.x()), float(q.y()), float(q.z())});
    }
  return c;
}

// Rotation Rot(x, β)·Rot(y, α) of paper Eq 2, applied to a cloud.
inline Cloud::Ptr tilt(const Cloud& in, double alpha_deg, double beta_deg) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(beta_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(alpha_deg * M_PI / 180, Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  Cloud::Ptr out(new Cloud);
  for (const auto& p : in) {
    const Eigen::Vector3d q = R * Eigen::Vector3d(p.x, p.y, p.z);
    out->push_back(pcl::PointXYZ{float(q.x()), float(q.y()), float(q.z())});
  }
  return out;
}

// room_with_pillar's pillar, [2, 2.6] × [1.7, 2.3] × [0, 1.6].
inline constexpr double kPillarLo[3] = {2.0, 1.7, 0.0}, kPillarHi[3] = {2.6, 2.3, 1.6};

// Does the segment a→b pass through the pillar (slab test)?
inline bool hits_pillar(const Point3& a, const Point3& b) {
  double t0 = 0, t1 = 1;
  for (int i = 0; i < 3; ++i) {
    const double d = b[i] - a[i];
    if (std::fabs(d) < 1e-12) {
      if (a[i] < kPillarLo[i] || a[i] > kPillarHi[i]) return false;
      continue;
    }
    double ta = (kPillarLo[i] - a[i]) / d, tb = (kPillarHi[i] - a[i]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// A 4 × 4 × 2.4 m room (walls only, as after preprocessing) with a
// 0.6 × 0.6 × 1.6 m pillar at [2, 2.6) × [1.7, 2.3), as surface points in
// the levelled frame.
inline Cloud room_with_pillar(double step = 0.02) {
  Cloud c;
  auto add = [&](double x, double y, double z) {
    c.push_back(pcl::PointXYZ{float(x), float(y), float(z)});
  };
  for (double z = step; z < 2.4; z += step) {
    for (double t = 0; t <= 4.0; t += step) {
      add(t, 0.01, z);
      add(t, 3.99, z);
      add(0.01, t, z);
      add(3.99, t, z);
    }
    if (z < 1.6)
      for (double t = 0; t < 0.6; t += step) {
        add(2.0 + t, 1.7, z);
        add(2.0 + t, 2.29, z);
        add(2.0, 1.7 + t, z);
        add(2.59, 1.7 + t, z);
      }
  }
  return c;
}

}  // namespace semioctree::testing
