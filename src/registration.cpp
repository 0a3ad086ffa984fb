#include "semioctree/registration.h"

#include <pcl/common/centroid.h>
#include <pcl/common/common.h>
#include <pcl/common/eigen.h>
#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/transformation_estimation_point_to_plane_lls.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "kd_tree_n.h"
#include "parallel_for.h"
#include "planar_point_to_plane.h"
#include "random_subset.h"
#include "semioctree/timing.h"

namespace semioctree {

namespace {

using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;
// PCL's ICP, exposing the number of iterations of the last alignment.
class Icp : public pcl::IterativeClosestPoint<PointN, PointN, double> {
 public:
  int iterations() const { return nr_iterations_; }
};

// A point's surface normal (needed by the point-to-plane error): the smallest
// eigenvector of the covariance of its (up to) 12 nearest neighbours in `tree` within
// `radius`. A point with fewer than 3 such neighbours (an isolated return) keeps a zero
// normal: it then adds nothing to the point-to-plane error. Returns whether it got one.
// `nn` and `d2` are the caller's buffers (room for 12 each).
constexpr int kNormalNeighbours = 12;
bool fit_normal(PointN& q, const detail::KdTreeN& tree, double radius, pcl::Indices& nn,
                float* d2) {
  nn.resize(kNormalNeighbours);
  const int found = tree.nearest_within(q, kNormalNeighbours, radius, nn.data(), d2);
  nn.resize(std::size_t(found));
  if (found < 3) return false;
  Eigen::Matrix3f cov;
  Eigen::Vector4f centroid;
  if (pcl::computeMeanAndCovarianceMatrix(*tree.getInputCloud(), nn, cov, centroid) < 3)
    return false;
  float eigenvalue;
  Eigen::Vector3f n;
  pcl::eigen33(cov, eigenvalue, n);
  if (!n.allFinite() || n.squaredNorm() < 0.5f) return false;
  q.normal_x = n.x();
  q.normal_y = n.y();
  q.normal_z = n.z();
  return true;
}

// The target's kd-tree as ICP's correspondence search. PCL's correspondence
// estimation asks for the nearest neighbour of every source point and drops it
// when farther than the correspondence distance; an unbounded search from a point
// far from any target surface (newly seen parts of the room, or a cloud that does
// not match at all) visits a large part of the tree. Searching only within the
// correspondence distance gives the same correspondences, several times faster
// on such points (a uniform-noise source: 0.64 → 0.23 s per iteration).
//
// The target's normals (and, with the facing known, their orientation) are fitted when
// a search first meets a point, into the target cloud itself: ICP pairs a share of the
// target's points, and reads the normals of those only (docs/registration.md, "What it
// costs"). Each point's normal is its own, so they are the normals a pass over every
// point gives. Searches are therefore not const in effect: one thread at a time.
//
// With the surfaces' facing known (SurfaceFacing), a source point with a normal pairs
// with the nearest target point within the bound whose surface faces the same way (or
// whose facing is unknown): the two faces of a wall are not confused.
class BoundedKdTree : public detail::KdTreeN {
 public:
  using Ptr = pcl::shared_ptr<BoundedKdTree>;
  // The target, whose normals are fitted within `radius` on demand (its normals zero
  // until then), and its facing (may be null; `offset` shifts it back to the facing's
  // frame). The cloud must outlive the tree.
  BoundedKdTree(const CloudN::Ptr& target, double radius, const SurfaceFacing* facing,
                const Eigen::Vector3d& offset)
      : target_(target), radius_(radius), offset_(offset), state_(target->size(), kUnfitted) {
    if (facing && facing->target_side) target_side_ = facing->target_side;
    setInputCloud(target);
  }
  void set_bound(double distance) { bound_ = distance; }
  // The number of target points with a normal among the first that give `wanted` of
  // them (all points when fewer have one).
  std::size_t normals_up_to(std::size_t wanted) const {
    std::size_t with_normal = 0;
    for (std::size_t i = 0; i < state_.size() && with_normal < wanted; ++i)
      if (prepare(int(i)) != kNoNormal) ++with_normal;
    return with_normal;
  }
  using detail::KdTreeN::nearestKSearch;
  int nearestKSearch(const PointN& point, int k, pcl::Indices& indices,
                     std::vector<float>& sqr_distances) const override {
    if (k != 1 || !(bound_ > 0)) {
      const int found = KdTreeN::nearestKSearch(point, k, indices, sqr_distances);
      for (int i = 0; i < found; ++i) prepare(indices[std::size_t(i)]);
      return found;
    }
    const Eigen::Vector3f n = point.getNormalVector3fMap();
    // The nearest within the bound, or the nearest few, nearest first: the first on a
    // surface facing the same way.
    constexpr int kFacingCandidates = 8;
    const bool facing = target_side_ && !(n.squaredNorm() < 0.5f);  // (a NaN normal: facing)
    int near[kFacingCandidates];
    float d2[kFacingCandidates];
    // The nearest alone first: most often it faces the same way, and a search for one
    // prunes more than a search for eight (whose first is the same point).
    int found = nearest_within(point, 1, bound_, near, d2);
    if (facing && found == 1 && !accepts(n, near[0]))
      found = nearest_within(point, kFacingCandidates, bound_, near, d2);
    for (int i = 0; i < found; ++i) {
      if (accepts(n, near[i]) || !facing) {  // (its normal fitted either way)
        indices.assign(1, near[i]);
        sqr_distances.assign(1, d2[i]);
        return 1;
      }
    }
    // None: report one "infinitely far" neighbour, which the caller rejects.
    indices.assign(1, 0);
    sqr_distances.assign(1, std::numeric_limits<float>::infinity());
    return 0;
  }

 private:
  enum State : std::uint8_t { kUnfitted, kNoNormal, kUnoriented, kOriented };
  // Whether target point i may pair with a source point of normal n: its normal, fitted
  // now if not yet, is unknown or unoriented, or faces the same way.
  bool accepts(const Eigen::Vector3f& n, int i) const {
    return prepare(i) != kOriented ||
           n.dot((*input_)[std::size_t(i)].getNormalVector3fMap()) > 0.0f;
  }
  // Fits point i's normal (and orients it) the first time it is asked for.
  State prepare(int i) const {
    State& state = state_[std::size_t(i)];
    if (state != kUnfitted) return state;
    PointN& q = (*target_)[std::size_t(i)];
    if (!fit_normal(q, *this, radius_, nn_, d2_)) return state = kNoNormal;
    if (!target_side_) return state = kUnoriented;
    // The side the surface was seen from: turned towards it, or left unoriented.
    const Eigen::Vector3f n = q.getNormalVector3fMap();
    const Eigen::Vector3d at = q.getVector3fMap().cast<double>() + offset_;
    const int side = target_side_(at, n.cast<double>());
    if (side == 0) return state = kUnoriented;
    if (side < 0) q.getNormalVector3fMap() = -n;
    return state = kOriented;
  }

  CloudN::Ptr target_;
  double radius_;
  Eigen::Vector3d offset_;
  std::function<int(const Eigen::Vector3d&, const Eigen::Vector3d&)> target_side_;
  double bound_ = 0;
  mutable std::vector<State> state_;
  mutable pcl::Indices nn_;  // fit_normal's buffers
  mutable float d2_[kNormalNeighbours];
};

// Voxel-grid downsampling (one centroid per occupied voxel) of `in`, or of the points of
// `in` that `indices` lists (all of them when null). PCL's VoxelGrid refuses grids of more
// than 2^31 cells (it then returns the input unchanged, e.g. a 0.05 m grid over a 60
// m-range scan with outliers), so such clouds are cut into slabs along x that each fit and
// filtered slab by slab.
Cloud::Ptr voxel_downsample(const Cloud& in, double leaf,
                            const pcl::IndicesConstPtr& indices = nullptr) {
  Cloud::Ptr out(new Cloud);
  if (indices ? indices->empty() : in.empty()) return out;
  Eigen::Vector4f lo, hi;
  if (indices)
    pcl::getMinMax3D(in, *indices, lo, hi);
  else
    pcl::getMinMax3D(in, lo, hi);
  if (!lo.allFinite() || !hi.allFinite()) return out;  // no finite point
  auto cells = [&](int axis) { return std::int64_t(std::floor((hi[axis] - lo[axis]) / leaf)) + 1; };
  const std::int64_t nx = cells(0), nyz = cells(1) * cells(2);
  const std::int64_t limit = std::numeric_limits<std::int32_t>::max() / 2;
  const std::int64_t slab_cells = std::max<std::int64_t>(1, limit / std::max<std::int64_t>(1, nyz));
  const std::int64_t slabs = (nx + slab_cells - 1) / slab_cells;

  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setLeafSize(float(leaf), float(leaf), float(leaf));
  if (slabs <= 1) {
    grid.setInputCloud(Cloud::ConstPtr(&in, [](const Cloud*) {}));  // lent, not copied
    if (indices) grid.setIndices(indices);
    grid.filter(*out);
    return out;
  }
  std::vector<Cloud::Ptr> parts(std::size_t(slabs), nullptr);
  const double width = double(slab_cells) * leaf;
  auto to_slab = [&](const pcl::PointXYZ& p) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
    const auto s = std::min<std::int64_t>(slabs - 1, std::int64_t((p.x - lo.x()) / width));
    auto& part = parts[std::size_t(s)];
    if (!part) part.reset(new Cloud);
    part->push_back(p);
  };
  if (indices)
    for (const auto i : *indices) to_slab(in[std::size_t(i)]);
  else
    for (const auto& p : in) to_slab(p);
  for (const auto& part : parts) {
    if (!part) continue;
    Cloud filtered;
    grid.setInputCloud(part);
    grid.filter(filtered);
    *out += filtered;
  }
  return out;
}

// The indices of the points of `cloud` inside the bounding box of `around` grown by
// `margin` on every side; null when all of them are.
pcl::IndicesPtr near_box(const Cloud& cloud, const Cloud& around, double margin) {
  Eigen::Vector4f lo, hi;
  pcl::getMinMax3D(around, lo, hi);
  const Eigen::Array3f grow = Eigen::Array3f::Constant(float(margin));
  const Eigen::Array3f low = lo.head<3>().array() - grow, high = hi.head<3>().array() + grow;
  auto inside = [&](const pcl::PointXYZ& q) {
    const Eigen::Array3f v = q.getArray3fMap();
    return (v >= low).all() && (v <= high).all();
  };
  const auto n = std::size_t(std::count_if(cloud.begin(), cloud.end(), inside));
  if (n == cloud.size()) return nullptr;
  pcl::IndicesPtr out(new pcl::Indices);
  out->reserve(n);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (inside(cloud[i])) out->push_back(pcl::index_t(i));
  return out;
}

// Points shifted by −offset, as PointNormal (normals zero).
CloudN::Ptr shifted(const Cloud& in, const Eigen::Vector3d& offset) {
  CloudN::Ptr out(new CloudN);
  out->reserve(in.size());
  for (const auto& p : in) {
    PointN q;
    q.x = float(double(p.x) - offset.x());
    q.y = float(double(p.y) - offset.y());
    q.z = float(double(p.z) - offset.z());
    q.normal_x = q.normal_y = q.normal_z = 0.0f;
    q.curvature = 0.0f;
    out->push_back(q);
  }
  return out;
}

// The normals of every point of `cloud` (fit_normal), fitted to the points of `tree`, on
// `threads` workers (0: one per core): each point's normal is its own, the same on any
// number of threads.
void estimate_normals(CloudN& cloud, const detail::KdTreeN& tree, double radius, unsigned threads) {
  constexpr std::size_t kChunk = 1024;
  const unsigned workers = detail::thread_count(threads);
  struct Scratch {
    pcl::Indices nn;
    float d2[kNormalNeighbours];
  };
  std::vector<Scratch> scratch(workers);
  detail::parallel_for(
      (cloud.size() + kChunk - 1) / kChunk, workers, 1, [&](std::size_t c, unsigned w) {
        Scratch& s = scratch[w];
        for (std::size_t i = c * kChunk, end = std::min(cloud.size(), i + kChunk); i < end; ++i)
          fit_normal(cloud[i], tree, radius, s.nn, s.d2);
      });
}

// Normals of `cloud` (estimate_normals within `radius`) turned towards `viewpoint`.
// `neighbours`: the cloud whose points the normals are fitted to (null: `cloud` itself).
void normals_facing(CloudN& cloud, double radius, const Eigen::Vector3f& viewpoint,
                    unsigned threads, const CloudN::ConstPtr& neighbours = nullptr) {
  if (cloud.empty()) return;
  detail::KdTreeN tree;
  tree.setInputCloud(neighbours ? neighbours : pcl::make_shared<CloudN>(cloud));
  estimate_normals(cloud, tree, radius, threads);
  for (PointN& q : cloud) {
    const Eigen::Vector3f n = q.getNormalVector3fMap();
    if (n.dot(viewpoint - q.getVector3fMap()) < 0.0f) q.getNormalVector3fMap() = -n;
  }
}

std::string describe(const RegistrationResult& r, const RegistrationParams& p) {
  std::ostringstream m;
  m << "fitness " << r.fitness << " m² (bound " << p.max_fitness << "), overlap " << r.overlap
    << " (bound " << p.min_overlap << ") within " << p.final_correspondence << " m; "
    << r.source_points << " source and " << r.target_points
    << " target points after downsampling; correction " << r.translation_m << " m, "
    << r.rotation_deg << "°";
  return m.str();
}

}  // namespace

Eigen::Isometry3d planar_pose(double x, double y, double yaw_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(x, y, 0.0));
  t.rotate(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()));
  return t;
}

RegistrationResult register_scan(const Cloud& source, const Cloud& target,
                                 const RegistrationParams& p, const SurfaceFacing* facing) {
  const auto t0 = Clock::now();
  if (!(p.voxel > 0) || !(p.final_correspondence > 0) ||
      !(p.max_correspondence >= p.final_correspondence) || p.max_iterations < 1 ||
      p.icp_source_points < std::max<std::size_t>(p.min_points, 1))
    throw std::invalid_argument(
        "registration parameters: need voxel > 0, 0 < final_correspondence <= "
        "max_correspondence, max_iterations >= 1 and icp_source_points >= min_points");
  if (source.empty() || target.empty()) {
    std::ostringstream m;
    m << "cannot register: the " << (source.empty() ? "source" : "target") << " cloud is empty";
    throw RegistrationError(m.str());
  }

  RegistrationResult r;
  const Cloud::Ptr src_ds = voxel_downsample(source, p.voxel);
  const double reach = 2.0 * p.max_correspondence;
  const Cloud::Ptr tgt_ds = voxel_downsample(target, p.voxel, near_box(target, *src_ds, reach));
  r.source_points = src_ds->size();
  r.target_points = tgt_ds->size();
  if (r.source_points >= p.min_points && r.target_points < p.min_points && !target.empty()) {
    std::ostringstream m;
    m << "registration failed: overlap 0 (bound " << p.min_overlap << "): only " << r.target_points
      << " target points (after " << p.voxel << " m downsampling) lie within " << reach
      << " m of the source's bounding box (need at least " << p.min_points
      << "); the clouds do not overlap or the initial guess is too far off";
    throw RegistrationError(m.str());
  }
  if (r.source_points < p.min_points || r.target_points < p.min_points) {
    std::ostringstream m;
    m << "cannot register: too few points after " << p.voxel << " m downsampling ("
      << r.source_points << " source, " << r.target_points << " target; need at least "
      << p.min_points << " each)";
    throw RegistrationError(m.str());
  }

  // Work about the source's centroid (in x, y only, so that a rotation about
  // z stays a planar motion): float coordinates keep their precision and the
  // yaw is not coupled to a translation by a lever of the survey's size.
  Eigen::Vector4d centroid;
  pcl::compute3DCentroid(*src_ds, centroid);
  const Eigen::Vector3d offset(centroid.x(), centroid.y(), 0.0);
  const CloudN::Ptr src = shifted(*src_ds, offset);
  const CloudN::Ptr tgt = shifted(*tgt_ds, offset);
  // One kd-tree over the target serves the normals, ICP and the final check; it fits the
  // target's normals as its searches meet them.
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  if (facing) viewpoint = (facing->source_viewpoint - offset).cast<float>();
  const BoundedKdTree::Ptr tree(new BoundedKdTree(tgt, 4.0 * p.voxel, facing, offset));
  const std::size_t with_normal = tree->normals_up_to(p.min_points);
  if (with_normal < p.min_points) {
    std::ostringstream m;
    m << "cannot register: only " << with_normal << " of " << tgt->size()
      << " target points have a surface normal (need at least " << p.min_points << ")";
    throw RegistrationError(m.str());
  }
  // Which way the surfaces face: the target's from where they were seen (as the tree fits
  // them), the source's towards its scanner (per stage, on that stage's sampling).
  auto source_at = [&](const CloudN::Ptr& cloud, double voxel) {
    if (facing && facing->target_side) normals_facing(*cloud, 4.0 * voxel, viewpoint, p.threads);
    return cloud;
  };
  // The source of a stage, with its normals: src_ds downsampled to `voxel` (src itself at
  // p.voxel), coarser by √2 steps until it holds at most icp_source_points. The last one
  // is kept for the next stage.
  double last_voxel = 0;
  CloudN::Ptr last;
  auto icp_source = [&](double voxel) {
    if (last && voxel == last_voxel) return last;
    last_voxel = voxel;
    if (voxel == p.voxel && src->size() <= p.icp_source_points) return last = source_at(src, voxel);
    Cloud::Ptr sampled = voxel_downsample(*src_ds, voxel);
    while (sampled->size() > p.icp_source_points) {
      voxel *= std::sqrt(2.0);
      sampled = voxel_downsample(*src_ds, voxel);
    }
    return last = source_at(shifted(*sampled, offset), voxel);
  };

  Icp icp;
  if (p.planar) {
    // x, y, yaw: the point-to-plane error linearised in the yaw, one 3 × 3 solve an
    // iteration (PCL's 3-DoF warp is minimised by Levenberg-Marquardt, several times
    // over every pair an iteration, to the same placements: docs/registration.md).
    icp.setTransformationEstimation(pcl::make_shared<detail::PlanarPointToPlane>());
  } else {
    icp.setTransformationEstimation(
        pcl::make_shared<
            pcl::registration::TransformationEstimationPointToPlaneLLS<PointN, PointN, double>>());
  }
  icp.setInputTarget(tgt);
  icp.setSearchMethodTarget(tree, true);  // built above over the same cloud
  icp.setMaximumIterations(p.max_iterations);
  icp.setTransformationEpsilon(1e-8);  // (0.1 mm)² between iterations
  icp.setTransformationRotationEpsilon(1.0 - 1e-9);
  icp.setEuclideanFitnessEpsilon(1e-6);  // relative change of the mean squared error

  // Coarse to fine: the correspondence distance shrinks geometrically from
  // max_correspondence to final_correspondence, by at most 4× per stage (0.5,
  // 0.16, 0.05 m by default). Point-to-plane ICP converges within a stage in a
  // few iterations, so more stages would mostly add iterations that only confirm.
  const double ratio = p.max_correspondence / p.final_correspondence;
  const int stages = 1 + int(std::ceil(std::log(ratio) / std::log(4.0) - 1e-9));
  Eigen::Matrix4d estimate = Eigen::Matrix4d::Identity();
  for (int s = 0; s < stages; ++s) {
    const double d = stages == 1
                         ? p.final_correspondence
                         : p.max_correspondence * std::pow(1.0 / ratio, double(s) / (stages - 1));
    // The coarse stages need no fine sampling of the source: a voxel of a
    // quarter of the correspondence distance is plenty, and makes the first
    // stage, where most iterations happen, several times cheaper.
    // Past p.icp_source_points, the source is sampled coarser still (icp_source).
    const double stage_voxel = d / 4.0;
    icp.setInputSource(icp_source(stage_voxel > 1.2 * p.voxel ? stage_voxel : p.voxel));
    icp.setMaxCorrespondenceDistance(d);
    tree->set_bound(d * 1.0001);
    CloudN aligned;
    icp.align(aligned, estimate);
    r.iterations += icp.iterations();
    if (!icp.hasConverged()) {
      std::ostringstream m;
      m << "registration failed: ICP found no correspondences within " << d << " m (stage " << s + 1
        << " of " << stages << "): overlap 0 (bound " << p.min_overlap
        << "), fitness undefined (bound " << p.max_fitness
        << " m²); the clouds do not overlap or the initial guess is too far off";
      throw RegistrationError(m.str());
    }
    estimate = icp.getFinalTransformation();
    // PCL counts reaching max_iterations as converged; we do not.
    r.converged =
        icp.getConvergeCriteria()->getConvergenceState() !=
        pcl::registration::DefaultConvergenceCriteria<double>::CONVERGENCE_CRITERIA_ITERATIONS;
  }
  // Fitness and overlap over the final correspondence distance, of the source points
  // (downsampled to p.voxel, as the bounds assume; a random icp_source_points of them if
  // more, normals from all: the means are the same) against every downsampled target
  // point (PCL's getFitnessScore, plus the inlier share; with the facing known, on
  // surfaces facing the same way).
  CloudN::Ptr checked = src;
  if (src->size() > p.icp_source_points) {
    checked = detail::random_subset(*src, p.icp_source_points, 4321);
    if (facing && facing->target_side)
      normals_facing(*checked, 4.0 * p.voxel, viewpoint, p.threads, src);
  } else {
    checked = icp_source(p.voxel);  // src, with its normals
  }
  CloudN aligned;
  pcl::transformPointCloudWithNormals(*checked, aligned, estimate);

  pcl::Indices nn(1);
  std::vector<float> d2(1);
  const double max_d2 = p.final_correspondence * p.final_correspondence;
  double sum = 0;
  std::size_t inliers = 0;
  tree->set_bound(p.final_correspondence);
  for (const auto& q : aligned) {
    if (tree->nearestKSearch(q, 1, nn, d2) > 0 && d2[0] <= max_d2) {
      sum += d2[0];
      ++inliers;
    }
  }
  r.overlap = double(inliers) / double(aligned.size());
  r.fitness = inliers > 0 ? sum / double(inliers) : std::numeric_limits<double>::infinity();

  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = offset;
  Eigen::Isometry3d icp_t;
  icp_t.matrix() = estimate;
  r.correction = shift * icp_t * shift.inverse();
  // Keep the rotation exactly orthonormal (the ICP result went through floats).
  r.correction.linear() =
      Eigen::Quaterniond(r.correction.rotation()).normalized().toRotationMatrix();
  r.translation_m = r.correction.translation().norm();
  r.rotation_deg = Eigen::AngleAxisd(r.correction.rotation()).angle() * 180.0 / M_PI;
  r.seconds = seconds_since(t0);

  if (!(r.fitness <= p.max_fitness) || r.overlap < p.min_overlap)
    throw RegistrationError("registration failed the bounds: " + describe(r, p));
  return r;
}

}  // namespace semioctree
