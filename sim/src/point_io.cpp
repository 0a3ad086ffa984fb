// Scan → PCD / PLY through PCL's writers, with fields x y z [intensity] row col.
#include "semioctree/sim/point_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "atomic_file.h"

namespace semioctree::sim {

namespace fs = std::filesystem;

namespace {

pcl::PCLPointCloud2 to_cloud(const Scan& scan) {
  const bool with_intensity = scan.intensity.size() == scan.points.size() && !scan.points.empty();
  pcl::PCLPointCloud2 cloud;
  auto add_field = [&](const char* name, std::uint8_t type) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = cloud.point_step;
    f.datatype = type;
    f.count = 1;
    cloud.fields.push_back(f);
    cloud.point_step += 4;
  };
  cloud.point_step = 0;
  add_field("x", pcl::PCLPointField::FLOAT32);
  add_field("y", pcl::PCLPointField::FLOAT32);
  add_field("z", pcl::PCLPointField::FLOAT32);
  if (with_intensity) add_field("intensity", pcl::PCLPointField::FLOAT32);
  add_field("row", pcl::PCLPointField::UINT32);
  add_field("col", pcl::PCLPointField::UINT32);
  cloud.width = static_cast<std::uint32_t>(scan.points.size());
  cloud.height = 1;
  cloud.is_dense = true;
  cloud.is_bigendian = false;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.data.resize(static_cast<std::size_t>(cloud.row_step));
  std::uint8_t* p = cloud.data.data();
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    std::memcpy(p, scan.points[i].data(), 12);
    p += 12;
    if (with_intensity) {
      std::memcpy(p, &scan.intensity[i], 4);
      p += 4;
    }
    std::memcpy(p, &scan.row[i], 4);
    std::memcpy(p + 4, &scan.col[i], 4);
    p += 8;
  }
  return cloud;
}

// Writes with a PCL writer `write(temporary path)` (its console quiet), then renames
// over `path`.
template <class Write>
void write_atomically(const std::string& path, Write write) {
  const bool ok = detail::replace_file_atomically(path, [&](const std::string& tmp) {
    const auto saved = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    const int status = write(tmp);
    pcl::console::setVerbosityLevel(saved);
    return status >= 0;
  });
  if (!ok) throw std::runtime_error(path + ": cannot write (is the directory there and writable?)");
}

// The pose (scanner frame → world) as the file's viewpoint (PCD VIEWPOINT, PLY
// obj_info), so that readers can place the scan.
struct Viewpoint {
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
};
Viewpoint viewpoint_of(const Scan& scan) {
  const Eigen::Isometry3d t = scan.sensor_to_world();
  return {Eigen::Vector4f(static_cast<float>(t.translation().x()),
                          static_cast<float>(t.translation().y()),
                          static_cast<float>(t.translation().z()), 0.0f),
          Eigen::Quaternionf(t.rotation().cast<float>())};
}

}  // namespace

void write_pcd(const std::string& path, const Scan& scan) {
  const pcl::PCLPointCloud2 cloud = to_cloud(scan);
  const Viewpoint vp = viewpoint_of(scan);
  write_atomically(path, [&](const std::string& tmp) {
    pcl::PCDWriter writer;
    return writer.writeBinary(tmp, cloud, vp.origin, vp.orientation);
  });
}

void write_ply(const std::string& path, const Scan& scan) {
  const pcl::PCLPointCloud2 cloud = to_cloud(scan);
  const Viewpoint vp = viewpoint_of(scan);
  write_atomically(path, [&](const std::string& tmp) {
    pcl::PLYWriter writer;
    return writer.writeBinary(tmp, cloud, vp.origin, vp.orientation, true);
  });
}

void write_scan(const std::string& path, const Scan& scan) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".pcd")
    write_pcd(path, scan);
  else if (ext == ".ply")
    write_ply(path, scan);
  else
    throw std::runtime_error(path + ": unknown point cloud type \"" + ext +
                             "\", expected .pcd or .ply");
}

}  // namespace semioctree::sim
