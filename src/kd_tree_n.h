// The kd-tree of registration (internal header): a cloud of pcl::PointNormal searched by
// nanoflann behind PCL's search::KdTree interface, which PCL's ICP takes.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <stdexcept>
#include <vector>

namespace semioctree::detail {

// The k nearest points within a bound, as a nanoflann result set: nearest first, each at
// a squared distance below max_d2 (strictly, as PCL's FLANN radius search keeps them).
class NearestWithin {
 public:
  // indices and d2: room for k each (k ≤ 0: nothing is kept).
  NearestWithin(int k, float max_d2, int* indices, float* d2)
      : k_(std::max(k, 0)), bound_(max_d2), indices_(indices), d2_(d2) {}
  std::size_t size() const { return std::size_t(n_); }
  bool full() const { return n_ == k_; }
  // nanoflann offers the points nearer than worstDist(), read once a leaf: a point may
  // come after the set filled with nearer ones, and is then left out.
  bool addPoint(float d2, int index) {
    int i = n_;
    for (; i > 0 && d2_[i - 1] > d2; --i)
      if (i < k_) d2_[i] = d2_[i - 1], indices_[i] = indices_[i - 1];
    if (i < k_) d2_[i] = d2, indices_[i] = index;
    if (n_ < k_) ++n_;
    return true;
  }
  float worstDist() const { return n_ == k_ && k_ > 0 ? d2_[k_ - 1] : bound_; }

 private:
  int k_, n_ = 0;
  float bound_;  // nanoflann offers the points strictly nearer than worstDist()
  int* indices_;
  float* d2_;
};

// A kd-tree over a PointNormal cloud behind PCL's KdTree interface, answered by nanoflann
// (leaves of 10 points): the neighbours PCL's FLANN tree finds (within a radius: strictly
// nearer than it), nearest first, in about half the time for the k nearest and a quarter
// for the nearest within a bound (docs/registration.md, "What it costs"). Points at equal
// distances may come in another order. Searches are const and may run in parallel.
class KdTreeN : public pcl::search::KdTree<pcl::PointNormal> {
 public:
  using PointN = pcl::PointNormal;
  using CloudN = pcl::PointCloud<PointN>;
  using Ptr = pcl::shared_ptr<KdTreeN>;

  KdTreeN() = default;
  KdTreeN(const KdTreeN&) = delete;  // nanoflann's index refers to this tree's points_
  KdTreeN& operator=(const KdTreeN&) = delete;

  // The whole cloud, of finite points (a subset given by indices: std::invalid_argument).
  // The cloud must outlive the tree and keep its points where they are.
  void setInputCloud(const PointCloudConstPtr& cloud,
                     const IndicesConstPtr& indices = IndicesConstPtr()) override {
    if (indices) throw std::invalid_argument("KdTreeN: searches over a subset are not supported");
    input_ = cloud;
    indices_.reset();
    index_.reset();
    points_ = Points{cloud.get()};
    if (cloud && !cloud->empty())
      index_ = std::make_unique<Index>(3, points_, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  }
  // The (up to) k nearest points within `radius` of p (squared distance < radius², in
  // floats as PCL's), nearest first, into indices[0..) and d2[0..) (room for k each);
  // returns how many. An infinite radius bounds nothing; a NaN one finds nothing.
  int nearest_within(const PointN& p, int k, double radius, int* indices, float* d2) const {
    if (k <= 0 || !index_ || !(radius > 0)) return 0;
    const float max_d2 = float(radius * radius);  // infinity stays infinite
    NearestWithin found(k, max_d2, indices, d2);
    index_->findNeighbors(found, p.data, nanoflann::SearchParams());
    return int(found.size());
  }
  using pcl::search::KdTree<PointN>::nearestKSearch;
  int nearestKSearch(const PointN& p, int k, pcl::Indices& indices,
                     std::vector<float>& d2) const override {
    return within(p, k, std::numeric_limits<double>::infinity(), indices, d2);
  }
  using pcl::search::KdTree<PointN>::radiusSearch;
  // The points within `radius`, nearest first: all of them (max_nn 0) or the max_nn nearest.
  int radiusSearch(const PointN& p, double radius, pcl::Indices& indices, std::vector<float>& d2,
                   unsigned int max_nn = 0) const override {
    return within(p, max_nn > 0 ? int(std::min<std::size_t>(max_nn, size())) : int(size()), radius,
                  indices, d2);
  }

 private:
  std::size_t size() const { return input_ ? input_->size() : 0; }
  int within(const PointN& p, int k, double radius, pcl::Indices& indices,
             std::vector<float>& d2) const {
    k = std::clamp(k, 0, int(size()));
    indices.resize(std::size_t(k));
    d2.resize(std::size_t(k));
    const int n = nearest_within(p, k, radius, indices.data(), d2.data());
    indices.resize(std::size_t(n));
    d2.resize(std::size_t(n));
    return n;
  }
  // The cloud as nanoflann's dataset.
  struct Points {
    const CloudN* cloud = nullptr;
    std::size_t kdtree_get_point_count() const { return cloud->size(); }
    float kdtree_get_pt(std::size_t i, std::size_t d) const { return (*cloud)[i].data[d]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Points>,
                                                    Points, 3, int>;
  Points points_;
  std::unique_ptr<Index> index_;
};

}  // namespace semioctree::detail
