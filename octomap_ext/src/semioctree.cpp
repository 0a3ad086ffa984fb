#include "semioctree/octomap_ext/semioctree.h"

#include <cstring>
#include <istream>
#include <ostream>
#include <sstream>
#include <utility>
#include <vector>

#include "semioctree/octomap_ext/node_stream.h"

namespace semioctree {

// ----------------------------------------------------------------------------- node

std::istream& SemiOcTreeNode::readData(std::istream& s) {
  char buf[kSerializedBytes];
  s.read(buf, sizeof(buf));
  std::memcpy(&value, buf, 4);
  label_ = static_cast<std::uint8_t>(buf[4]);
  // buf[5] is reserved (see kSerializedBytes); the in-memory flags stay as they are.
  std::memcpy(&aux_, buf + 6, 2);
  return s;
}

std::ostream& SemiOcTreeNode::writeData(std::ostream& s) const {
  char buf[kSerializedBytes];
  std::memcpy(buf, &value, 4);
  buf[4] = static_cast<char>(label_);
  buf[5] = 0;  // reserved
  std::memcpy(buf + 6, &aux_, 2);
  return s.write(buf, sizeof(buf));
}

std::optional<Label> label_from_name(std::string_view name) {
  for (int i = 0; i < kLabelCount; ++i)
    if (kLabelNames[i] == name) return static_cast<Label>(i);
  return std::nullopt;
}

// ----------------------------------------------------------------------------- statistics

std::uint64_t OctantStatistics::total() const {
  std::uint64_t n = 0;
  for (const auto& row : count)
    for (auto v : row) n += v;
  return n;
}
std::uint64_t OctantStatistics::at_level(unsigned level) const {
  std::uint64_t n = 0;
  if (level < count.size())
    for (auto v : count[level]) n += v;
  return n;
}
std::uint64_t OctantStatistics::with_label(Label l) const {
  std::uint64_t n = 0;
  for (const auto& row : count) n += row[static_cast<int>(l)];
  return n;
}
double OctantStatistics::total_volume() const {
  double v = 0;
  for (double x : volume) v += x;
  return v;
}

// ----------------------------------------------------------------------------- tree

SemiOcTree::StaticMemberInitializer SemiOcTree::semioctree_member_init_;

SemiOcTree::StaticMemberInitializer::StaticMemberInitializer() {
  register_tree_types();
}

void register_tree_types() {
  // Once, whoever comes first: this file's static initializer or a caller.
  static const bool registered = [] {
    auto* prototype = new SemiOcTree(0.1);
    prototype->clearKeyRays();
    SemiOcTree::registerTreeType(prototype);
    return true;
  }();
  (void)registered;
}

}  // namespace semioctree

// What semioctree::octomap_ext's link interface tells the linker to resolve
// (--undefined): it lives in this object file, so the file and its static initializer
// (the registration) are always linked, even from a static library.
extern "C" void semioctree_register_tree_types() {
  semioctree::register_tree_types();
}

namespace semioctree {

unsigned SemiOcTree::leaf_level_for(double leaf_size, double coarse_size) {
  if (!(leaf_size > 0) || !std::isfinite(leaf_size))
    throw std::invalid_argument("leaf size must be a positive number of metres, got " +
                                std::to_string(leaf_size));
  if (!(coarse_size > 0) || !std::isfinite(coarse_size))
    throw std::invalid_argument("coarse size must be a positive number of metres, got " +
                                std::to_string(coarse_size));
  const double ratio = coarse_size / leaf_size;
  for (unsigned k = 0; k <= kMaxLeafLevel; ++k) {
    if (std::fabs(ratio - double(1u << k)) <= 1e-6 * double(1u << k)) return k;
  }
  std::ostringstream msg;
  msg << "coarse size " << coarse_size << " m is not leaf size " << leaf_size
      << " m times a power of two (2^0 .. 2^" << kMaxLeafLevel << "); ratio is " << ratio;
  throw std::invalid_argument(msg.str());
}

SemiOcTree::SemiOcTree(double leaf_size, double coarse_size)
    : OccupancyOcTreeBase<SemiOcTreeNode>(leaf_size),
      leaf_level_(leaf_level_for(leaf_size, coarse_size)) {
  semioctree_member_init_.ensureLinking();
}

SemiOcTree::SemiOcTree(double leaf_size)
    : OccupancyOcTreeBase<SemiOcTreeNode>(leaf_size), leaf_level_(0) {
  semioctree_member_init_.ensureLinking();
}

std::uint64_t SemiOcTree::pack(const octomap::OcTreeKey& c) {
  return pack_octant_key(c);
}

CoarseIndex SemiOcTree::coarse_index(const octomap::OcTreeKey& key) const {
  const int off = int(kKeyOrigin >> leaf_level_);
  return {int(key.k[0] >> leaf_level_) - off, int(key.k[1] >> leaf_level_) - off,
          int(key.k[2] >> leaf_level_) - off};
}

bool SemiOcTree::key_of(const Point3& p, octomap::OcTreeKey& key) const {
  return coordToKeyChecked(p.x, p.y, p.z, key);
}

bool SemiOcTree::coarse_index_of(const Point3& p, CoarseIndex& out) const {
  octomap::OcTreeKey key;
  if (!key_of(p, key)) return false;
  out = coarse_index(key);
  return true;
}

octomap::OcTreeKey SemiOcTree::coarse_key(const CoarseIndex& c) const {
  const int off = int(kKeyOrigin >> leaf_level_);
  const int lim = int(1u << (kTreeDepth - leaf_level_));
  const int v[3] = {c.x + off, c.y + off, c.z + off};
  octomap::OcTreeKey key;
  for (int i = 0; i < 3; ++i) {
    if (v[i] < 0 || v[i] >= lim)
      throw std::out_of_range("coarse index outside OctoMap's key range");
    key.k[i] = static_cast<octomap::key_type>(unsigned(v[i]) << leaf_level_);
  }
  return key;
}

Point3 SemiOcTree::coarse_min_corner(const CoarseIndex& c) const {
  const double L = coarse_size();
  return {c.x * L, c.y * L, c.z * L};
}

SemiOcTreeNode* SemiOcTree::find_coarse(const CoarseIndex& c) const {
  const int off = int(kKeyOrigin >> leaf_level_);
  const int lim = int(1u << (kTreeDepth - leaf_level_));
  const int v[3] = {c.x + off, c.y + off, c.z + off};
  for (int x : v)
    if (x < 0 || x >= lim) return nullptr;
  return coarse_.value_or(
      pack_key_parts(std::uint64_t(v[0]), std::uint64_t(v[1]), std::uint64_t(v[2])), nullptr);
}

SemiOcTreeNode* SemiOcTree::create_coarse(const CoarseIndex& c, Label label) {
  if (SemiOcTreeNode* found = find_coarse(c)) return found;
  const octomap::OcTreeKey key = coarse_key(c);
  if (!root) {
    root = new SemiOcTreeNode();
    ++tree_size;
  }
  SemiOcTreeNode* node = root;
  const unsigned cd = coarse_depth();
  for (unsigned depth = 0; depth < cd; ++depth) {
    const unsigned idx = octomap::computeChildIdx(key, int(kTreeDepth - 1 - depth));
    node = nodeChildExists(node, idx) ? getNodeChild(node, idx) : createNodeChild(node, idx);
  }
  node->set_label(label);
  node->setLogOdds(log_odds_for(label));
  node->flags_ |= SemiOcTreeNode::kCoarseRoot;
  coarse_.insert_or_assign(pack(octomap::OcTreeKey(key.k[0] >> leaf_level_, key.k[1] >> leaf_level_,
                                                   key.k[2] >> leaf_level_)),
                           node);
  size_changed = true;
  return node;
}

float SemiOcTree::log_odds_for(Label label) const {
  switch (label_occupancy(label)) {
    case Occupancy::kOccupied:
      return clamping_thres_max;
    case Occupancy::kFree:
      return clamping_thres_min;
    default:
      return 0.0f;  // unknown: at the threshold, so OctoMap readers treat it as not free
  }
}

std::optional<Octant> SemiOcTree::find_octant(const octomap::OcTreeKey& key) const {
  const SemiOcTreeNode* node = find_coarse(coarse_index(key));
  if (!node) return std::nullopt;
  unsigned level = 0;
  while (level < leaf_level_ && nodeHasChildren(node)) {
    node = getNodeChild(node, octomap::computeChildIdx(key, int(leaf_level_ - 1 - level)));
    ++level;
  }
  return make_octant(key, level, node);
}

std::optional<Octant> SemiOcTree::find_octant(const Point3& p) const {
  octomap::OcTreeKey key;
  if (!key_of(p, key)) return std::nullopt;
  return find_octant(key);
}

SemiOcTreeNode* SemiOcTree::touch_octant(const octomap::OcTreeKey& key, unsigned level) {
  if (level > leaf_level_) throw std::out_of_range("octant level below the leaf level");
  SemiOcTreeNode* node = create_coarse(coarse_index(key));
  for (unsigned l = 0; l < level; ++l) {
    if (!nodeHasChildren(node)) expandNode(node);
    node = getNodeChild(node, octomap::computeChildIdx(key, int(leaf_level_ - 1 - l)));
  }
  return node;
}

void SemiOcTree::split(const octomap::OcTreeKey& key, unsigned level) {
  if (level >= leaf_level_) throw std::logic_error("cannot split an octant at the leaf level");
  SemiOcTreeNode* node = touch_octant(key, level);
  if (!nodeHasChildren(node)) expandNode(node);
}

void SemiOcTree::delete_children(SemiOcTreeNode* node) {
  // OctoMap's deleteNodeChild only frees childless children; free whole subtrees.
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    SemiOcTreeNode* child = getNodeChild(node, i);
    std::size_t n = 0;
    calcNumNodesRecurs(child, n);
    ++n;  // calcNumNodesRecurs counts descendants only
    deleteNodeRecurs(child);
    tree_size -= n;
  }
  node->release_child_array();
  size_changed = true;
}

SemiOcTreeNode* SemiOcTree::set_label(const octomap::OcTreeKey& key, unsigned level, Label label) {
  SemiOcTreeNode* node = touch_octant(key, level);
  if (nodeHasChildren(node)) delete_children(node);
  node->set_label(label);
  node->setLogOdds(log_odds_for(label));
  return node;
}

bool SemiOcTree::mark_recurs(SemiOcTreeNode* node, std::uint32_t labels) {
  if (!nodeHasChildren(node)) return (labels >> unsigned(node->label())) & 1u;
  bool any = false;
  for (unsigned i = 0; i < 8; ++i)
    if (nodeChildExists(node, i)) any |= mark_recurs(getNodeChild(node, i), labels);
  node->set_flag(SemiOcTreeNode::kMarked, any);
  return any;
}

void SemiOcTree::mark_subtrees(std::uint32_t labels) {
  marked_labels_ = labels;
  for_each_coarse([&](const CoarseIndex&, SemiOcTreeNode* node) {
    if (nodeHasChildren(node))
      mark_recurs(node, labels);
    else
      node->set_flag(SemiOcTreeNode::kMarked, false);
  });
}

OctantStatistics SemiOcTree::statistics() const {
  OctantStatistics st;
  st.leaf_level = leaf_level_;
  st.leaf_size = resolution;
  st.count.assign(leaf_level_ + 1, {});
  st.coarse_voxels = coarse_.size();
  for_each_octant([&](const Octant& o) {
    const int l = static_cast<int>(o.label());
    ++st.count[o.level][l];
    st.volume[l] += o.size * o.size * o.size;
  });
  return st;
}

std::size_t SemiOcTree::memory_bytes() const {
  // Node storage plus the hash index (buckets and one entry per coarse voxel).
  return memoryUsage() + coarse_.memory_bytes();
}

namespace {

[[noreturn]] void refuse(const char* what) {
  throw std::logic_error(std::string("SemiOcTree: OctoMap's ") + what +
                         " is not supported: labels are the map and coarse voxels are indexed; "
                         "edit it with set_label (see semioctree.h)");
}

}  // namespace

SemiOcTreeNode* SemiOcTree::updateNode(const octomap::OcTreeKey&, float, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::updateNode(const octomap::point3d&, float, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::updateNode(double, double, double, float, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::updateNode(const octomap::OcTreeKey&, bool, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::updateNode(const octomap::point3d&, bool, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::updateNode(double, double, double, bool, bool) {
  refuse("updateNode");
}
SemiOcTreeNode* SemiOcTree::setNodeValue(const octomap::OcTreeKey&, float, bool) {
  refuse("setNodeValue");
}
SemiOcTreeNode* SemiOcTree::setNodeValue(const octomap::point3d&, float, bool) {
  refuse("setNodeValue");
}
SemiOcTreeNode* SemiOcTree::setNodeValue(double, double, double, float, bool) {
  refuse("setNodeValue");
}
void SemiOcTree::insertPointCloud(const octomap::Pointcloud&, const octomap::point3d&, double, bool,
                                  bool) {
  refuse("insertPointCloud");
}
void SemiOcTree::insertPointCloud(const octomap::Pointcloud&, const octomap::point3d&,
                                  const octomap::pose6d&, double, bool, bool) {
  refuse("insertPointCloud");
}
void SemiOcTree::insertPointCloud(const octomap::ScanNode&, double, bool, bool) {
  refuse("insertPointCloud");
}
void SemiOcTree::insertPointCloudRays(const octomap::Pointcloud&, const octomap::point3d&, double,
                                      bool) {
  refuse("insertPointCloudRays");
}
bool SemiOcTree::insertRay(const octomap::point3d&, const octomap::point3d&, double, bool) {
  refuse("insertRay");
}
std::istream& SemiOcTree::readBinaryData(std::istream&) {
  refuse("readBinary (a .bt file holds occupancy only; import it, see import.h)");
}
std::ostream& SemiOcTree::writeBinaryData(std::ostream&) const {
  refuse("writeBinary (a .bt file holds occupancy only; see export.h)");
}
void SemiOcTree::toMaxLikelihood() {
  refuse("toMaxLikelihood (writeBinary calls it; a .bt file holds occupancy only, see export.h)");
}

bool SemiOcTree::isNodeCollapsible(const SemiOcTreeNode* node) const {
  if (!nodeChildExists(node, 0)) return false;
  const SemiOcTreeNode* first = getNodeChild(node, 0);
  if (first->is_coarse_root()) return false;  // the coarse grid is never merged away
  if (nodeHasChildren(first)) return false;
  // Occupied octants exist only at the leaf level (paper 2.2.1).
  if (first->label() == Label::kOccupied) return false;
  for (unsigned i = 1; i < 8; ++i) {
    if (!nodeChildExists(node, i)) return false;
    const SemiOcTreeNode* child = getNodeChild(node, i);
    if (nodeHasChildren(child) || !(*child == *first)) return false;
  }
  return true;
}

void SemiOcTree::prune_subtree(SemiOcTreeNode* node) {
  if (!nodeHasChildren(node)) return;
  for (unsigned i = 0; i < 8; ++i)
    if (nodeChildExists(node, i)) prune_subtree(getNodeChild(node, i));
  pruneNode(node);  // merges only when isNodeCollapsible says so
}

void SemiOcTree::prune() {
  // Post-order within each coarse voxel, in one pass. (OctoMap's prune() goes
  // level by level from the bottom and stops at the first level where nothing
  // merged, which misses octants split at coarse levels.)
  for_each_coarse([&](const CoarseIndex&, SemiOcTreeNode* node) { prune_subtree(node); });
}

void SemiOcTree::clear() {
  OccupancyOcTreeBase<SemiOcTreeNode>::clear();
  coarse_.clear();
}

void SemiOcTree::compact() {
  if (!root) return;
  // Copy into nodes allocated in traversal order: all coarse voxels one after
  // another (nearly every traversal step touches one first), then each voxel's
  // octree by itself, the 8 children of a node one after another.
  SemiOcTree fresh(resolution);
  fresh.root = new SemiOcTreeNode();
  fresh.tree_size = 1;
  fresh.root->copyData(*root);
  using Pair = std::pair<const SemiOcTreeNode*, SemiOcTreeNode*>;
  // Copies the children of every node in `level`, level by level, down to
  // `stop_depth` levels below; returns the deepest level copied.
  auto copy_levels = [&](std::vector<Pair> level, unsigned levels) {
    std::vector<Pair> next;
    for (unsigned d = 0; d < levels && !level.empty(); ++d) {
      next.clear();
      for (const auto& [from, to] : level) {
        if (!nodeHasChildren(from)) continue;
        for (unsigned i = 0; i < 8; ++i) {
          if (!nodeChildExists(from, i)) continue;
          SemiOcTreeNode* child = fresh.createNodeChild(to, i);
          child->copyData(*getNodeChild(from, i));
          next.emplace_back(getNodeChild(from, i), child);
        }
      }
      level.swap(next);
    }
    return level;
  };
  // The grid down to the coarse voxels first, then each coarse voxel's own
  // octree in one block: a ray crossing a split voxel finds its nodes together.
  const std::vector<Pair> coarse = copy_levels({{root, fresh.root}}, coarse_depth());
  for (const Pair& c : coarse) copy_levels({c}, leaf_level_);
  std::swap(root, fresh.root);
  std::swap(tree_size, fresh.tree_size);
  size_changed = true;
  fresh.size_changed = true;
  rebuild_coarse_index();
  // `fresh` now owns the old nodes and frees them.
}

void SemiOcTree::mark_coarse_recurs(SemiOcTreeNode* node, unsigned depth, octomap::OcTreeKey key) {
  if (depth == coarse_depth()) {
    node->flags_ |= SemiOcTreeNode::kCoarseRoot;
    coarse_.insert_or_assign(
        pack(octomap::OcTreeKey(key.k[0] >> leaf_level_, key.k[1] >> leaf_level_,
                                key.k[2] >> leaf_level_)),
        node);
    return;
  }
  node->flags_ &= static_cast<std::uint8_t>(~SemiOcTreeNode::kCoarseRoot);
  for (unsigned i = 0; i < 8; ++i)
    if (nodeChildExists(node, i))
      mark_coarse_recurs(getNodeChild(node, i), depth + 1, detail::child_key(key, depth, i));
}

void SemiOcTree::rebuild_coarse_index() {
  coarse_.clear();
  if (root) mark_coarse_recurs(root, 0, octomap::OcTreeKey(0, 0, 0));
}

// ----------------------------------------------------------------------------- file format

namespace {

constexpr char kMagic[8] = {'S', 'E', 'M', 'I', 'O', 'C', 'T', '1'};
constexpr std::uint32_t kFormatVersion = 1;

struct PayloadHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t leaf_level;
  double resolution;
  std::uint64_t node_count;
  std::uint64_t payload_bytes;
  std::uint64_t payload_hash;
};
static_assert(sizeof(PayloadHeader) == 48, "payload header layout");

}  // namespace

std::ostream& SemiOcTree::writeData(std::ostream& s) const {
  std::ostringstream nodes;
  if (root) OccupancyOcTreeBase<SemiOcTreeNode>::writeData(nodes);
  const std::string payload = nodes.str();
  PayloadHeader h{};
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  h.version = kFormatVersion;
  h.leaf_level = leaf_level_;
  h.resolution = resolution;
  h.node_count = root ? calcNumNodes() : 0;
  h.payload_bytes = payload.size();
  h.payload_hash = fnv1a64(payload.data(), payload.size());
  s.write(reinterpret_cast<const char*>(&h), sizeof(h));
  return s.write(payload.data(), std::streamsize(payload.size()));
}

std::istream& SemiOcTree::readData(std::istream& s) {
  clear();
  PayloadHeader h{};
  if (!s.read(reinterpret_cast<char*>(&h), sizeof(h)))
    throw FileFormatError("SemiOcTree data is truncated (no payload header)");
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0)
    throw FileFormatError("SemiOcTree data does not start with the SEMIOCT1 marker");
  if (h.version != kFormatVersion)
    throw FileFormatError("SemiOcTree data version " + std::to_string(h.version) +
                          " is not supported (expected 1)");
  if (h.leaf_level > kMaxLeafLevel)
    throw FileFormatError("SemiOcTree leaf level " + std::to_string(h.leaf_level) +
                          " is out of range (0.." + std::to_string(kMaxLeafLevel) + ")");
  if (!(h.resolution > 0) || !std::isfinite(h.resolution))
    throw FileFormatError("SemiOcTree resolution is not a positive number");
  const std::uint64_t per_node = SemiOcTreeNode::kSerializedBytes + 1;
  if (h.payload_bytes != h.node_count * per_node)
    throw FileFormatError("SemiOcTree payload size " + std::to_string(h.payload_bytes) +
                          " does not match " + std::to_string(h.node_count) + " nodes");
  const std::string payload = read_exactly(s, h.payload_bytes);  // throws when short
  if (fnv1a64(payload.data(), payload.size()) != h.payload_hash)
    throw FileFormatError("SemiOcTree data is corrupted (checksum mismatch)");

  const unsigned cd = kTreeDepth - h.leaf_level;
  const auto check_node = [&](const char* data, unsigned depth, bool has_children) -> const char* {
    float v;
    std::memcpy(&v, data, 4);
    if (!std::isfinite(v)) return "non-finite log-odds";
    if (!is_valid_label(static_cast<std::uint8_t>(data[4]))) return "invalid label";
    if (depth < cd && !has_children) return "a node above the coarse level is a leaf";
    return nullptr;
  };
  const std::size_t counted =
      validate_node_stream(payload, SemiOcTreeNode::kSerializedBytes, check_node);
  if (counted != h.node_count) throw FileFormatError("SemiOcTree node count mismatch");

  setResolution(h.resolution);
  leaf_level_ = h.leaf_level;
  if (h.node_count > 0) {
    std::istringstream nodes(payload);
    OccupancyOcTreeBase<SemiOcTreeNode>::readData(nodes);
  }
  rebuild_coarse_index();
  return s;
}

}  // namespace semioctree
