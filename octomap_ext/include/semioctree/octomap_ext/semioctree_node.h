// Node of the SemiOcTree: OctoMap occupancy log-odds plus a label and a little
// per-node state, packed into the tail padding of OcTreeNode (16 bytes).
#pragma once

#include <octomap/OcTreeNode.h>

#include <cstdint>
#include <iosfwd>

#include "semioctree/octomap_ext/labels.h"

namespace semioctree {

class SemiOcTreeNode : public octomap::OcTreeNode {
 public:
  // Flags kept with the node. kCoarseRoot is structural (set by the tree on the
  // nodes of the coarse grid) and is neither copied nor written to files.
  enum Flag : std::uint8_t {
    kCoarseRoot = 1u << 0,
    kSeen = 1u << 1,      // direct line of sight from some scanner position
    kBoundary = 1u << 2,  // partly visible octant (split during the occlusion study)
    // Set by SemiOcTree::mark_subtrees on split octants whose subtree holds a
    // leaf with one of the asked labels; transient (not copied, not written).
    kMarked = 1u << 3,
  };
  static constexpr std::uint8_t kPersistentFlags = kSeen | kBoundary;

  SemiOcTreeNode() = default;

  Label label() const { return static_cast<Label>(label_); }
  void set_label(Label l) { label_ = static_cast<std::uint8_t>(l); }
  bool has_flag(Flag f) const { return (flags_ & f) != 0; }
  void set_flag(Flag f, bool on) { flags_ = on ? (flags_ | f) : (flags_ & ~f); }
  std::uint8_t flags() const { return flags_; }
  bool is_coarse_root() const { return has_flag(kCoarseRoot); }
  // Stage-specific counter (e.g. index of the last scan that tested the octant).
  std::uint16_t aux() const { return aux_; }
  void set_aux(std::uint16_t a) { aux_ = a; }

  // OctoMap calls these (non-virtual, resolved on the node type):
  // copyData on expand/prune, operator== to decide whether siblings collapse.
  void copyData(const SemiOcTreeNode& from) {
    octomap::OcTreeNode::copyData(from);
    label_ = from.label_;
    aux_ = from.aux_;
    flags_ = static_cast<std::uint8_t>((flags_ & kCoarseRoot) | (from.flags_ & kPersistentFlags));
  }
  bool operator==(const SemiOcTreeNode& rhs) const {
    return rhs.value == value && rhs.label_ == label_ &&
           (rhs.flags_ & kPersistentFlags) == (flags_ & kPersistentFlags) && rhs.aux_ == aux_;
  }

  // Nodes come from a pool of 16-byte slots: half the footprint of malloc's
  // 32-byte chunks, so more of a map stays in cache during ray traversal.
  static void* operator new(std::size_t size);
  static void operator delete(void* p, std::size_t size) noexcept;

  // Serialized form in .ot files: log-odds, label, persistent flags, aux (8 bytes).
  static constexpr std::size_t kSerializedBytes = 8;
  std::istream& readData(std::istream& s);
  std::ostream& writeData(std::ostream& s) const;

 private:
  friend class SemiOcTree;
  // Frees the (already emptied) child pointer array; OctoMap keeps it otherwise.
  void release_child_array() {
    delete[] children;
    children = nullptr;
  }
  std::uint8_t label_ = 0;
  std::uint8_t flags_ = 0;
  std::uint16_t aux_ = 0;
};

static_assert(sizeof(SemiOcTreeNode) == 16, "SemiOcTreeNode must stay 16 bytes");

}  // namespace semioctree
