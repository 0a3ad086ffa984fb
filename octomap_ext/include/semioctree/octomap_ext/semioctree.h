// SemiOcTree: a world-aligned grid of coarse voxels of side L = r·2^k, each the
// root of an octree refined down to the leaf size r only where needed.
//
// It is one OctoMap tree (OccupancyOcTreeBase<SemiOcTreeNode>) whose nodes at
// depth 16−k are the coarse voxels. Those nodes are never pruned away and are
// indexed by a hash map, so a coarse voxel is reached in O(1) instead of a
// 16-level descent. The whole structure reads and writes as one `.ot` file of
// type "SemiOcTree" through OctoMap's AbstractOcTree factory.
#pragma once

#include <octomap/OccupancyOcTreeBase.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/labels.h"
#include "semioctree/octomap_ext/packed_key_map.h"
#include "semioctree/octomap_ext/semioctree_node.h"

namespace semioctree {

// OctoMap's key of coordinate 0 on every axis (its tree_max_val, 2^15 in a tree
// of depth 16): the leaf cell [i r, (i+1) r) has key i + kKeyOrigin.
constexpr std::int64_t kKeyOrigin = 32768;

// The leaf cell index i of a key part (the cell [i r, (i+1) r)).
inline std::int64_t leaf_cell(octomap::key_type key_part) {
  return std::int64_t(key_part) - kKeyOrigin;
}

// Three 16-bit key parts and a level (0-255) as one 64-bit value: level in bits 48-55,
// x in 32-47, y in 16-31, z in 0-15. Distinct octants give distinct values.
inline std::uint64_t pack_key_parts(std::uint64_t x, std::uint64_t y, std::uint64_t z,
                                    unsigned level = 0) {
  return (std::uint64_t(level) << 48) | (x << 32) | (y << 16) | z;
}
inline std::uint64_t pack_octant_key(const octomap::OcTreeKey& key, unsigned level = 0) {
  return pack_key_parts(key.k[0], key.k[1], key.k[2], level);
}
// The key and the level pack_octant_key packed.
inline octomap::OcTreeKey unpack_octant_key(std::uint64_t packed) {
  return octomap::OcTreeKey(octomap::key_type(packed >> 32), octomap::key_type(packed >> 16),
                            octomap::key_type(packed));
}
inline unsigned unpack_octant_level(std::uint64_t packed) {
  return unsigned(packed >> 48) & 0xffu;
}

// A point in world coordinates (metres), in double precision: OctoMap's point3d
// is float, which puts points on cell boundaries into the wrong cell.
struct Point3 {
  double x = 0, y = 0, z = 0;
  Point3() = default;
  Point3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  Point3(const octomap::point3d& p) : x(p.x()), y(p.y()), z(p.z()) {}  // NOLINT
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

// Integer index of a coarse voxel: voxel (i, j, l) is the cube
// [iL, (i+1)L) × [jL, (j+1)L) × [lL, (l+1)L).
struct CoarseIndex {
  int x = 0, y = 0, z = 0;
  bool operator==(const CoarseIndex& o) const { return x == o.x && y == o.y && z == o.z; }
};

// One leaf of the octant structure (an octant that is not split further).
struct Octant {
  octomap::OcTreeKey key;  // key of the octant's minimum corner cell
  unsigned level = 0;      // 0 = coarse voxel, leaf_level() = leaf size
  double size = 0;         // side length in metres
  Point3 center;
  const SemiOcTreeNode* node = nullptr;  // null only for space outside any coarse voxel
  Label label() const { return node ? node->label() : Label::kUnknown; }
};

// Octants per level and label, and volume per label.
struct OctantStatistics {
  unsigned leaf_level = 0;
  double leaf_size = 0;
  std::vector<std::array<std::uint64_t, kLabelCount>> count;  // [level][label]
  std::array<double, kLabelCount> volume{};                   // m³ per label
  std::uint64_t coarse_voxels = 0;

  std::uint64_t total() const;
  std::uint64_t at_level(unsigned level) const;
  std::uint64_t with_label(Label l) const;
  double total_volume() const;
};

// Why a segment traversal ended.
enum class TraversalEnd {
  kReachedEnd,  // the octant containing the end point was visited
  kStopped,     // the visitor asked to stop
  kOutOfRange,  // an end point lies outside OctoMap's key range (nothing visited)
};

// An octant crossed by a segment, handed to the traversal visitor.
struct RayStep {
  octomap::OcTreeKey key;                // minimum-corner key of the octant
  unsigned level = 0;                    // 0 = coarse voxel ... leaf_level() = leaf
  const SemiOcTreeNode* node = nullptr;  // null: no coarse voxel there (unknown space)
  double t_enter = 0;                    // segment parameter in [0, 1] where the octant is entered
  // A split octant crossed in one step (traverse_marked: nothing marked below);
  // its node's label says nothing about its children then.
  bool summary = false;
  Label label() const { return node ? node->label() : Label::kUnknown; }
};

void register_tree_types();  // below, with its documentation

class SemiOcTree : public octomap::OccupancyOcTreeBase<SemiOcTreeNode> {
 public:
  static constexpr unsigned kTreeDepth = 16;
  static constexpr unsigned kMaxLeafLevel = 12;
  static_assert(kKeyOrigin == std::int64_t(1) << (kTreeDepth - 1), "OctoMap's key of 0");

  // Leaf size r and coarse size L; L must be r·2^k for an integer 0 ≤ k ≤ 12,
  // else std::invalid_argument with a message saying so.
  SemiOcTree(double leaf_size, double coarse_size);
  // A tree with k = 0 (coarse voxel = leaf). Needed by OctoMap's factory.
  explicit SemiOcTree(double leaf_size);
  ~SemiOcTree() override = default;
  // OctoMap's copy would share the coarse index's node pointers with the
  // source (and drop the labels): not copyable.
  SemiOcTree(const SemiOcTree&) = delete;
  SemiOcTree& operator=(const SemiOcTree&) = delete;

  // k such that coarse = leaf·2^k; throws std::invalid_argument otherwise.
  static unsigned leaf_level_for(double leaf_size, double coarse_size);

  SemiOcTree* create() const override { return new SemiOcTree(resolution); }
  std::string getTreeType() const override { return "SemiOcTree"; }

  double leaf_size() const { return resolution; }
  double coarse_size() const { return resolution * double(1u << leaf_level_); }
  // Level of the leaf octants, k (coarse = leaf·2^k): levels run from 0 (coarse
  // voxel) to leaf_level() (leaf).
  unsigned leaf_level() const { return leaf_level_; }
  unsigned coarse_depth() const { return kTreeDepth - leaf_level_; }
  // Edge of an octant of `level` (0 = coarse voxel ... leaf_level() = leaf);
  // std::out_of_range for a level finer than the leaf.
  double octant_size(unsigned level) const {
    if (level > leaf_level_) throw std::out_of_range("octant level finer than the leaf");
    return resolution * double(1u << (leaf_level_ - level));
  }

  // --- coarse grid ------------------------------------------------------------
  CoarseIndex coarse_index(const octomap::OcTreeKey& key) const;
  // False when the point is outside OctoMap's key range.
  bool coarse_index_of(const Point3& p, CoarseIndex& out) const;
  octomap::OcTreeKey coarse_key(const CoarseIndex& c) const;  // min-corner key
  Point3 coarse_min_corner(const CoarseIndex& c) const;
  SemiOcTreeNode* find_coarse(const CoarseIndex& c) const;
  // Finds or creates the coarse voxel; a new one gets `label` (default unknown).
  SemiOcTreeNode* create_coarse(const CoarseIndex& c, Label label = Label::kUnknown);
  std::size_t coarse_count() const { return coarse_.size(); }
  // Calls f(CoarseIndex, SemiOcTreeNode*) for every coarse voxel, in key order.
  template <class F>
  void for_each_coarse(F&& f) const;

  // --- octants ----------------------------------------------------------------
  bool key_of(const Point3& p, octomap::OcTreeKey& key) const;
  // The leaf octant containing the leaf cell `key`; nullopt when no coarse voxel.
  std::optional<Octant> find_octant(const octomap::OcTreeKey& key) const;
  std::optional<Octant> find_octant(const Point3& p) const;
  // The node of the octant at `level` containing `key`, creating the coarse voxel
  // and splitting octants on the way as needed.
  SemiOcTreeNode* touch_octant(const octomap::OcTreeKey& key, unsigned level);
  // Splits the leaf octant at `level` containing `key` into its 8 children, which
  // inherit its label. Throws std::logic_error at the leaf level.
  void split(const octomap::OcTreeKey& key, unsigned level);
  // Makes the octant at `level` containing `key` a leaf with this label (any
  // children are removed). Creates the coarse voxel and splits parents as needed.
  SemiOcTreeNode* set_label(const octomap::OcTreeKey& key, unsigned level, Label label);
  // Occupancy log-odds stored with each label (OctoMap readers see these).
  float log_odds_for(Label label) const;

  inline Octant make_octant(const octomap::OcTreeKey& key, unsigned level,
                            const SemiOcTreeNode* node) const;
  // Calls f(const Octant&) for every leaf octant, in OctoMap's depth-first order.
  template <class F>
  void for_each_octant(F&& f) const;
  OctantStatistics statistics() const;
  // Memory of nodes plus the coarse index, in bytes.
  std::size_t memory_bytes() const;

  // Merges 8 sibling octants into their parent only when they carry the same
  // label (and value); coarse voxels are never merged away, and occupied
  // octants never leave the leaf level.
  void prune() override;
  bool isNodeCollapsible(const SemiOcTreeNode* node) const override;
  void clear() override;
  // Re-allocates every node, in traversal order: the coarse voxels one after
  // another, then each coarse voxel's octree by itself. Octants, labels and the
  // coarse index are unchanged; node pointers taken before are invalid.
  void compact();

  // --- ray traversal ------------------------------------------------------------
  // Visits, in order along the segment a→b, every octant the segment passes
  // through, each once and at its own size: an unsplit coarse voxel is one step.
  // Cells are half-open, [i r, (i+1) r), so each point of the segment lies in
  // exactly one cell; the first octant holds a, the last holds b. The visitor is
  // `bool(const RayStep&)`; returning false stops the traversal.
  template <class Visitor>
  TraversalEnd traverse(const Point3& a, const Point3& b, Visitor&& visit) const;
  // The same walk, but a split octant whose subtree holds none of the labels
  // last given to mark_subtrees is one step (RayStep::summary): a query that
  // only cares about those labels (e.g. "is anything occupied on the way?")
  // skips the refinement of empty and occluded space.
  template <class Visitor>
  TraversalEnd traverse_marked(const Point3& a, const Point3& b, Visitor&& visit) const;
  // Sets SemiOcTreeNode::kMarked on every split octant (coarse voxels included)
  // whose subtree holds a leaf with a label in `labels` (bit 1 << label), and
  // clears it elsewhere. Later edits that add or remove such leaves make the
  // marks stale until the next call; splitting an unmarked leaf keeps them valid.
  void mark_subtrees(std::uint32_t labels);
  // Calls f(const Octant&) for every leaf octant carrying a label last given to
  // mark_subtrees whose interior meets the interior of the convex hull of `apex` and the
  // octant (`key`, `level`) (a wedge from a point to a box), in no particular order;
  // returning false from f stops the search. Returns false if f stopped it. Octants that
  // only touch the hull (a floor under the box) are not visited. Marks must be fresh.
  template <class F>
  bool for_each_marked_in_hull(const Point3& apex, const octomap::OcTreeKey& key, unsigned level,
                               F&& f) const;

  // --- OctoMap's occupancy updates: refused -----------------------------------
  // Here the labels are the map and the coarse voxels are indexed. OctoMap's
  // log-odds updates would change values under unchanged labels, or create
  // coarse voxels the index never hears of, so a map would read back
  // differently from what the updates said. They throw std::logic_error, also
  // through a base-class reference; edit the map with set_label / split.
  // The .bt format holds occupancy only: toMaxLikelihood (which writeBinary
  // calls) would turn unknown and occluded octants' values occupied, and
  // readBinaryData has no labels to read; both throw. Through a base-class
  // reference OctoMap's readBinary clears the tree and takes the file's
  // resolution before readBinaryData throws (an empty .bt even reads without
  // error). To make a SemiOcTree from an OctoMap map see import.h, to write
  // a .bt export.h.
  SemiOcTreeNode* updateNode(const octomap::OcTreeKey& key, float log_odds_update,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* updateNode(const octomap::point3d& value, float log_odds_update,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* updateNode(double x, double y, double z, float log_odds_update,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* updateNode(const octomap::OcTreeKey& key, bool occupied,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* updateNode(const octomap::point3d& value, bool occupied,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* updateNode(double x, double y, double z, bool occupied,
                             bool lazy_eval = false) override;
  SemiOcTreeNode* setNodeValue(const octomap::OcTreeKey& key, float log_odds_value,
                               bool lazy_eval = false) override;
  SemiOcTreeNode* setNodeValue(const octomap::point3d& value, float log_odds_value,
                               bool lazy_eval = false) override;
  SemiOcTreeNode* setNodeValue(double x, double y, double z, float log_odds_value,
                               bool lazy_eval = false) override;
  void insertPointCloud(const octomap::Pointcloud& scan, const octomap::point3d& sensor_origin,
                        double maxrange = -1., bool lazy_eval = false,
                        bool discretize = false) override;
  void insertPointCloud(const octomap::Pointcloud& scan, const octomap::point3d& sensor_origin,
                        const octomap::pose6d& frame_origin, double maxrange = -1.,
                        bool lazy_eval = false, bool discretize = false) override;
  void insertPointCloud(const octomap::ScanNode& scan, double maxrange = -1.,
                        bool lazy_eval = false, bool discretize = false) override;
  void insertPointCloudRays(const octomap::Pointcloud& scan, const octomap::point3d& sensor_origin,
                            double maxrange = -1., bool lazy_eval = false) override;
  bool insertRay(const octomap::point3d& origin, const octomap::point3d& end,
                 double maxrange = -1.0, bool lazy_eval = false) override;
  std::istream& readBinaryData(std::istream& s) override;
  std::ostream& writeBinaryData(std::ostream& s) const override;
  void toMaxLikelihood() override;
  // Not virtual in OctoMap, so hidden here, on the SemiOcTree type only (a
  // base-class reference still reaches them): deleteNode would free indexed
  // coarse voxels (use set_label(key, level, Label::kUnknown) to forget an
  // octant), swapContent would leave both trees' indexes stale, and the .bt
  // readers and writers are the above's callers.
  bool readBinary(std::istream& s) = delete;
  bool readBinary(const std::string& filename) = delete;
  bool writeBinary(std::ostream& s) = delete;
  bool writeBinary(const std::string& filename) = delete;
  bool writeBinaryConst(std::ostream& s) const = delete;
  bool writeBinaryConst(const std::string& filename) const = delete;
  bool deleteNode(double x, double y, double z, unsigned int depth = 0) = delete;
  bool deleteNode(const octomap::point3d& value, unsigned int depth = 0) = delete;
  bool deleteNode(const octomap::OcTreeKey& key, unsigned int depth = 0) = delete;
  void swapContent(octomap::OcTreeBaseImpl<SemiOcTreeNode, octomap::AbstractOccupancyOcTree>&) =
      delete;

  // --- file format ------------------------------------------------------------
  // .ot payload: a small header (magic, leaf level k, exact resolution, node
  // count, byte count, FNV-1a hash) and OctoMap's node stream. readData throws
  // FileFormatError on anything malformed and leaves the tree empty.
  std::istream& readData(std::istream& s) override;
  std::ostream& writeData(std::ostream& s) const override;

 protected:
  // Registers the type with AbstractOcTree so that AbstractOcTree::read and
  // octomap tools linking octomap_ext can create it from a file header.
  class StaticMemberInitializer {
   public:
    StaticMemberInitializer();
    void ensureLinking() {}
  };
  static StaticMemberInitializer semioctree_member_init_;
  friend void register_tree_types();  // registers the prototype (OctoMap's call is protected)

 private:
  struct SegmentFrame;  // per-segment constants of traverse()
  // for_each_octant over the subtree of `node` (at `depth`, minimum-corner key `key`).
  template <class F>
  void for_each_octant_below(const SemiOcTreeNode* node, unsigned depth,
                             const octomap::OcTreeKey& key, F& f) const;
  template <bool kMarkedOnly, class Visitor>
  TraversalEnd traverse_impl(const Point3& a, const Point3& b, Visitor& visit) const;
  template <bool kMarkedOnly, class Visitor>
  bool traverse_children(const SegmentFrame& f, const SemiOcTreeNode* node, unsigned level,
                         const std::int64_t base[3], double t_in, int p_in, double t_out, int p_out,
                         Visitor& visit) const;
  static std::uint64_t pack(const octomap::OcTreeKey& coarse_key_bits);
  void rebuild_coarse_index();
  void prune_subtree(SemiOcTreeNode* node);
  bool mark_recurs(SemiOcTreeNode* node, std::uint32_t labels);
  void mark_coarse_recurs(SemiOcTreeNode* node, unsigned depth, octomap::OcTreeKey key);
  void delete_children(SemiOcTreeNode* node);
  template <class F>
  bool hull_children(const double apex[3], const double lo[3], const double hi[3],
                     const SemiOcTreeNode* node, unsigned level, const std::int64_t base[3],
                     F& f) const;

  unsigned leaf_level_ = 0;
  std::uint32_t marked_labels_ = 0;  // the labels last given to mark_subtrees
  // Packed (key >> k) of each coarse voxel → its node.
  PackedKeyMap<SemiOcTreeNode*, 50> coarse_;  // packed coarse index → node
};

// Registers SemiOcTree with OctoMap's tree factory, so that AbstractOcTree::read and
// createTree know the type. Linking the CMake target semioctree::octomap_ext does it
// before main() even in a program that names no SemiOcTree symbol (the target makes the
// linker keep the registration, which a static library would otherwise drop); call this
// only when linking the library by other means. Idempotent.
void register_tree_types();

// Thrown for malformed tree data (bad magic, truncation, hash mismatch, ...).
class FileFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace semioctree

#include "semioctree/octomap_ext/semioctree_impl.hxx"
