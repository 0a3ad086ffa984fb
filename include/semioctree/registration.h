// Stage 2 (paper 2.3): scans after the first are placed in the survey frame by
// the robot's reported (odometry) pose, then refined by ICP against the merged
// cloud of the previous scans.
// The frames and the order in which a scan is levelled, placed and refined:
// docs/data-flow.md ("Frames").
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <stdexcept>

#include "semioctree/scan_io.h"

namespace semioctree {

struct RegistrationParams {
  double voxel = 0.05;                 // both clouds are voxel-downsampled to this for ICP, m
  double max_correspondence = 0.5;     // first (coarse) ICP stage, m
  double final_correspondence = 0.05;  // last stage, m; stages in between shrink it ≤ 4× each
  int max_iterations = 50;             // per stage
  // Failure bounds, both measured over final_correspondence on the downsampled
  // clouds. Two samplings of the same surfaces at 0.05 m, well aligned, give a
  // fitness of 2-3e-4 m² (the nearest voxel centroid lies a couple of cm away
  // along the surface); unrelated points spread over the 0.05 m band give
  // ≈ final_correspondence² / 3 = 8e-4 m². Scale max_fitness with
  // final_correspondence² (and voxel²) when changing those.
  double max_fitness = 6e-4;  // m²
  // Share of source points with a target point within final_correspondence.
  // A second scan 2.4 m from the first in the same room overlaps ~0.7; a scan
  // that sees mostly new space (another room) may fall below this bound.
  double min_overlap = 0.25;
  // true: estimate x, y and yaw only. Both clouds are levelled with the floor at
  // z = 0 by `preprocess`, which fixes z, roll and pitch from the whole floor —
  // far better than ICP can on clouds whose floor and ceiling were cut out (only
  // a few bench tops and sills constrain them). Dropping those 3 DoF also removes
  // the ways a coarse stage can go wrong (tilting or sinking to fit a wall) and
  // leaves fewer unknowns for the same data. false: full 6 DoF (clouds that are
  // not levelled alike).
  bool planar = true;
  std::size_t min_points = 100;  // fewer points in either cloud after downsampling: error
  // ICP pairs at most this many source points an iteration (the source downsampled
  // coarser until it fits); fitness and overlap are measured on the last stage's source
  // (docs/registration.md, "What it costs").
  std::size_t icp_source_points = 20000;
  // Workers for the source's surface normals (0: one per core); the result is the same.
  unsigned threads = 0;
};

struct RegistrationResult {
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();  // refined = correction · guess
  double fitness = 0;      // mean squared distance of the source points that have a target point
                           // within final_correspondence (as PCL's getFitnessScore), m²
  double overlap = 0;      // share of source points with a target point within final_correspondence
  bool converged = false;  // the last stage met ICP's convergence criteria before max_iterations
  double translation_m = 0, rotation_deg = 0;        // size of the correction
  std::size_t source_points = 0, target_points = 0;  // after downsampling
  int iterations = 0;                                // ICP iterations, all stages
  double seconds = 0;                                // wall-clock time of register_scan
};

class RegistrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Which way the surfaces of both clouds face (docs/registration.md, "The two faces of
// a wall"). With it, a source point pairs only with target points on a surface facing
// the same way, so that the side of a wall a new scan sees first is not laid onto the
// other side, mapped from the next room (a shift by the wall's thickness that fits well).
struct SurfaceFacing {
  // The source scan's optical centre, placed as the source is: its surfaces face it.
  Eigen::Vector3d source_viewpoint = Eigen::Vector3d::Zero();
  // The side from which the target's surface at `point` (normal `normal`, either sign)
  // was seen: +1 along the normal, -1 against it, 0 unknown (both sides, or neither).
  std::function<int(const Eigen::Vector3d& point, const Eigen::Vector3d& normal)> target_side;
};

// `source` is already placed by the initial guess (odometry) in the target's
// frame; only the target's points within 2 · max_correspondence of the source's bounding
// box take part (ICP cannot bring the source further). `facing` (may be null): pair only
// surfaces that face the same way. Throws
// RegistrationError (the message gives fitness, overlap and the bounds) when the
// result fails the bounds, when ICP finds no correspondences, or when either cloud
// is empty or too small; std::invalid_argument for inconsistent parameters.
RegistrationResult register_scan(const Cloud& source, const Cloud& target,
                                 const RegistrationParams& params = {},
                                 const SurfaceFacing* facing = nullptr);

// Placement of a levelled scan by a planar pose: rotation `yaw_deg` about z,
// then translation (x, y, 0).
Eigen::Isometry3d planar_pose(double x, double y, double yaw_deg);

}  // namespace semioctree
