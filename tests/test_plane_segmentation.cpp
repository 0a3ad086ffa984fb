// RANSAC's plane segmentation with laned inlier counts (src/plane_segmentation.h): the
// counts are PCL's own scalar counts point for point, and a segmentation finds the same
// planes, inliers and coefficients as PCL's SACSegmentation.
#include <gtest/gtest.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/sample_consensus/sac_model_plane.h>

#include <cmath>
#include <random>
#include <vector>

#include "src/plane_segmentation.h"

namespace semioctree::detail {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// PCL's plane model with its scalar count in reach (the one Debian's PCL runs; a PCL built
// for SSE4.1 or AVX2 counts otherwise).
struct ScalarPlaneModel : pcl::SampleConsensusModelPlane<pcl::PointXYZ> {
  using pcl::SampleConsensusModelPlane<pcl::PointXYZ>::SampleConsensusModelPlane;
  std::size_t scalar_count(const Eigen::VectorXf& c, double threshold) const {
    return countWithinDistanceStandard(c, threshold);
  }
};

// Points within a few thresholds of the plane n·p + d = 0, many of them a rounding away
// from ±threshold (where the order of the dot product's additions decides), and points
// anywhere.
Cloud::Ptr points_about(const Eigen::Vector3f& n, float d, double threshold, std::mt19937& rng) {
  std::uniform_real_distribution<float> box(-12.0f, 12.0f), unit(-1.0f, 1.0f);
  Cloud::Ptr c(new Cloud);
  for (int i = 0; i < 60000; ++i) {
    const Eigen::Vector3f p(box(rng), box(rng), box(rng));
    const float off = -(n.dot(p) + d);  // onto the plane
    float along;
    if (i % 3 == 0)
      along = float(threshold) * (i % 2 ? 1.0f : -1.0f) * (1.0f + 1e-6f * unit(rng));
    else if (i % 3 == 1)
      along = 3.0f * float(threshold) * unit(rng);
    else
      along = box(rng);
    const Eigen::Vector3f q = p + (off + along) * n;
    c->push_back(pcl::PointXYZ(q.x(), q.y(), q.z()));
  }
  return c;
}

TEST(PlaneSegmentation, CountsArePclsScalarCounts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::size_t boundary_cases = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Eigen::Vector3f n(unit(rng), unit(rng), unit(rng));
    n.normalize();
    const float d = 5.0f * unit(rng);
    const double threshold = trial % 2 ? 0.03 : 0.05;
    const Cloud::Ptr cloud = points_about(n, d, threshold, rng);
    const ScalarPlaneModel pcl_model(cloud);
    std::vector<float> x, y, z;
    for (const auto& q : *cloud) x.push_back(q.x), y.push_back(q.y), z.push_back(q.z);
    // The plane as RANSAC's candidates give it (not normalised), and rescaled.
    for (const float scale : {1.0f, 0.37f, 2.9f}) {
      Eigen::VectorXf c(4);
      c << scale * n.x(), scale * n.y(), scale * n.z(), scale * d;
      const float cf[4] = {c[0], c[1], c[2], c[3]};
      const std::size_t ours =
          count_near_plane(x.size(), x.data(), y.data(), z.data(), cf, threshold);
      EXPECT_EQ(ours, pcl_model.scalar_count(c, threshold)) << "trial " << trial;
      // Points that float rounding puts within a few ulps of the threshold: the count
      // depends on how the dot product is added up there.
      for (std::size_t j = 0; j < x.size(); ++j) {
        const double exact = double(c[0]) * x[j] + double(c[1]) * y[j] + double(c[2]) * z[j] + c[3];
        boundary_cases += std::fabs(std::fabs(exact) - threshold) < 1e-6 * threshold;
      }
    }
  }
  EXPECT_GT(boundary_cases, 1000u);  // the test reaches the cases where it matters
}

// Walls of a room (vertical planes) and its floor, with clutter: the laned segmentation
// and PCL's find the same plane each round, with the same inliers and coefficients.
TEST(PlaneSegmentation, FindsPclsPlanes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.006f);
  Cloud::Ptr room(new Cloud);
  for (int i = 0; i < 30000; ++i) {
    const float a = 8.0f * u(rng), b = 6.0f * u(rng), h = 3.0f * u(rng);
    switch (i % 6) {
      case 0:
        room->push_back(pcl::PointXYZ(a, 0.0f + noise(rng), h));
        break;
      case 1:
        room->push_back(pcl::PointXYZ(a, 6.0f + noise(rng), h));
        break;
      case 2:
        room->push_back(pcl::PointXYZ(0.0f + noise(rng), b, h));
        break;
      case 3:
        room->push_back(pcl::PointXYZ(8.0f + noise(rng), b, h));
        break;
      case 4:
        room->push_back(pcl::PointXYZ(a, b, noise(rng)));
        break;
      default:
        room->push_back(pcl::PointXYZ(a, b, h));
        break;  // clutter
    }
  }
  for (const int type : {pcl::SACMODEL_PARALLEL_PLANE, pcl::SACMODEL_PERPENDICULAR_PLANE}) {
    for (const bool optimize : {false, true}) {
      pcl::SACSegmentation<pcl::PointXYZ> theirs;
      PlaneSegmentation ours;
      for (pcl::SACSegmentation<pcl::PointXYZ>* seg :
           {static_cast<pcl::SACSegmentation<pcl::PointXYZ>*>(&theirs),
            static_cast<pcl::SACSegmentation<pcl::PointXYZ>*>(&ours)}) {
        seg->setOptimizeCoefficients(optimize);
        seg->setModelType(type);
        seg->setMethodType(pcl::SAC_RANSAC);
        seg->setAxis(Eigen::Vector3f::UnitZ());
        seg->setEpsAngle(5.0 * M_PI / 180.0);
        seg->setDistanceThreshold(0.03);
        seg->setMaxIterations(2000);
        seg->setInputCloud(room);
      }
      pcl::PointIndices in_theirs, in_ours;
      pcl::ModelCoefficients c_theirs, c_ours;
      theirs.segment(in_theirs, c_theirs);
      ours.segment(in_ours, c_ours);
      ASSERT_GT(in_theirs.indices.size(), 4000u) << type;
      EXPECT_EQ(in_ours.indices, in_theirs.indices) << type << " " << optimize;
      EXPECT_EQ(c_ours.values, c_theirs.values) << type << " " << optimize;
    }
  }
}

}  // namespace
}  // namespace semioctree::detail
