// Open-addressing hash map from 64-bit packed keys (coarse voxels, cells,
// lattice points) to small values. The ray traversal looks a coarse voxel up
// on nearly every step through empty space and the pipeline's per-point loops
// index millions of cells, so a lookup must cost a multiply and a probe or
// two, not a modulo by a prime and a pointer chase as in std::unordered_map.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace semioctree {

// kMaxLoadPercent: the table doubles before it is fuller than this. Lookups
// that mostly miss (the traversal's, outside the map) want it low.
template <class Value, unsigned kMaxLoadPercent = 75>
class PackedKeyMap {
  static_assert(kMaxLoadPercent > 0 && kMaxLoadPercent < 100, "load must be in (0, 100) %");

 public:
  static constexpr std::uint64_t kNoKey = ~std::uint64_t(0);  // never a packed key

  // Sized for `expected` keys without growing.
  explicit PackedKeyMap(std::size_t expected = 0) { reserve(expected); }

  const Value* find(std::uint64_t key) const {
    if (slots_.empty()) return nullptr;
    for (std::size_t i = slot_of(key);; i = (i + 1) & (slots_.size() - 1)) {
      const Slot& s = slots_[i];
      if (s.key == key) return &s.value;
      if (s.key == kNoKey) return nullptr;
    }
  }
  Value value_or(std::uint64_t key, Value fallback) const {
    const Value* v = find(key);
    return v ? *v : fallback;
  }
  // The value stored with `key`, storing `value` first if the key is new;
  // second: whether it was new.
  std::pair<Value*, bool> try_emplace(std::uint64_t key, const Value& value) {
    if (100 * (size_ + 1) > kMaxLoadPercent * slots_.size()) reserve(2 * size_ + 1);
    for (std::size_t i = slot_of(key);; i = (i + 1) & (slots_.size() - 1)) {
      Slot& s = slots_[i];
      if (s.key == key) return {&s.value, false};
      if (s.key == kNoKey) {
        s.key = key;
        s.value = value;
        ++size_;
        return {&s.value, true};
      }
    }
  }
  void insert_or_assign(std::uint64_t key, const Value& value) {
    const auto r = try_emplace(key, value);
    if (!r.second) *r.first = value;
  }
  // As a set of keys: false when the key was already there.
  bool insert(std::uint64_t key) { return try_emplace(key, Value{}).second; }
  // Hints the cache to fetch the slot of `key` (loops know their next keys).
  void prefetch(std::uint64_t key) const {
    if (!slots_.empty()) __builtin_prefetch(&slots_[slot_of(key)]);
  }
  // Room for n keys without growing.
  void reserve(std::size_t n) {
    if (n == 0) return;
    std::size_t capacity = 64;
    while (kMaxLoadPercent * capacity < 100 * n) capacity *= 2;
    if (capacity <= slots_.size()) return;
    std::vector<Slot> old(capacity);
    old.swap(slots_);
    shift_ = 64 - unsigned(__builtin_ctzll(capacity));
    size_ = 0;
    for (const Slot& s : old)
      if (s.key != kNoKey) try_emplace(s.key, s.value);
  }
  void clear() {
    slots_.clear();
    slots_.shrink_to_fit();
    size_ = 0;
    shift_ = 64;
  }
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return slots_.size(); }  // slots
  std::size_t memory_bytes() const { return slots_.capacity() * sizeof(Slot); }

 private:
  struct Slot {
    std::uint64_t key = kNoKey;
    Value value{};
  };
  std::size_t slot_of(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hashing
  }

  std::vector<Slot> slots_;  // a power of two of them
  unsigned shift_ = 64;
  std::size_t size_ = 0;
};

}  // namespace semioctree
