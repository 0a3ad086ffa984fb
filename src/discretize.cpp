#include "semioctree/discretize.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree {

namespace {

// 16-bit keys interleaved (x in bit 0): sorted, they follow OctoMap's
// depth-first order.
std::uint64_t spread(std::uint64_t v) {
  v &= 0xffff;
  v = (v | (v << 16)) & 0x0000ff0000ffull;
  v = (v | (v << 8)) & 0x00f00f00f00full;
  v = (v | (v << 4)) & 0x0c30c30c30c3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}
std::uint64_t compact(std::uint64_t v) {
  v &= 0x249249249249ull;
  v = (v | (v >> 2)) & 0x0c30c30c30c3ull;
  v = (v | (v >> 4)) & 0x00f00f00f00full;
  v = (v | (v >> 8)) & 0x0000ff0000ffull;
  v = (v | (v >> 16)) & 0xffff;
  return v;
}
std::uint64_t morton(const octomap::OcTreeKey& k) {
  return spread(k.k[0]) | (spread(k.k[1]) << 1) | (spread(k.k[2]) << 2);
}
octomap::OcTreeKey unmorton(std::uint64_t m) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(compact(m)),
                            static_cast<octomap::key_type>(compact(m >> 1)),
                            static_cast<octomap::key_type>(compact(m >> 2)));
}

}  // namespace

std::size_t extend_coarse_grid(SemiOcTree& tree, const Cloud& cloud, double ceiling_height,
                               double extent_snap, Label label, DiscretizeReport* report) {
  DiscretizeReport rep;
  if (!(ceiling_height > 0) || !std::isfinite(ceiling_height))
    throw std::invalid_argument("ceiling height must be above the floor (z = 0), got " +
                                std::to_string(ceiling_height));
  // Bounds of the points between floor and ceiling.
  double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi[2] = {-lo[0], -lo[1]};
  for (const auto& p : cloud) {
    if (p.z < 0 || p.z >= ceiling_height) {
      ++rep.points_outside;
      continue;
    }
    lo[0] = std::min(lo[0], double(p.x));
    lo[1] = std::min(lo[1], double(p.y));
    hi[0] = std::max(hi[0], double(p.x));
    hi[1] = std::max(hi[1], double(p.y));
    ++rep.points_used;
  }
  if (rep.points_used == 0)
    throw std::invalid_argument("no point lies between the floor and the ceiling");
  CoarseIndex cmin, cmax;
  const double below_ceiling = std::nextafter(ceiling_height, 0.0);
  // Snap the bounds outwards to the extent grid, then to coarse voxels.
  const double snap = extent_snap > 0 ? extent_snap : tree.coarse_size();
  // (Half a leaf inside the snapped faces, so rounding cannot reach past them.)
  const double inset = 0.5 * tree.leaf_size();
  if (extent_snap > 0) {
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::floor(lo[a] / snap) * snap + inset;
      hi[a] = (std::floor(hi[a] / snap) + 1) * snap - inset;
    }
  }
  const double top =
      extent_snap > 0 ? std::ceil(below_ceiling / snap) * snap - inset : below_ceiling;
  if (!tree.coarse_index_of({lo[0], lo[1], extent_snap > 0 ? inset : 0.0}, cmin) ||
      !tree.coarse_index_of({hi[0], hi[1], top}, cmax))
    throw std::invalid_argument("the cloud lies outside OctoMap's key range at this leaf size");
  std::size_t created = 0;
  for (int i = cmin.x; i <= cmax.x; ++i)
    for (int j = cmin.y; j <= cmax.y; ++j)
      for (int l = cmin.z; l <= cmax.z; ++l) {
        if (tree.find_coarse({i, j, l})) continue;
        tree.create_coarse({i, j, l}, label);
        ++created;
      }
  rep.min_coarse = cmin;
  rep.max_coarse = cmax;
  if (report) *report = rep;
  return created;
}

std::size_t mark_occupied(SemiOcTree& tree, const Cloud& cloud, double ceiling_height) {
  // The leaf of every point is occupied; its ancestors are split on the way.
  // Points sharing a leaf are skipped through a hash set of leaf keys (a tree
  // descent per point would cost more than the labelling itself), and the
  // leaves are labelled in Morton (depth-first) order, so that successive
  // descents share their path and find it in cache.
  const unsigned leaf = tree.leaf_level();
  PackedKeyMap<std::uint32_t> seen(cloud.size());
  std::vector<std::uint64_t> order;
  order.reserve(cloud.size());
  for (const auto& p : cloud) {
    if (p.z < 0 || p.z >= ceiling_height) continue;
    octomap::OcTreeKey key;
    if (!tree.key_of({p.x, p.y, p.z}, key)) continue;
    if (!tree.find_coarse(tree.coarse_index(key))) continue;  // outside the grid
    const std::uint64_t m = morton(key);
    if (seen.insert(m)) order.push_back(m);
  }
  std::sort(order.begin(), order.end());
  for (std::uint64_t m : order) tree.set_label(unmorton(m), leaf, Label::kOccupied);
  return order.size();
}

std::unique_ptr<SemiOcTree> discretize(const Cloud& cloud, double ceiling_height,
                                       const DiscretizeParams& params, DiscretizeReport* report) {
  auto tree = std::make_unique<SemiOcTree>(params.leaf, params.coarse);  // validates L = r·2^k
  DiscretizeReport rep;
  // The coarse grid over the room: every voxel an unsplit `empty` candidate.
  extend_coarse_grid(*tree, cloud, ceiling_height, params.extent_snap, Label::kEmpty, &rep);
  rep.occupied_leaves = mark_occupied(*tree, cloud, ceiling_height);
  if (report) *report = rep;
  return tree;
}

}  // namespace semioctree
