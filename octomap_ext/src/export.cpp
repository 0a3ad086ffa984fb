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
  Node* place(const octomap::OcTreeKey& key, unsigned depth) {
    if (!this->root) {
      this->root = new Node();
      this->tree_size = 1;
      this->size_changed = true;
    }
    Node* n = this->root;
    for (unsigned d = 0; d < depth; ++d) {
      const unsigned idx = octomap::computeChildIdx(key, int(SemiOcTree::kTreeDepth - 1 - d));
      n = this->nodeChildExists(n, idx) ? this->getNodeChild(n, idx)
                                        : this->createNodeChild(n, idx);
    }
    return n;
  }
};

unsigned depth_of(const SemiOcTree& tree, const Octant& o) {
  return tree.coarse_depth() + o.level;
}

}  // namespace

std::unique_ptr<octomap::ColorOcTree> to_color_octree(const SemiOcTree& tree) {
  auto out = std::make_unique<OctantPlacer<octomap::ColorOcTree>>(tree.leaf_size());
  const float occupied = out->getClampingThresMaxLog();
  tree.for_each_octant([&](const Octant& o) {
    if (o.label() == Label::kUnknown) return;
    auto* node = out->place(o.key, depth_of(tree, o));
    node->setLogOdds(occupied);
    const Rgb c = label_color(o.label());
    node->setColor(c.r, c.g, c.b);
  });
  // Inner nodes: occupancy = max of children, colour = average (not drawn).
  // ColorOcTree's updateInnerOccupancy reads the root without checking it: a tree
  // with no labelled octant (an empty .ot) has none.
  if (out->getRoot()) out->updateInnerOccupancy();
  return out;
}

std::unique_ptr<octomap::OcTree> to_occupancy_octree(const SemiOcTree& tree) {
  auto out = std::make_unique<OctantPlacer<octomap::OcTree>>(tree.leaf_size());
  const float occupied = out->getClampingThresMaxLog();
  const float free = out->getClampingThresMinLog();
  tree.for_each_octant([&](const Octant& o) {
    const Occupancy occ = label_occupancy(o.label());
    if (occ == Occupancy::kUnknown) return;
    out->place(o.key, depth_of(tree, o))->setLogOdds(occ == Occupancy::kOccupied ? occupied : free);
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
