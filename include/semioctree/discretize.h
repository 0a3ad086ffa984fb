// Stage 3 (paper 2.2, 2.2.1): occupancy analysis into the SemiOcTree. Coarse
// voxels of side L cover the cloud's bounds between floor and ceiling, snapped
// to the world grid, all `empty` candidates at first; every voxel holding a
// point is split, children holding points are split again down to the leaf
// size, and the leaf holding a point is `occupied`. Children without points
// stay unsplit (candidates for the occlusion study). Occupied octants exist
// only at the leaf level. With L = r it is the homogeneous voxelization,
// through the same code.
#pragma once

#include <cstddef>
#include <memory>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/scan_io.h"

namespace semioctree {

struct DiscretizeParams {
  double leaf = 0.05;   // r
  double coarse = 0.8;  // L = r·2^k
  // The region covered is the cloud's bounds snapped outwards to multiples of
  // this size (0: the coarse size). Comparing a homogeneous grid with a
  // semioctree over the same region: give both the semioctree's L.
  double extent_snap = 0.0;
};

struct DiscretizeReport {
  std::size_t points_used = 0;     // between floor and ceiling
  std::size_t points_outside = 0;  // below the floor or above the ceiling
  std::size_t occupied_leaves = 0;
  CoarseIndex min_coarse, max_coarse;  // inclusive range of coarse voxels
};

// `cloud` is levelled with the floor at z = 0 (see preprocess). Throws
// std::invalid_argument for a bad leaf/coarse pair or an empty room.
std::unique_ptr<SemiOcTree> discretize(const Cloud& cloud, double ceiling_height,
                                       const DiscretizeParams& params,
                                       DiscretizeReport* report = nullptr);

// The two steps of discretize, also used to add later scans (stage 8).
// Creates the coarse voxels over the cloud's bounds (snapped to `extent_snap`,
// 0: the coarse size) that do not exist yet, labelled `label`; returns how many.
std::size_t extend_coarse_grid(SemiOcTree& tree, const Cloud& cloud, double ceiling_height,
                               double extent_snap, Label label, DiscretizeReport* report = nullptr);
// Labels the leaf of every point inside the coarse grid occupied, splitting
// the octants above it (their other children keep the label they had, the
// finer resolution wins); returns the number of distinct leaves.
std::size_t mark_occupied(SemiOcTree& tree, const Cloud& cloud, double ceiling_height);

}  // namespace semioctree
