// The kd-tree of registration (src/kd_tree_n.h): its neighbours are the brute-force
// ones (the k nearest strictly within a bound, nearest first, as PCL's FLANN radius
// search keeps them), through nanoflann and through PCL's search interface that ICP calls.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "src/kd_tree_n.h"

namespace semioctree::detail {
namespace {

using CloudN = KdTreeN::CloudN;

pcl::PointNormal at(float x, float y, float z) {
  pcl::PointNormal p;
  p.x = x;
  p.y = y;
  p.z = z;
  p.normal_x = p.normal_y = p.normal_z = 0;
  return p;
}

CloudN::Ptr random_cloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  CloudN::Ptr cloud(new CloudN);
  for (std::size_t i = 0; i < n; ++i) cloud->push_back(at(u(rng), u(rng), 0.3f * u(rng)));
  return cloud;
}

// Every point of `cloud` within `radius` of q (squared distance < radius² in floats, as
// the tree computes it), nearest first, at most k.
std::vector<std::pair<float, int>> brute_force(const CloudN& cloud, const pcl::PointNormal& q,
                                               int k, double radius) {
  std::vector<std::pair<float, int>> near;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float dx = cloud[i].x - q.x, dy = cloud[i].y - q.y, dz = cloud[i].z - q.z;
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < float(radius * radius)) near.emplace_back(d2, int(i));
  }
  std::sort(near.begin(), near.end());
  if (int(near.size()) > k) near.resize(std::size_t(k));
  return near;
}

TEST(KdTree, TheKNearestWithinTheBoundAreTheBruteForceOnes) {
  const CloudN::Ptr cloud = random_cloud(3000, 7);
  KdTreeN tree;
  tree.setInputCloud(cloud);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  for (int trial = 0; trial < 300; ++trial) {
    const pcl::PointNormal q = at(u(rng), u(rng), u(rng) * 0.4f);
    for (const int k : {1, 8, 12, 40})
      for (const double radius : {0.05, 0.2, 0.5, std::numeric_limits<double>::infinity()}) {
        const auto expected = brute_force(*cloud, q, k, radius);
        std::vector<int> idx(std::size_t(k), -1);
        std::vector<float> d2(std::size_t(k), -1);
        const int n = tree.nearest_within(q, k, radius, idx.data(), d2.data());
        ASSERT_EQ(n, int(expected.size())) << "k " << k << " radius " << radius;
        for (int i = 0; i < n; ++i) {
          EXPECT_EQ(idx[std::size_t(i)], expected[std::size_t(i)].second);
          EXPECT_FLOAT_EQ(d2[std::size_t(i)], expected[std::size_t(i)].first);
        }
      }
  }
}

TEST(KdTree, APointAtExactlyTheRadiusIsLeftOutAsPclsRadiusSearchDoes) {
  CloudN::Ptr cloud(new CloudN);
  cloud->push_back(at(0.5f, 0, 0));                        // 0.5 m: d² = 0.25 exactly
  cloud->push_back(at(std::nextafter(0.5f, 0.0f), 0, 0));  // just within
  cloud->push_back(at(0, 0.25f, 0));                       // well within
  KdTreeN tree;
  tree.setInputCloud(cloud);
  pcl::Indices idx;
  std::vector<float> d2;
  ASSERT_EQ(tree.radiusSearch(at(0, 0, 0), 0.5, idx, d2), 2);
  EXPECT_EQ(idx, (pcl::Indices{2, 1}));
  EXPECT_LT(d2[1], 0.25f);
  ASSERT_EQ(tree.radiusSearch(at(0, 0, 0), 0.5, idx, d2, 1), 1);
  EXPECT_EQ(idx[0], 2);
  EXPECT_EQ(tree.radiusSearch(at(0, 0, 0), 0.2, idx, d2), 0);
  EXPECT_TRUE(idx.empty());
  // PCL's own tree over the same cloud: the same answer.
  pcl::search::KdTree<pcl::PointNormal> pcl_tree;
  pcl_tree.setInputCloud(cloud);
  pcl::Indices pcl_idx;
  std::vector<float> pcl_d2;
  ASSERT_EQ(pcl_tree.radiusSearch(at(0, 0, 0), 0.5, pcl_idx, pcl_d2), 2);
  EXPECT_EQ(pcl_idx, (pcl::Indices{2, 1}));
  // No radius, or a NaN one: nothing.
  EXPECT_EQ(tree.radiusSearch(at(0, 0, 0), 0.0, idx, d2), 0);
  EXPECT_EQ(tree.radiusSearch(at(0, 0, 0), std::nan(""), idx, d2), 0);
}

TEST(KdTree, PclSearchesAnswerAsNanoflannDoes) {
  const CloudN::Ptr cloud = random_cloud(500, 3);
  KdTreeN tree;
  tree.setInputCloud(cloud);
  const pcl::PointNormal q = at(0.1f, -0.2f, 0.05f);
  pcl::Indices idx;
  std::vector<float> d2;
  // More neighbours asked for than the cloud holds: all of them, nearest first.
  ASSERT_EQ(tree.nearestKSearch(q, 600, idx, d2), 500);
  const auto all = brute_force(*cloud, q, 600, std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(idx[i], all[i].second);
  // A radius search keeping every point within it.
  const auto within = brute_force(*cloud, q, 600, 0.3);
  ASSERT_GT(within.size(), 12u);
  ASSERT_EQ(tree.radiusSearch(q, 0.3, idx, d2), int(within.size()));
  for (std::size_t i = 0; i < within.size(); ++i) EXPECT_EQ(idx[i], within[i].second);
  EXPECT_EQ(tree.getInputCloud(), cloud);
}

TEST(KdTree, AnEmptyCloudHasNoNeighboursAndASubsetIsRefused) {
  KdTreeN tree;
  tree.setInputCloud(CloudN::Ptr(new CloudN));
  pcl::Indices idx{5};
  std::vector<float> d2{1};
  EXPECT_EQ(tree.nearestKSearch(at(0, 0, 0), 3, idx, d2), 0);
  EXPECT_TRUE(idx.empty());
  const CloudN::Ptr cloud = random_cloud(10, 1);
  pcl::IndicesConstPtr subset(new pcl::Indices{1, 2});
  EXPECT_THROW(tree.setInputCloud(cloud, subset), std::invalid_argument);
}

}  // namespace
}  // namespace semioctree::detail
