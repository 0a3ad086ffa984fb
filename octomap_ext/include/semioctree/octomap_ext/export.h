// Exports of a SemiOcTree for the OctoMap / point-cloud world:
//  - ColorOcTree: every labelled octant as an occupied node in its class colour
//    (opens in stock octovis; unknown space is left out);
//  - OcTree occupancy: occupied → occupied; empty/out/door/window/scan/nbv →
//    free; occluded/unknown → unknown (absent), for .bt files;
//  - PLY of octant centres (x y z, red green blue, label, level, size).
// Octants keep their size: a coarse octant becomes one node at its depth.
#pragma once

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <memory>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

// One leaf drawn over the map in an export with a label of its own (where a scanner
// stood, the next view): the export shows it as if the map held it there, the octant
// around it split so that the rest keeps its label. The map itself is not touched.
struct LeafMark {
  octomap::OcTreeKey key;  // of a leaf
  Label label = Label::kUnknown;
};

// Later marks win where they meet; a mark labelled unknown is not drawn (as unknown
// octants are not exported).
std::unique_ptr<octomap::ColorOcTree> to_color_octree(const SemiOcTree& tree,
                                                      const std::vector<LeafMark>& marks = {});
std::unique_ptr<octomap::OcTree> to_occupancy_octree(const SemiOcTree& tree,
                                                     const std::vector<LeafMark>& marks = {});

// The files of those two trees, written from the map without building them: the same
// bytes as write_tree_file(*to_color_octree(tree, marks)) and
// write_binary_file(*to_occupancy_octree(tree, marks)), in one walk of the map's nodes
// and a few bytes a node. Atomic (write_file_atomically); FileError on failure.
void write_color_octree_file(const SemiOcTree& tree, const std::vector<LeafMark>& marks,
                             const std::string& path);
void write_occupancy_binary_file(const SemiOcTree& tree, const std::vector<LeafMark>& marks,
                                 const std::string& path);

struct PlyOptions {
  bool include_unknown = false;  // unknown octants are skipped by default
};
// Binary little-endian PLY; written atomically. Returns the vertex count.
std::size_t write_octant_ply(const SemiOcTree& tree, const std::string& path,
                             const PlyOptions& options = {});

}  // namespace semioctree
