// Drawing a random subset of a point cloud, for the stages that search or check on a
// sample of a scan (RANSAC's planes, registration's final check).
#pragma once

#include <pcl/point_cloud.h>

#include <cstddef>
#include <cstdint>
#include <random>

#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree::detail {

// `count` points of `cloud` drawn at random, each at most once, in the order drawn (a copy
// of all of them if it has no more); the same seed draws the same points. The first
// `count` steps of a Fisher-Yates shuffle of the indices, with only the indices the steps
// move held in a hash map: drawing tens of thousands of points of a scan of millions
// neither copies nor shuffles the whole scan.
template <class PointT>
typename pcl::PointCloud<PointT>::Ptr random_subset(const pcl::PointCloud<PointT>& cloud,
                                                    std::size_t count, std::uint64_t seed) {
  typename pcl::PointCloud<PointT>::Ptr out(new pcl::PointCloud<PointT>);
  if (cloud.size() <= count) {
    *out = cloud;
    return out;
  }
  std::mt19937_64 rng(seed);
  PackedKeyMap<std::uint64_t> moved(2 * count);  // index → the index now at it
  auto at = [&](std::uint64_t i) { return moved.value_or(i, i); };
  out->reserve(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    const std::uint64_t j = std::uniform_int_distribution<std::uint64_t>(i, cloud.size() - 1)(rng);
    const std::uint64_t drawn = at(j);
    moved.insert_or_assign(j, at(i));
    out->push_back(cloud[std::size_t(drawn)]);
  }
  return out;
}

}  // namespace semioctree::detail
