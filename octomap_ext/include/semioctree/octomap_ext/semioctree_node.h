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
  // Flags kept with the node, in memory only (neither copied nor written to files).
  enum Flag : std::uint8_t {
    kCoarseRoot = 1u << 0,  // set by the tree on the nodes of the coarse grid
    // Set by SemiOcTree::mark_subtrees on split octants whose subtree holds a
    // leaf with one of the asked labels.
    kMarked = 1u << 1,
  };

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
    flags_ = static_cast<std::uint8_t>(flags_ & kCoarseRoot);
  }
  bool operator==(const SemiOcTreeNode& rhs) const {
    return rhs.value == value && rhs.label_ == label_ && rhs.aux_ == aux_;
  }

  // Serialized form in .ot files: log-odds, label, a reserved byte (written 0,
  // ignored when read: older files kept two never-set flags there), aux (8 bytes).
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
