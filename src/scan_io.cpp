#include "semioctree/scan_io.h"

#include <pcl/common/transforms.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "point_file_checks.h"

namespace semioctree {

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool finite(const pcl::PointXYZ& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// Drops NaN/Inf points in place; returns how many.
std::size_t drop_invalid(Cloud& cloud) {
  const std::size_t before = cloud.size();
  cloud.erase(
      std::remove_if(cloud.begin(), cloud.end(), [](const pcl::PointXYZ& p) { return !finite(p); }),
      cloud.end());
  cloud.width = std::uint32_t(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  return before - cloud.size();
}

std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// Empty when `m` (scanner → survey) is a rigid transform whose position lies
// within kMaxPoseCoordinate; else what is wrong with it.
std::string pose_problem(const Eigen::Matrix4d& m) {
  if (!m.allFinite()) return "is not finite (NaN or Inf)";
  const Eigen::Vector3d t = m.block<3, 1>(0, 3);
  if (t.cwiseAbs().maxCoeff() > kMaxPoseCoordinate)
    return "puts the scanner at (" + number_text(t.x()) + ", " + number_text(t.y()) + ", " +
           number_text(t.z()) + "), beyond ±" + number_text(kMaxPoseCoordinate) + " m";
  const Eigen::Matrix3d r = m.block<3, 3>(0, 0);
  const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > kRotationTolerance)
    return "is not rigid: its rotation part is not orthonormal (axis lengths " +
           number_text(r.col(0).norm()) + ", " + number_text(r.col(1).norm()) + ", " +
           number_text(r.col(2).norm()) + "; RᵀR differs from the identity by " + number_text(off) +
           ", more than " + number_text(kRotationTolerance) + ")";
  if (r.determinant() < 0)
    return "is not rigid: its rotation part is a reflection (determinant -1)";
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kRotationTolerance)
    return "is not rigid: it is a projection, not a rotation and translation";
  return {};
}

void require_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw ScanReadError(path + ": no such file");
}

Scan read_pcl(const std::string& path, bool pcd) {
  require_file(path);
  std::string data = "data";
  if (pcd)
    data = detail::check_pcd_file(path) + " data";
  else
    detail::check_ply_file(path);
  Scan scan;
  scan.points.reset(new Cloud);
  scan.source = path;
  // What pcl::io::loadPCDFile / loadPLYFile do, with a check between reading
  // and converting.
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int version = 0, rc = 0;
  {
    // PCL warns on stderr about PLY elements it skips (e.g. its own camera
    // element); a failure is reported below through rc.
    const auto saved = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    if (pcd)
      rc = pcl::PCDReader().read(path, blob, origin, orientation, version);
    else
      rc = pcl::PLYReader().read(path, blob, origin, orientation, version);
    pcl::console::setVerbosityLevel(saved);
  }
  // The header and sizes were checked above: what PCL cannot read is the data.
  if (rc < 0)
    throw ScanReadError(
        path + ": not a readable " + (pcd ? "PCD" : "PLY") + " point cloud: its " + data + " is " +
        (data == "binary_compressed data" ? "corrupt (LZF decompression failed)" : "malformed"));
  // A PLY camera element sets the cloud's size from its data, after the
  // header: a size beyond the data read makes PCL's conversion read past it.
  const std::uint64_t cells = std::uint64_t(blob.width) * blob.height;
  if (cells == 0 || cells > detail::kMaxFilePoints ||
      blob.row_step != std::uint64_t(blob.width) * blob.point_step ||
      std::uint64_t(blob.row_step) * blob.height > blob.data.size())
    throw ScanReadError(path + ": the file's cloud size, " + std::to_string(blob.width) + " x " +
                        std::to_string(blob.height) + " points, does not match its data (" +
                        std::to_string(blob.point_step ? blob.data.size() / blob.point_step : 0) +
                        " points)");
  pcl::fromPCLPointCloud2(blob, *scan.points);
  scan.points->sensor_origin_ = origin;
  scan.points->sensor_orientation_ = orientation;
  const Eigen::Vector3f position = origin.head<3>();
  const Eigen::Quaternionf q = orientation;
  if (!position.allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-6f)
    throw ScanReadError(path + ": the file's viewpoint is not a valid pose");
  scan.pose.scanner_to_survey =
      Eigen::Translation3d(position.cast<double>()) * q.normalized().cast<double>();
  if (const std::string problem = pose_problem(scan.pose.scanner_to_survey.matrix());
      !problem.empty())
    throw ScanReadError(path + ": the file's viewpoint " + problem);
  scan.pose_from_file = !scan.pose.scanner_to_survey.isApprox(Eigen::Isometry3d::Identity());
  scan.invalid_dropped = drop_invalid(*scan.points);
  if (scan.points->empty()) throw ScanReadError(path + ": holds no valid points");
  return scan;
}

// Splits a line into numbers (spaces, tabs or commas); false if any token is not a number.
bool parse_numbers(const std::string& line, std::vector<double>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (std::isspace(static_cast<unsigned char>(line[i])) || line[i] == ','))
      ++i;
    if (i >= line.size()) break;
    const char* start = line.c_str() + i;
    char* end = nullptr;
    const double v = std::strtod(start, &end);
    if (end == start) return false;
    out.push_back(v);
    i += std::size_t(end - start);
  }
  return true;
}

Scan read_xyz(const std::string& path) {
  require_file(path);
  std::ifstream f(path);
  if (!f) throw ScanReadError(path + ": cannot open");
  Scan scan;
  scan.points.reset(new Cloud);
  scan.source = path;
  std::string line;
  std::vector<double> v;
  std::size_t lineno = 0;
  while (std::getline(f, line)) {
    ++lineno;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#' || line[first] == '/') continue;
    if (!parse_numbers(line, v) || v.size() < 3)
      throw ScanReadError(path + ":" + std::to_string(lineno) + ": expected 'x y z [...]', got '" +
                          line.substr(0, 60) + "'");
    const pcl::PointXYZ p{float(v[0]), float(v[1]), float(v[2])};
    if (finite(p))
      scan.points->push_back(p);
    else
      ++scan.invalid_dropped;
  }
  if (scan.points->empty()) throw ScanReadError(path + ": holds no valid points");
  return scan;
}

std::vector<Scan> read_ptx(const std::string& path) {
  require_file(path);
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  std::ifstream f(path);
  if (ec || !f) throw ScanReadError(path + ": cannot open");
  std::vector<Scan> scans;
  std::string line;
  std::vector<double> v;
  std::size_t lineno = 0;
  auto next_numbers = [&](std::size_t want, const char* what) {
    if (!std::getline(f, line))
      throw ScanReadError(path + ":" + std::to_string(lineno + 1) + ": file ends, expected " +
                          what);
    ++lineno;
    if (!parse_numbers(line, v) || v.size() < want)
      throw ScanReadError(path + ":" + std::to_string(lineno) + ": expected " + what + ", got '" +
                          line.substr(0, 60) + "'");
  };
  while (true) {
    // Skip blank lines between scans; stop at the end of the file.
    std::streampos at = f.tellg();
    bool more = false;
    while (std::getline(f, line)) {
      if (line.find_first_not_of(" \t\r") != std::string::npos) {
        more = true;
        break;
      }
      ++lineno;
      at = f.tellg();
    }
    if (!more) break;
    f.clear();
    f.seekg(at);
    next_numbers(1, "the column count");
    const double cols = v[0];
    next_numbers(1, "the row count");
    const double rows = v[0];
    if (!(cols >= 1 && rows >= 1 && cols * rows < 1e9))
      throw ScanReadError(path + ":" + std::to_string(lineno) + ": bad scan size " +
                          std::to_string(cols) + " x " + std::to_string(rows));
    for (int i = 0; i < 4; ++i) next_numbers(3, "a scanner position/axis line (3 numbers)");
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      next_numbers(4, "a transformation matrix row (4 numbers)");
      for (int c = 0; c < 4; ++c) m(r, c) = v[std::size_t(c)];
    }
    // PTX stores the matrix transposed: translation in the last row.
    if (const std::string problem = pose_problem(m.transpose()); !problem.empty())
      throw ScanReadError(path + ":" + std::to_string(lineno - 3) +
                          ": the transformation matrix of scan " + std::to_string(scans.size()) +
                          " " + problem);
    Scan scan;
    scan.points.reset(new Cloud);
    scan.source = path + "#" + std::to_string(scans.size());
    scan.pose.scanner_to_survey.matrix() = m.transpose();
    scan.pose_from_file = true;
    const std::size_t n = std::size_t(cols) * std::size_t(rows);
    // Each point takes at least "0 0 0" and a line end (the last may lack it): a
    // size the rest of the file cannot hold is wrong, and must not be allocated.
    const std::streamoff here = f.tellg();
    const std::uint64_t left =
        here < 0 ? 0 : file_size - std::min<std::uint64_t>(file_size, std::uint64_t(here));
    if (6 * std::uint64_t(n) - 1 > left)
      throw ScanReadError(path + ":" + std::to_string(lineno - 9) + ": scan " +
                          std::to_string(scans.size()) + " of " +
                          std::to_string(std::size_t(cols)) + " x " +
                          std::to_string(std::size_t(rows)) + " points needs at least " +
                          std::to_string(6 * std::uint64_t(n) - 1) + " more bytes, the file has " +
                          std::to_string(left) + " (truncated, or its size is wrong)");
    scan.points->reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      next_numbers(3, "a point 'x y z [intensity [r g b]]'");
      const pcl::PointXYZ p{float(v[0]), float(v[1]), float(v[2])};
      // (0, 0, 0) marks a direction with no return.
      if (!finite(p) || (v[0] == 0 && v[1] == 0 && v[2] == 0))
        ++scan.invalid_dropped;
      else
        scan.points->push_back(p);
    }
    if (scan.points->empty())
      throw ScanReadError(scan.source +
                          ": holds no valid points (each is (0, 0, 0), no return, or NaN)");
    scans.push_back(std::move(scan));
  }
  if (scans.empty()) throw ScanReadError(path + ": holds no scan");
  return scans;
}

}  // namespace

ScanPose ScanPose::from_xyz_yaw(double x, double y, double z, double yaw_deg) {
  ScanPose p;
  p.scanner_to_survey = Eigen::Translation3d(x, y, z) *
                        Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  return p;
}

double ScanPose::yaw_deg() const {
  const Eigen::Vector3d x_axis = scanner_to_survey.linear() * Eigen::Vector3d::UnitX();
  return std::atan2(x_axis.y(), x_axis.x()) * 180.0 / M_PI;
}

std::vector<Scan> read_scans(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") return {read_pcl(path, true)};
  if (ext == ".ply") return {read_pcl(path, false)};
  if (ext == ".xyz" || ext == ".txt" || ext == ".asc" || ext == ".pts") return {read_xyz(path)};
  if (ext == ".ptx") return read_ptx(path);
  throw ScanReadError(path + ": unknown point cloud format '" + ext +
                      "' (expected .pcd, .ply, .xyz/.txt/.asc or .ptx)");
}

ScanPose parse_pose(const std::string& text) {
  std::vector<double> v;
  if (!parse_numbers(text, v) || v.size() < 3 || v.size() > 4)
    throw std::invalid_argument("pose '" + text + "': expected X,Y,Z or X,Y,Z,YAW_DEG");
  for (double x : v)
    if (!std::isfinite(x)) throw std::invalid_argument("pose '" + text + "': not a finite number");
  if (v.size() == 4 && std::abs(v[3]) > 360)
    throw std::invalid_argument("pose '" + text + "': the heading must be within ±360 degrees");
  const ScanPose pose = ScanPose::from_xyz_yaw(v[0], v[1], v[2], v.size() == 4 ? v[3] : 0.0);
  if (const std::string problem = pose_problem(pose.scanner_to_survey.matrix()); !problem.empty())
    throw std::invalid_argument("pose '" + text + "' " + problem);
  return pose;
}

ScanPose read_pose_json(const std::string& path) {
  require_file(path);
  std::ifstream f(path);
  nlohmann::json j;
  try {
    f >> j;
  } catch (const std::exception& e) {
    throw ScanReadError(path + ": not valid JSON: " + e.what());
  }
  auto num = [&](const char* key, bool required) {
    if (!j.contains(key)) {
      if (required) throw ScanReadError(path + ": " + key + ": missing");
      return 0.0;
    }
    if (!j[key].is_number()) throw ScanReadError(path + ": " + key + ": must be a number");
    return j[key].get<double>();
  };
  if (!j.is_object())
    throw ScanReadError(path + ": expected an object {\"x\":..,\"y\":..,\"z\":..,\"yaw_deg\":..}");
  const double yaw = num("yaw_deg", false);
  if (std::abs(yaw) > 360) throw ScanReadError(path + ": yaw_deg must be within ±360 degrees");
  const ScanPose pose = ScanPose::from_xyz_yaw(num("x", true), num("y", true), num("z", true), yaw);
  if (const std::string problem = pose_problem(pose.scanner_to_survey.matrix()); !problem.empty())
    throw ScanReadError(path + ": the pose " + problem);
  return pose;
}

Cloud::Ptr to_survey_frame(const Scan& scan) {
  Cloud::Ptr out(new Cloud);
  pcl::transformPointCloud(*scan.points, *out, scan.pose.scanner_to_survey.matrix().cast<float>());
  return out;
}

}  // namespace semioctree
