// Mesh files (OBJ read here, PLY through PCL's reader) and OctoMap .bt files as triangle meshes.
#include <octomap/OcTree.h>
#include <pcl/PolygonMesh.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "grid_cell_key.h"
#include "semioctree/sim/mesh.h"

namespace semioctree::sim {

namespace fs = std::filesystem;

Eigen::Vector3d TriangleMesh::min_corner() const {
  Eigen::Vector3d m = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& v : vertices) m = m.cwiseMin(v);
  return m;
}

Eigen::Vector3d TriangleMesh::max_corner() const {
  Eigen::Vector3d m = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  for (const auto& v : vertices) m = m.cwiseMax(v);
  return m;
}

namespace {

// PCL reports parse problems on the console itself; we report them as exceptions.
class QuietPcl {
 public:
  QuietPcl() : saved_(pcl::console::getVerbosityLevel()) {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  }
  ~QuietPcl() { pcl::console::setVerbosityLevel(saved_); }

 private:
  pcl::console::VERBOSITY_LEVEL saved_;
};

void check_readable(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path + ": no such file");
  if (fs::is_directory(path, ec))
    throw std::runtime_error(path + ": is a directory, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open for reading");
  if (in.peek() == std::ifstream::traits_type::eof())
    throw std::runtime_error(path + ": file is empty");
}

// OBJ is a line format simple enough to read here, with messages that give the line;
// PCL's OBJ reader crashes on some malformed files.
TriangleMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  TriangleMesh mesh;
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& what) {
    throw std::runtime_error(path + ": line " + std::to_string(line_no) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      Eigen::Vector3d v;
      if (!(ls >> v.x() >> v.y() >> v.z()) || !v.allFinite())
        fail("expected \"v X Y Z\", got \"" + line + "\"");
      mesh.vertices.push_back(v);
    } else if (tag == "f") {
      std::vector<int> face;
      std::string corner;
      while (ls >> corner) {
        // "i", "i/t", "i//n" or "i/t/n"; negative indices count back from the last vertex.
        std::size_t used = 0;
        long index = 0;
        try {
          index = std::stol(corner, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || (used < corner.size() && corner[used] != '/'))
          fail("expected vertex indices in the face, got \"" + corner + "\"");
        const long n = static_cast<long>(mesh.vertices.size());
        const long resolved = index > 0 ? index - 1 : n + index;
        if (index == 0 || resolved < 0 || resolved >= n)
          fail("face refers to vertex " + std::to_string(index) + ", but " + std::to_string(n) +
               " vertices are defined so far");
        face.push_back(static_cast<int>(resolved));
      }
      if (face.size() < 3) fail("a face needs at least 3 vertices");
      for (std::size_t k = 1; k + 1 < face.size(); ++k)
        mesh.triangles.emplace_back(face[0], face[k], face[k + 1]);
    }
    // Other records (vt, vn, o, g, s, usemtl, mtllib, l, ...) do not change the geometry.
  }
  if (mesh.triangles.empty()) throw std::runtime_error(path + ": the mesh has no faces");
  return mesh;
}

}  // namespace

TriangleMesh read_mesh_file(const std::string& path) {
  check_readable(path);
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  pcl::PolygonMesh polygon_mesh;
  int status = -1;
  {
    QuietPcl quiet;
    if (ext == ".obj") return read_obj(path);
    if (ext == ".ply")
      status = pcl::io::loadPLYFile(path, polygon_mesh);
    else
      throw std::runtime_error(path + ": unknown mesh type \"" + ext + "\", expected .obj or .ply");
  }
  if (status < 0) throw std::runtime_error(path + ": not a readable " + ext.substr(1) + " mesh");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  {
    QuietPcl quiet;
    pcl::fromPCLPointCloud2(polygon_mesh.cloud, cloud);
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(cloud.size());
  for (const auto& p : cloud.points) mesh.vertices.emplace_back(p.x, p.y, p.z);
  for (std::size_t f = 0; f < polygon_mesh.polygons.size(); ++f) {
    const auto& ids = polygon_mesh.polygons[f].vertices;
    for (auto id : ids)
      if (id < 0 || static_cast<std::size_t>(id) >= mesh.vertices.size())
        throw std::runtime_error(path + ": face " + std::to_string(f) + " refers to vertex " +
                                 std::to_string(id) + ", but there are only " +
                                 std::to_string(mesh.vertices.size()) + " vertices");
    for (std::size_t k = 1; k + 1 < ids.size(); ++k)  // polygons as fans
      mesh.triangles.emplace_back(static_cast<int>(ids[0]), static_cast<int>(ids[k]),
                                  static_cast<int>(ids[k + 1]));
  }
  for (const auto& v : mesh.vertices)
    if (!v.allFinite()) throw std::runtime_error(path + ": a vertex has a non-finite coordinate");
  if (mesh.triangles.empty()) throw std::runtime_error(path + ": the mesh has no faces");
  return mesh;
}

TriangleMesh read_octomap_occupied(const std::string& path) {
  check_readable(path);
  octomap::OcTree tree(0.1);
  if (!tree.readBinary(path)) throw std::runtime_error(path + ": not a readable OctoMap .bt file");
  const double res = tree.getResolution();
  const unsigned max_depth = tree.getTreeDepth();

  // Occupied space as a set of finest-level cells, so every face lies on one lattice and
  // neighbouring faces share vertices exactly (a watertight surface).
  std::unordered_set<std::uint64_t> cells;
  std::vector<std::array<std::uint32_t, 3>> cell_list;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const std::uint32_t n = 1u << (max_depth - it.getDepth());
    const octomap::OcTreeKey k = it.getIndexKey();
    for (std::uint32_t dx = 0; dx < n; ++dx)
      for (std::uint32_t dy = 0; dy < n; ++dy)
        for (std::uint32_t dz = 0; dz < n; ++dz) {
          const std::array<std::uint32_t, 3> c{k[0] + dx + 1, k[1] + dy + 1, k[2] + dz + 1};
          if (cells.insert(detail::grid_cell_key(c[0], c[1], c[2])).second) cell_list.push_back(c);
        }
  }
  if (cell_list.empty()) throw std::runtime_error(path + ": the octree has no occupied voxels");

  constexpr double kKeyOrigin = 32768;  // OctoMap's key of coordinate 0 (depth 16)
  TriangleMesh mesh;
  std::unordered_map<std::uint64_t, int> corner_ids;
  // Cell c (shifted by +1 above so that c − 1 never underflows) spans
  // [(c − 1 − kKeyOrigin)·res, (c − kKeyOrigin)·res) on each axis.
  auto corner = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    const std::uint64_t key = detail::grid_cell_key(x, y, z);
    auto found = corner_ids.find(key);
    if (found != corner_ids.end()) return found->second;
    const int id = static_cast<int>(mesh.vertices.size());
    mesh.vertices.emplace_back((static_cast<double>(x) - 1 - kKeyOrigin) * res,
                               (static_cast<double>(y) - 1 - kKeyOrigin) * res,
                               (static_cast<double>(z) - 1 - kKeyOrigin) * res);
    corner_ids.emplace(key, id);
    return id;
  };
  for (const auto& c : cell_list) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        std::array<std::uint32_t, 3> nb = c;
        nb[axis] = side ? nb[axis] + 1 : nb[axis] - 1;
        if (cells.count(detail::grid_cell_key(nb[0], nb[1], nb[2]))) continue;
        // The face on plane `axis` = c[axis] + side, spanned by the two other axes.
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        std::array<int, 4> q;
        for (int k = 0; k < 4; ++k) {
          std::array<std::uint32_t, 3> p = c;
          p[axis] += side;
          p[a1] += (k == 1 || k == 2) ? 1 : 0;
          p[a2] += (k >= 2) ? 1 : 0;
          q[k] = corner(p[0], p[1], p[2]);
        }
        // (a1, a2, axis) is right-handed, so ring 0-1-2-3 faces +axis.
        if (side)
          mesh.triangles.emplace_back(q[0], q[1], q[2]),
              mesh.triangles.emplace_back(q[0], q[2], q[3]);
        else
          mesh.triangles.emplace_back(q[0], q[2], q[1]),
              mesh.triangles.emplace_back(q[0], q[3], q[2]);
      }
    }
  }
  return mesh;
}

}  // namespace semioctree::sim
