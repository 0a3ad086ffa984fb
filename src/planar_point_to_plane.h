// ICP's step for a planar motion (internal header): the point-to-plane error minimised over
// x, y and the yaw, linearised in the yaw, by one 3 × 3 solve (docs/registration.md,
// "What it costs"). PCL's estimators are 6-DoF in closed form, or a warp minimised by
// Levenberg-Marquardt.
#pragma once

#include <pcl/correspondence.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/transformation_estimation.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstddef>
#include <utility>

namespace semioctree::detail {

// Pairs (source point p, target point q with normal n) give residuals (p − q)·n. With the
// source turned by a small yaw θ about z and moved by (tx, ty), a residual grows by
// tx·n_x + ty·n_y + θ·(p_x·n_y − p_y·n_x): the (tx, ty, θ) minimising the sum of the
// squares solves 3 normal equations. The step returned turns by θ exactly (cos, sin), so a
// rotation stays a rotation; ICP's iterations take the linearisation's remainder. A
// direction the pairs do not constrain (every normal along x, say) is not moved along:
// LDLT leaves a zero pivot's unknown at zero. Pairs without a finite normal are skipped.
class PlanarPointToPlane
    : public pcl::registration::TransformationEstimation<pcl::PointNormal, pcl::PointNormal,
                                                         double> {
 public:
  using PointN = pcl::PointNormal;
  using CloudN = pcl::PointCloud<PointN>;

  void estimateRigidTransformation(const CloudN& src, const CloudN& tgt,
                                   Matrix4& m) const override {
    solve(
        src.size(), [&](std::size_t i) { return std::make_pair(&src[i], &tgt[i]); }, m);
  }
  void estimateRigidTransformation(const CloudN& src, const pcl::Indices& in_src, const CloudN& tgt,
                                   Matrix4& m) const override {
    solve(
        in_src.size(),
        [&](std::size_t i) { return std::make_pair(&src[std::size_t(in_src[i])], &tgt[i]); }, m);
  }
  void estimateRigidTransformation(const CloudN& src, const pcl::Indices& in_src, const CloudN& tgt,
                                   const pcl::Indices& in_tgt, Matrix4& m) const override {
    solve(
        in_src.size(),
        [&](std::size_t i) {
          return std::make_pair(&src[std::size_t(in_src[i])], &tgt[std::size_t(in_tgt[i])]);
        },
        m);
  }
  void estimateRigidTransformation(const CloudN& src, const CloudN& tgt,
                                   const pcl::Correspondences& pairs, Matrix4& m) const override {
    solve(
        pairs.size(),
        [&](std::size_t i) {
          return std::make_pair(&src[std::size_t(pairs[i].index_query)],
                                &tgt[std::size_t(pairs[i].index_match)]);
        },
        m);
  }

 private:
  // pair(i): pointers to the i-th source and target points.
  template <class Pair>
  static void solve(std::size_t n, const Pair& pair, Matrix4& m) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      const auto [p, q] = pair(i);
      const double nx = q->normal_x, ny = q->normal_y, nz = q->normal_z;
      if (!(std::isfinite(nx) && std::isfinite(ny) && std::isfinite(nz))) continue;
      const Eigen::Vector3d j(nx, ny, double(p->x) * ny - double(p->y) * nx);
      const double r =
          (double(p->x) - q->x) * nx + (double(p->y) - q->y) * ny + (double(p->z) - q->z) * nz;
      a.noalias() += j * j.transpose();
      b -= j * r;
    }
    m = Matrix4::Identity();
    const Eigen::Vector3d x = a.ldlt().solve(b);
    if (!x.allFinite()) return;  // (no pairs: no step)
    const double c = std::cos(x.z()), s = std::sin(x.z());
    m(0, 0) = c, m(0, 1) = -s, m(1, 0) = s, m(1, 1) = c;
    m(0, 3) = x.x(), m(1, 3) = x.y();
  }
};

}  // namespace semioctree::detail
