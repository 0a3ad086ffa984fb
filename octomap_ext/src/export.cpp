#include "semioctree/octomap_ext/export.h"

#include <cstring>
#include <sstream>
#include <vector>

#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

namespace {

// Gives access to a tree's root so that nodes can be placed at any depth:
// OctoMap's public updateNode/setNodeValue always descend to depth 16.
template <class TREE>
class OctantPlacer : public TREE {
 public:
  using Node = typename TREE::NodeType;
  explicit OctantPlacer(double res) : TREE(res) {}
  // The node of the octant at `key` and `depth`, created if need be. A node placed before
  // at a coarser depth around it is split on the way (its eight children take its value):
  // between calls, every node without children was placed (the nodes created on the way
  // down each get a child).
  Node* place(const octomap::OcTreeKey& key, unsigned depth) {
    bool created = false;
    if (!this->root) {
      this->root = new Node();
      this->tree_size = 1;
      this->size_changed = true;
      created = true;
    }
    Node* n = this->root;
    for (unsigned d = 0; d < depth; ++d) {
      if (!created && !this->nodeHasChildren(n)) this->expandNode(n);
      const unsigned idx = octomap::computeChildIdx(key, int(SemiOcTree::kTreeDepth - 1 - d));
      created = !this->nodeChildExists(n, idx);
      n = created ? this->createNodeChild(n, idx) : this->getNodeChild(n, idx);
    }
    return n;
  }
};

// Calls place(key, depth, label) for every labelled octant of `tree` (unknown ones are
// left out), then for every mark, at the leaves' depth.
template <class Place>
void place_octants_and_marks(const SemiOcTree& tree, const std::vector<LeafMark>& marks,
                             const Place& place) {
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kUnknown) place(o.key, tree.coarse_depth() + o.level, o.label());
  });
  for (const LeafMark& m : marks) place(m.key, SemiOcTree::kTreeDepth, m.label);
}

}  // namespace

std::unique_ptr<octomap::ColorOcTree> to_color_octree(const SemiOcTree& tree,
                                                      const std::vector<LeafMark>& marks) {
  auto out = std::make_unique<OctantPlacer<octomap::ColorOcTree>>(tree.leaf_size());
  const float occupied = out->getClampingThresMaxLog();
  place_octants_and_marks(tree, marks, [&](const octomap::OcTreeKey& key, unsigned depth, Label l) {
    auto* node = out->place(key, depth);
    node->setLogOdds(occupied);
    const Rgb c = label_color(l);
    node->setColor(c.r, c.g, c.b);
  });
  // Inner nodes: occupancy = max of children, colour = average (not drawn).
  // ColorOcTree's updateInnerOccupancy reads the root without checking it: a tree
  // with no labelled octant (an empty .ot) has none.
  if (out->getRoot()) out->updateInnerOccupancy();
  return out;
}

std::unique_ptr<octomap::OcTree> to_occupancy_octree(const SemiOcTree& tree,
                                                     const std::vector<LeafMark>& marks) {
  auto out = std::make_unique<OctantPlacer<octomap::OcTree>>(tree.leaf_size());
  const float occupied = out->getClampingThresMaxLog();
  const float free = out->getClampingThresMinLog();
  place_octants_and_marks(tree, marks, [&](const octomap::OcTreeKey& key, unsigned depth, Label l) {
    const Occupancy occ = label_occupancy(l);
    if (occ == Occupancy::kUnknown) return;
    out->place(key, depth)->setLogOdds(occ == Occupancy::kOccupied ? occupied : free);
  });
  out->updateInnerOccupancy();
  return out;
}

std::size_t write_octant_ply(const SemiOcTree& tree, const std::string& path,
                             const PlyOptions& options) {
  std::vector<char> body;
  std::size_t n = 0;
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() == Label::kUnknown && !options.include_unknown) return;
    const float xyz[3] = {float(o.center.x), float(o.center.y), float(o.center.z)};
    const Rgb c = label_color(o.label());
    const unsigned char bytes[5] = {c.r, c.g, c.b, static_cast<unsigned char>(o.label()),
                                    static_cast<unsigned char>(o.level)};
    const float size = float(o.size);
    const std::size_t at = body.size();
    body.resize(at + sizeof(xyz) + sizeof(bytes) + sizeof(size));
    std::memcpy(body.data() + at, xyz, sizeof(xyz));
    std::memcpy(body.data() + at + sizeof(xyz), bytes, sizeof(bytes));
    std::memcpy(body.data() + at + sizeof(xyz) + sizeof(bytes), &size, sizeof(size));
    ++n;
  });
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\n"
         << "comment semioctree octant centres; label: ";
  for (int i = 0; i < kLabelCount; ++i)
    header << i << "=" << kLabelNames[i] << (i + 1 < kLabelCount ? " " : "");
  header << "\ncomment leaf " << tree.leaf_size() << " coarse " << tree.coarse_size()
         << " (level 0 = coarse voxel)\n"
         << "element vertex " << n << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
         << "property uchar label\nproperty uchar level\nproperty float size\n"
         << "end_header\n";
  write_file_atomically(path, [&](std::ostream& s) {
    const std::string h = header.str();
    s.write(h.data(), std::streamsize(h.size()));
    s.write(body.data(), std::streamsize(body.size()));
  });
  return n;
}

}  // namespace semioctree
