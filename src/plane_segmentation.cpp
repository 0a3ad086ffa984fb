#include "plane_segmentation.h"

#include <cmath>
#include <limits>
#include <type_traits>

#include "vector_clones.h"

namespace semioctree::detail {

SEMIOCTREE_VECTOR_CLONES
std::size_t count_near_plane(std::size_t n, const float* x, const float* y, const float* z,
                             const float c[4], double threshold) {
  // |d| < threshold (a double) for a float |d| exactly when |d| < the least float not below
  // the threshold: a float comparison, lanes at a time.
  float below = float(threshold);
  if (double(below) < threshold)
    below = std::nextafter(below, std::numeric_limits<float>::infinity());
  const float c0 = c[0], c1 = c[1], c2 = c[2], c3 = c[3];
  std::size_t count = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float d = (c0 * x[j] + c2 * z[j]) + (c1 * y[j] + c3);
    count += std::fabs(d) < below;
  }
  return count;
}

bool PlaneSegmentation::initSACModel(const int model_type) {
  if (!SACSegmentation::initSACModel(model_type)) return false;
  // PCL built the model and set its axis and angle: the same, laned.
  auto laned = [&](auto* pcl_model) {
    using Model = std::remove_pointer_t<decltype(pcl_model)>;
    auto model = pcl::make_shared<LanedPlaneModel<Model>>(input_, *indices_, random_);
    model->setAxis(pcl_model->getAxis());
    model->setEpsAngle(pcl_model->getEpsAngle());
    model_ = model;
  };
  if (model_type == pcl::SACMODEL_PARALLEL_PLANE)
    laned(static_cast<pcl::SampleConsensusModelParallelPlane<pcl::PointXYZ>*>(model_.get()));
  else if (model_type == pcl::SACMODEL_PERPENDICULAR_PLANE)
    laned(static_cast<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>*>(model_.get()));
  return true;
}

}  // namespace semioctree::detail
