#include "semioctree/octomap_ext/export.h"

#include <cstdint>
#include <cstring>
#include <optional>
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

// The nodes of an export in OctoMap's file order (depth first, children 0 to 7), found by
// one walk of the map's own nodes, which are OctoMap's (the same depths and child
// indices). They are those OctantPlacer would create: a node where an exported octant or
// a mark lies at or below it; an exported octant holding a mark split into its eight
// children down to the mark's leaf (the children take its label); a mark elsewhere hung
// on a path of its own. `Policy` says which labels are exported and what a node stores:
//   static bool exported(Label);
//   Entry inner(const std::optional<Summary> children[8], unsigned mask);  // mask: present
//   Summary summary_of_inner(const Entry&), summary_of_leaf(Label);
//   bool writes_leaves: whether a leaf has an entry of its own, Entry leaf(Label) (.ot),
//   or not (.bt)
template <class Policy>
class ExportWalk {
 public:
  using Entry = typename Policy::Entry;
  using Summary = typename Policy::Summary;

  ExportWalk(const SemiOcTree& tree, const std::vector<LeafMark>& marks) : tree_(tree) {
    for (std::size_t i = 0; i < marks.size(); ++i)
      if (Policy::exported(marks[i].label)) marks_.push_back(marks[i]);
  }

  // Walks the map; then entries() are the written nodes in file order and nodes() counts
  // every node of the export.
  void run() {
    std::vector<std::uint32_t> all(marks_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = std::uint32_t(i);
    visit(tree_.getRoot(), 0, octomap::OcTreeKey(0, 0, 0), nullptr, all);
  }
  const std::vector<Entry>& entries() const { return entries_; }
  std::size_t nodes() const { return nodes_; }

 private:
  static constexpr unsigned kLeafDepth = SemiOcTree::kTreeDepth;

  // The node at `depth` and `key`: the map's `node` (may be null), or, inside an
  // exported octant split by a mark, its label `inside`; `marks` those within it.
  // Returns whether it exists in the export, and its summary.
  std::optional<Summary> visit(const SemiOcTreeNode* node, unsigned depth,
                               const octomap::OcTreeKey& key, const Label* inside,
                               const std::vector<std::uint32_t>& marks) {
    Label label = Label::kUnknown;
    const Label* octant = inside;
    if (!inside && node && !tree_.nodeHasChildren(node) && depth >= tree_.coarse_depth()) {
      label = node->label();  // an octant of the map
      if (Policy::exported(label)) octant = &label;
    }
    const bool map_inner = !inside && node && tree_.nodeHasChildren(node);
    if (!map_inner && marks.empty()) {  // a leaf of the export, or nothing
      if (!octant) return std::nullopt;
      ++nodes_;
      if (Policy::writes_leaves) entries_.push_back(Policy::leaf(*octant));
      return Policy::summary_of_leaf(*octant);
    }
    if (!map_inner && depth == kLeafDepth) {  // a mark's leaf: the last mark there wins
      ++nodes_;
      const Label l = marks_[marks.back()].label;
      if (Policy::writes_leaves) entries_.push_back(Policy::leaf(l));
      return Policy::summary_of_leaf(l);
    }
    // An inner node: its entry first, filled once its children are known.
    ++nodes_;
    const std::size_t at = entries_.size();
    entries_.emplace_back();
    std::optional<Summary> children[8];
    unsigned mask = 0;
    std::vector<std::uint32_t> in_child;
    const unsigned bit = SemiOcTree::kTreeDepth - 1 - depth;
    for (unsigned i = 0; i < 8; ++i) {
      in_child.clear();
      for (std::uint32_t m : marks)
        if (octomap::computeChildIdx(marks_[m].key, int(bit)) == i) in_child.push_back(m);
      const SemiOcTreeNode* child =
          map_inner && tree_.nodeChildExists(node, i) ? tree_.getNodeChild(node, i) : nullptr;
      children[i] = visit(child, depth + 1, detail::child_key(key, depth, i), octant, in_child);
      if (children[i]) mask |= 1u << i;
    }
    if (mask == 0) {  // the map's node holds nothing exported
      entries_.resize(at);
      --nodes_;
      return std::nullopt;
    }
    entries_[at] = Policy::inner(children, mask);
    return Policy::summary_of_inner(entries_[at]);
  }

  const SemiOcTree& tree_;
  std::vector<LeafMark> marks_;
  std::vector<Entry> entries_;
  std::size_t nodes_ = 0;
};

// ColorOcTree (.ot): every node written as its log-odds (all occupied: an inner node takes
// the largest of its children's), its colour (an inner node's the average of its
// children's that are set, as updateInnerOccupancy makes it), then its child mask.
struct ColorPolicy {
  struct Entry {
    std::uint8_t mask = 0;
    Rgb color;
  };
  using Summary = Rgb;
  static constexpr bool writes_leaves = true;
  static bool exported(Label l) { return l != Label::kUnknown; }
  static Entry leaf(Label l) { return {0, label_color(l)}; }
  static Summary summary_of_leaf(Label l) { return label_color(l); }
  static Summary summary_of_inner(const Entry& e) { return e.color; }
  static Entry inner(const std::optional<Summary> children[8], unsigned mask) {
    // ColorOcTreeNode::getAverageChildColor: white is "not set".
    int r = 0, g = 0, b = 0, n = 0;
    for (unsigned i = 0; i < 8; ++i) {
      if (!children[i]) continue;
      const Rgb& c = *children[i];
      if (c.r == 255 && c.g == 255 && c.b == 255) continue;
      r += c.r, g += c.g, b += c.b, ++n;
    }
    const Rgb avg = n > 0 ? Rgb{std::uint8_t(r / n), std::uint8_t(g / n), std::uint8_t(b / n)}
                          : Rgb{255, 255, 255};
    return {std::uint8_t(mask), avg};
  }
};

// OcTree (.bt): each inner node (and the root) written as two bytes of child codes, two
// bits a child: 0 absent, 1 free, 2 occupied, 3 inner (OccupancyOcTreeBase::writeBinaryNode).
struct OccupancyPolicy {
  using Entry = std::uint16_t;
  using Summary = std::uint8_t;  // the node's code in its parent's entry
  static constexpr bool writes_leaves = false;
  static bool exported(Label l) { return label_occupancy(l) != Occupancy::kUnknown; }
  static Entry leaf(Label) { return 0; }
  static Summary summary_of_leaf(Label l) {
    return label_occupancy(l) == Occupancy::kOccupied ? 2 : 1;
  }
  static Summary summary_of_inner(const Entry&) { return 3; }
  static Entry inner(const std::optional<Summary> children[8], unsigned) {
    Entry codes = 0;
    for (unsigned i = 0; i < 8; ++i)
      if (children[i]) codes = Entry(codes | (unsigned(*children[i]) << (2 * i)));
    return codes;
  }
};

}  // namespace

void write_color_octree_file(const SemiOcTree& tree, const std::vector<LeafMark>& marks,
                             const std::string& path) {
  ExportWalk<ColorPolicy> walk(tree, marks);
  walk.run();
  const float occupied = octomap::ColorOcTree(tree.leaf_size()).getClampingThresMaxLog();
  write_file_atomically(path, [&](std::ostream& s) {
    write_ot_header(s, "ColorOcTree", walk.nodes(), tree.leaf_size());
    std::vector<char> chunk;
    const auto flush = [&] {
      s.write(chunk.data(), std::streamsize(chunk.size()));
      chunk.clear();
    };
    for (const ColorPolicy::Entry& e : walk.entries()) {
      char node[8];  // ColorOcTreeNode::writeData, then the child mask
      std::memcpy(node, &occupied, 4);
      node[4] = char(e.color.r), node[5] = char(e.color.g), node[6] = char(e.color.b);
      node[7] = char(e.mask);
      chunk.insert(chunk.end(), node, node + 8);
      if (chunk.size() >= (1u << 16)) flush();
    }
    flush();
    if (!s) throw FileError(path + ": could not write the tree");
  });
}

void write_occupancy_binary_file(const SemiOcTree& tree, const std::vector<LeafMark>& marks,
                                 const std::string& path) {
  ExportWalk<OccupancyPolicy> walk(tree, marks);
  walk.run();
  write_file_atomically(path, [&](std::ostream& s) {
    write_bt_header(s, walk.nodes(), tree.leaf_size());
    // A root without children still writes its (empty) codes.
    const std::size_t root_only = walk.nodes() > 0 && walk.entries().empty() ? 2 : 0;
    std::vector<char> bytes(root_only, 0);
    bytes.reserve(2 * walk.entries().size());
    for (const std::uint16_t codes : walk.entries()) {
      bytes.push_back(char(codes & 0xff));  // children 0-3, then 4-7
      bytes.push_back(char(codes >> 8));
    }
    s.write(bytes.data(), std::streamsize(bytes.size()));
    if (!s) throw FileError(path + ": could not write the tree");
  });
}

std::unique_ptr<octomap::ColorOcTree> to_color_octree(const SemiOcTree& tree,
                                                      const std::vector<LeafMark>& marks) {
  auto out = std::make_unique<OctantPlacer<octomap::ColorOcTree>>(tree.leaf_size());
  const float occupied = out->getClampingThresMaxLog();
  place_octants_and_marks(tree, marks, [&](const octomap::OcTreeKey& key, unsigned depth, Label l) {
    if (l == Label::kUnknown) return;  // a mark labelled unknown: nothing to draw
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
