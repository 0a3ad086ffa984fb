#include "semioctree/octomap_ext/import.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace semioctree {

namespace {

// Octants of sizeof(SemiOcTreeNode) bytes that this machine's physical memory holds.
std::uint64_t octants_in_physical_memory() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return std::numeric_limits<std::uint64_t>::max();
  return std::uint64_t(pages) * std::uint64_t(page_size) / sizeof(SemiOcTreeNode);
}

}  // namespace

std::unique_ptr<SemiOcTree> from_occupancy_octree(const octomap::OcTree& map, double coarse_size,
                                                  Label unobserved, OccupancyImportReport* report,
                                                  std::uint64_t max_octants) {
  auto tree = std::make_unique<SemiOcTree>(map.getResolution(), coarse_size);
  OccupancyImportReport rep;
  const unsigned k = tree->leaf_level();
  const unsigned coarse_depth = tree->coarse_depth();
  const unsigned max_depth = SemiOcTree::kTreeDepth;
  // OctoMap's iterator gives a node at depth d < 16 the key of its centre cell: its
  // cells are [key − n/2, key + n/2) per axis, n = 2^(16 − d).
  auto first_cell = [](const octomap::OcTreeKey& key, std::uint32_t n, int axis) {
    return std::uint32_t(key[axis]) - n / 2;
  };
  auto cell_key = [](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return octomap::OcTreeKey(octomap::key_type(x), octomap::key_type(y), octomap::key_type(z));
  };
  const std::uint32_t coarse_cells = 1u << k;
  // The coarse voxels first, over the bounding box of the map's nodes (space inside it
  // that the map does not hold is unobserved, not outside), so that a later label never
  // meets a missing voxel.
  struct Node {
    octomap::OcTreeKey key;
    unsigned depth;
    bool occupied;
  };
  std::vector<Node> nodes;
  std::uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};  // cells, inclusive
  // Octants the labelling below makes, besides the coarse voxels. The map's leaves do
  // not overlap and lie in 2^48 cells: no sum overflows.
  std::uint64_t labelled_octants = 0;
  for (auto it = map.begin_leafs(), end = map.end_leafs(); it != end; ++it) {
    nodes.push_back({it.getKey(), it.getDepth(), map.isNodeOccupied(*it)});
    const std::uint32_t n = 1u << (max_depth - it.getDepth());
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], first_cell(it.getKey(), n, a));
      hi[a] = std::max(hi[a], first_cell(it.getKey(), n, a) + n - 1);
    }
    const std::uint64_t per_axis = nodes.back().occupied           ? n   // leaves
                                   : it.getDepth() >= coarse_depth ? 1u  // one octant
                                                                   : n / coarse_cells;
    labelled_octants += per_axis * per_axis * per_axis;
  }
  if (!nodes.empty()) {
    const CoarseIndex c0 = tree->coarse_index(cell_key(lo[0], lo[1], lo[2]));
    const CoarseIndex c1 = tree->coarse_index(cell_key(hi[0], hi[1], hi[2]));
    const std::uint64_t coarse = std::uint64_t(c1.x - c0.x + 1) * std::uint64_t(c1.y - c0.y + 1) *
                                 std::uint64_t(c1.z - c0.z + 1);
    const std::uint64_t limit = max_octants ? max_octants : octants_in_physical_memory();
    if (coarse + labelled_octants > limit)
      throw std::length_error(
          "the map's " + std::to_string(nodes.size()) + " leaf nodes span " +
          std::to_string(c1.x - c0.x + 1) + " x " + std::to_string(c1.y - c0.y + 1) + " x " +
          std::to_string(c1.z - c0.z + 1) + " coarse voxels of " + std::to_string(coarse_size) +
          " m and would make " + std::to_string(coarse + labelled_octants) +
          " octants, more than the " + std::to_string(limit) +
          (max_octants ? " allowed" : " this machine's memory holds") +
          " (a corrupted map, or far-apart nodes?)");
    for (auto x = c0.x; x <= c1.x; ++x)
      for (auto y = c0.y; y <= c1.y; ++y)
        for (auto z = c0.z; z <= c1.z; ++z) {
          tree->create_coarse({x, y, z}, unobserved);
          ++rep.coarse_voxels;
        }
  }
  rep.map_leaves = nodes.size();

  for (const Node& node : nodes) {
    const std::uint32_t n = 1u << (max_depth - node.depth);
    const std::uint32_t x0 = first_cell(node.key, n, 0), y0 = first_cell(node.key, n, 1),
                        z0 = first_cell(node.key, n, 2);
    if (node.occupied) {  // occupied octants are leaves: every cell of the node
      for (std::uint32_t dx = 0; dx < n; ++dx)
        for (std::uint32_t dy = 0; dy < n; ++dy)
          for (std::uint32_t dz = 0; dz < n; ++dz) {
            tree->set_label(cell_key(x0 + dx, y0 + dy, z0 + dz), k, Label::kOccupied);
            ++rep.occupied_leaves;
          }
      continue;
    }
    if (node.depth >= coarse_depth) {  // within one coarse voxel: one octant
      tree->set_label(node.key, node.depth - coarse_depth, Label::kEmpty);
      ++rep.empty_octants;
      continue;
    }
    for (std::uint32_t dx = 0; dx < n; dx += coarse_cells)  // each coarse voxel it covers
      for (std::uint32_t dy = 0; dy < n; dy += coarse_cells)
        for (std::uint32_t dz = 0; dz < n; dz += coarse_cells) {
          tree->set_label(cell_key(x0 + dx, y0 + dy, z0 + dz), 0, Label::kEmpty);
          ++rep.empty_octants;
        }
  }
  tree->prune();
  if (report) *report = rep;
  return tree;
}

double nearest_coarse_size(double resolution, double wanted) {
  double best = resolution;
  for (unsigned k = 0; k <= SemiOcTree::kMaxLeafLevel; ++k) {
    const double size = resolution * double(1u << k);
    const double d = std::abs(std::log2(size / wanted)), db = std::abs(std::log2(best / wanted));
    if (d <= db + 1e-12) best = size;  // a tie goes to the larger size
  }
  return best;
}

std::optional<OccupancyFloor> find_occupancy_floor(const octomap::OcTree& map) {
  const unsigned max_depth = SemiOcTree::kTreeDepth;
  const int origin = int(map.coordToKey(0.0));  // the key of layer 0
  std::map<int, std::size_t> per_layer;         // layer → occupied leaves
  for (auto it = map.begin_leafs(), end = map.end_leafs(); it != end; ++it) {
    if (!map.isNodeOccupied(*it)) continue;
    const int n = 1 << (max_depth - it.getDepth());  // leaves a side
    const int first = int(it.getKey()[2]) - n / 2 - origin;
    for (int z = first; z < first + n; ++z) per_layer[z] += std::size_t(n) * std::size_t(n);
  }
  if (per_layer.empty()) return std::nullopt;
  std::size_t most = 0;
  for (const auto& [layer, count] : per_layer) most = std::max(most, count);
  for (const auto& [layer, count] : per_layer) {
    if (4 * count < most) continue;
    OccupancyFloor f;
    f.shift_layers = -layer;
    f.leaves = count;
    const auto above = per_layer.find(layer + 1);
    if (above != per_layer.end() && 4 * above->second >= count) {
      f.shift_layers = -(layer + 1);  // on the boundary: layers −1 and 0 after the shift
      f.leaves += above->second;
    }
    f.z = -f.shift_layers * map.getResolution();
    return f;
  }
  return std::nullopt;  // not reached: the fullest layer passes
}

std::unique_ptr<octomap::OcTree> shifted_by_layers(const octomap::OcTree& map, int layers) {
  auto out = std::make_unique<octomap::OcTree>(map.getResolution());
  out->setOccupancyThres(map.getOccupancyThres());
  out->setProbHit(map.getProbHit());
  out->setProbMiss(map.getProbMiss());
  out->setClampingThresMin(map.getClampingThresMin());
  out->setClampingThresMax(map.getClampingThresMax());
  const unsigned max_depth = SemiOcTree::kTreeDepth;
  for (auto it = map.begin_leafs(), end = map.end_leafs(); it != end; ++it) {
    const int n = 1 << (max_depth - it.getDepth());
    const octomap::OcTreeKey c = it.getKey();
    const float value = it->getLogOdds();
    for (int dz = 0; dz < n; ++dz) {
      const long z = long(c[2]) - n / 2 + dz + layers;
      if (z < 0 || z > long(std::numeric_limits<octomap::key_type>::max()))
        throw std::invalid_argument("shifting the map by " + std::to_string(layers) +
                                    " layers moves it out of OctoMap's key range");
      for (int dy = 0; dy < n; ++dy)
        for (int dx = 0; dx < n; ++dx)
          out->setNodeValue(
              octomap::OcTreeKey(octomap::key_type(c[0] - n / 2 + dx),
                                 octomap::key_type(c[1] - n / 2 + dy), octomap::key_type(z)),
              value, true);
    }
  }
  out->updateInnerOccupancy();
  out->prune();
  return out;
}

}  // namespace semioctree
