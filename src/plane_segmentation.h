// PCL's RANSAC plane segmentation (SACSegmentation) with the inlier counts of its plane
// models run lanes at a time (internal header). RANSAC counts a candidate plane's inliers
// among all the points on each of its hundreds of iterations; PCL runs that count four or
// eight points at a time only when PCL itself was built for SSE4.1 or AVX2, and the
// distribution's build is not, so its scalar loop takes most of a wall search's time
// (docs/data-flow.md, "Planes by RANSAC"). Everything else is PCL's: the sampling, the
// models' constraints, the iterations, the final inliers and the refit.
#pragma once

#include <pcl/point_types.h>
#include <pcl/sample_consensus/sac_model_parallel_plane.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cstddef>
#include <vector>

namespace semioctree::detail {

// The number of points j < n with |(c[0]·x[j] + c[2]·z[j]) + (c[1]·y[j] + c[3])| < threshold,
// in float arithmetic: the count PCL's scalar SampleConsensusModelPlane::countWithinDistance
// gives (its 4-element dot product adds the products in that order), point for point.
std::size_t count_near_plane(std::size_t n, const float* x, const float* y, const float* z,
                             const float c[4], double threshold);

// A PCL plane model (pcl::SampleConsensusModelParallelPlane or
// SampleConsensusModelPerpendicularPlane of pcl::PointXYZ) whose inlier count is
// count_near_plane's over a copy of its points' coordinates, made when it is built.
template <class Model>
class LanedPlaneModel : public Model {
 public:
  LanedPlaneModel(const typename Model::PointCloudConstPtr& cloud, const pcl::Indices& indices,
                  bool random)
      : Model(cloud, indices, random), copied_from_(cloud.get()) {
    const std::size_t n = this->indices_->size();
    x_.resize(n), y_.resize(n), z_.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      const pcl::PointXYZ& q = (*cloud)[std::size_t((*this->indices_)[j])];
      x_[j] = q.x, y_[j] = q.y, z_[j] = q.z;
    }
  }
  std::size_t countWithinDistance(const Eigen::VectorXf& coefficients,
                                  double threshold) const override {
    // (Points or indices set again since: PCL's own count.)
    if (this->input_.get() != copied_from_ || this->indices_->size() != x_.size())
      return Model::countWithinDistance(coefficients, threshold);
    if (!this->isModelValid(coefficients)) return 0;
    const float c[4] = {coefficients[0], coefficients[1], coefficients[2], coefficients[3]};
    return count_near_plane(x_.size(), x_.data(), y_.data(), z_.data(), c, threshold);
  }

 private:
  const pcl::PointCloud<pcl::PointXYZ>* copied_from_;
  std::vector<float> x_, y_, z_;
};

// pcl::SACSegmentation of pcl::PointXYZ whose SACMODEL_PARALLEL_PLANE and
// SACMODEL_PERPENDICULAR_PLANE models are LanedPlaneModels (the same axis and angle); the
// same planes, inliers and coefficients as PCL's, sooner.
class PlaneSegmentation : public pcl::SACSegmentation<pcl::PointXYZ> {
 protected:
  bool initSACModel(int model_type) override;
};

}  // namespace semioctree::detail
