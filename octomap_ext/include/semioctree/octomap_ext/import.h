// An OctoMap occupancy map as a SemiOcTree: the way in for OctoMap users who map with
// their own tools (an octomap::OcTree in memory, or a .bt/.ot file) and want the NBV
// without our point-cloud pipeline. The SemiOcTree keeps the map's resolution as its
// leaf and OctoMap's key space, so keys and coordinates carry over unchanged.
#pragma once

#include <octomap/OcTree.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct OccupancyImportReport {
  std::size_t map_leaves = 0;       // leaf nodes of the OctoMap map (at any depth)
  std::size_t occupied_leaves = 0;  // SemiOcTree leaves made occupied
  std::size_t empty_octants = 0;    // octants made empty (at their own size)
  std::size_t coarse_voxels = 0;    // coarse voxels created
};

// Every coarse voxel (edge `coarse_size`, the map's resolution times a power of two)
// within the bounding box of the map's nodes is created, labelled `unobserved` (space
// inside the map's extent that the map does not hold was not observed); then each leaf node
// of the map labels its own space: occupied (OctoMap's isNodeOccupied) → occupied
// leaves (a pruned occupied node is expanded: occupied octants are leaves), free →
// one empty octant of the node's size (a coarse voxel or larger: each coarse voxel
// it covers). Space the map does not hold keeps `unobserved`: kUnknown (the default)
// for study_occlusion to classify from known scanner positions (OcclusionScope
// kUnknown), or kOccluded to take all of it as hidden. Sibling octants left with one
// label are merged. Throws std::invalid_argument if coarse_size is not the map's
// resolution times a power of two (up to 2^kMaxLeafLevel).
//
// A few bytes of map can claim a huge extent (two nodes at opposite corners of
// OctoMap's key space) or a huge solid (a pruned occupied node): before creating
// anything, the octants the import would make (coarse voxels over the extent,
// occupied leaves, empty octants) are counted, and more than `max_octants` throws
// std::length_error saying how many. 0: as many as this machine's physical memory
// holds at sizeof(SemiOcTreeNode) bytes each (a lower bound of their cost).
std::unique_ptr<SemiOcTree> from_occupancy_octree(const octomap::OcTree& map, double coarse_size,
                                                  Label unobserved = Label::kUnknown,
                                                  OccupancyImportReport* report = nullptr,
                                                  std::uint64_t max_octants = 0);

// The coarse size for a map of leaf `resolution`: resolution · 2^k (k = 0 …
// SemiOcTree::kMaxLeafLevel) nearest `wanted` in ratio (|log2(size / wanted)| least); of
// two equally near, the larger (fewer coarse voxels).
double nearest_coarse_size(double resolution, double wanted);

// The floor of an occupancy map as a shift of its leaf layers (layer i: z ∈ [i·res,
// (i+1)·res)). The floor is the lowest dense layer of occupied leaves: the lowest with
// at least a quarter as many occupied leaves as the fullest layer (a floor or ceiling
// spans the mapped area; a wall's layer holds only its perimeter, specks and points
// below the floor are sparse). A surface lying on a layer boundary fills the layer
// above too (at least a quarter as much): then the floor is that boundary.
struct OccupancyFloor {
  int shift_layers = 0;    // add to every z key: the floor then lies in layer 0 or on z = 0
  double z = 0;            // the floor's height in the map's frame: −shift_layers · res
  std::size_t leaves = 0;  // occupied leaves in the floor's layer(s)
};
// Nullopt when the map holds no occupied leaf.
std::optional<OccupancyFloor> find_occupancy_floor(const octomap::OcTree& map);

// A copy of `map` moved up by `layers` leaf layers (z keys + layers): the same nodes
// and log-odds, no resampling. Throws std::invalid_argument if a node would leave the
// key range.
std::unique_ptr<octomap::OcTree> shifted_by_layers(const octomap::OcTree& map, int layers);

}  // namespace semioctree
