// Open-addressing hash table from a packed coarse key to its node. The ray
// traversal looks a coarse voxel up on nearly every step through empty space,
// so lookups must cost a multiply and a probe or two, not a modulo by a prime
// and a pointer chase as in std::unordered_map.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace semioctree {

template <class Node>
class CoarseTable {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);

  Node* find(std::uint64_t key) const {
    if (slots_.empty()) return nullptr;
    for (std::size_t i = slot_of(key);; i = (i + 1) & mask_) {
      const Slot& s = slots_[i];
      if (s.key == key) return s.node;
      if (s.key == kEmpty) return nullptr;
    }
  }
  // Hints the cache to fetch the slot of `key` (the traversal knows the next
  // coarse voxel one step ahead).
  void prefetch(std::uint64_t key) const {
    if (!slots_.empty()) __builtin_prefetch(&slots_[slot_of(key)]);
  }
  // Inserts or replaces.
  void insert(std::uint64_t key, Node* node) {
    if ((size_ + 1) * 2 > slots_.size()) grow();
    for (std::size_t i = slot_of(key);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.key == key) {
        s.node = node;
        return;
      }
      if (s.key == kEmpty) {
        s = {key, node};
        ++size_;
        return;
      }
    }
  }
  void clear() {
    slots_.clear();
    size_ = 0;
    mask_ = 0;
    shift_ = 64;
  }
  std::size_t size() const { return size_; }
  std::size_t memory_bytes() const { return slots_.capacity() * sizeof(Slot); }

 private:
  struct Slot {
    std::uint64_t key = kEmpty;
    Node* node = nullptr;
  };
  std::size_t slot_of(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hashing
  }
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    const std::size_t cap = old.empty() ? 64 : old.size() * 2;
    slots_.assign(cap, Slot{});
    mask_ = cap - 1;
    shift_ = 64;
    for (std::size_t c = cap; c > 1; c >>= 1) --shift_;
    size_ = 0;
    for (const Slot& s : old)
      if (s.key != kEmpty) insert(s.key, s.node);
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  std::size_t mask_ = 0;
  unsigned shift_ = 64;
};

}  // namespace semioctree
