// Scans in: a scan is its points (in the scanner's frame) plus the scanner's
// pose in the survey frame. Readers for PCD and PLY (PCL), XYZ text and PTX
// (several scans per file, each with its pose). NaN/Inf points are dropped and
// counted, never fatal.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace semioctree {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// Largest scanner coordinate a pose may give, metres: points are floats, and
// beyond 1e5 m a float resolves no better than 8 mm; a larger value is a typo.
constexpr double kMaxPoseCoordinate = 1e5;
// A pose's rotation part must be orthonormal (RᵀR = I) within this, with determinant +1.
constexpr double kRotationTolerance = 1e-4;

// Scanner pose: the rigid transform from the scanner's frame to the survey frame.
struct ScanPose {
  Eigen::Isometry3d scanner_to_survey = Eigen::Isometry3d::Identity();

  static ScanPose from_xyz_yaw(double x, double y, double z, double yaw_deg);
  Eigen::Vector3d position() const { return scanner_to_survey.translation(); }
  double yaw_deg() const;  // heading about z
};

struct Scan {
  Cloud::Ptr points;  // scanner frame
  ScanPose pose;
  std::string source;               // file (and scan number for PTX)
  std::size_t invalid_dropped = 0;  // NaN/Inf points and PTX "no return" points
  // The file gave the pose: a PTX header, or a PCD/PLY viewpoint other than the
  // identity (PCL's VIEWPOINT / camera element, as `semioctree scan` writes it).
  bool pose_from_file = false;
};

// Bad input: the message names the file (and line where it applies).
class ScanReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// By extension (case-insensitive): .pcd, .ply, .xyz/.txt/.asc, .ptx. PCD and
// PLY give one scan posed by the file's viewpoint (points in the scanner's
// frame, the viewpoint the scanner's pose: the identity when the file has
// none); XYZ one scan with the identity pose; PTX one scan per header. Throws
// ScanReadError for a file that cannot be read, is malformed or holds no point.
std::vector<Scan> read_scans(const std::string& path);

// Every pose read (PTX header, PCD/PLY viewpoint, text, JSON) is checked: finite,
// rigid, within kMaxPoseCoordinate, a heading within ±360°.
// "X,Y,Z,YAW_DEG" (YAW optional) → pose; throws std::invalid_argument.
ScanPose parse_pose(const std::string& text);
// {"x":..,"y":..,"z":..,"yaw_deg":..} → pose; throws ScanReadError.
ScanPose read_pose_json(const std::string& path);

// Points transformed into the survey frame.
Cloud::Ptr to_survey_frame(const Scan& scan);

}  // namespace semioctree
