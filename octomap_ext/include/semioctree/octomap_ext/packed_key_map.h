// Open-addressing hash map from 64-bit packed keys (coarse voxels, cells,
// lattice points) to small values. The ray traversal looks a coarse voxel up
// on nearly every step through empty space and the pipeline's per-point loops
// index millions of cells, so a lookup must cost a multiply and a probe or
// two, not a modulo by a prime and a pointer chase as in std::unordered_map.
#pragma once

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace semioctree {

// Three 21-bit parts (each taken modulo 2^21) as one key of a PackedKeyMap: x in bits
// 42-62, y in 21-41, z in 0-20 (bit 63 stays clear, so no key is kNoKey); and back.
inline std::uint64_t pack_cell_parts(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  constexpr std::uint64_t kMask = (std::uint64_t(1) << 21) - 1;
  return ((x & kMask) << 42) | ((y & kMask) << 21) | (z & kMask);
}
inline std::uint64_t unpack_cell_part(std::uint64_t packed, int axis) {
  return (packed >> (21 * (2 - axis))) & ((std::uint64_t(1) << 21) - 1);
}

// kMaxLoadPercent: the table doubles before it is fuller than this. Lookups
// that mostly miss (the traversal's, outside the map) want it low.
template <class Value, unsigned kMaxLoadPercent = 75>
class PackedKeyMap {
  static_assert(kMaxLoadPercent > 0 && kMaxLoadPercent < 100, "load must be in (0, 100) %");
  static_assert(!std::is_same_v<Value, bool>, "std::vector<bool> has no addressable values");

 public:
  // Marks a free slot, so it is not a key (no packed key uses all 64 bits).
  static constexpr std::uint64_t kNoKey = ~std::uint64_t(0);

  // Sized for `expected` keys without growing.
  explicit PackedKeyMap(std::size_t expected = 0) { reserve(expected); }
  // The most keys a table of `slots` slots (a power of two) holds without growing.
  static constexpr std::size_t keys_held_in(std::size_t slots) {
    return slots * kMaxLoadPercent / 100;
  }

  const Value* find(std::uint64_t key) const {
    assert(key != kNoKey);
    if (keys_.empty()) return nullptr;
    for (std::size_t i = slot_of(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (keys_[i] == key) return &values_[i];
      if (keys_[i] == kNoKey) return nullptr;
    }
  }
  Value value_or(std::uint64_t key, Value fallback) const {
    const Value* v = find(key);
    return v ? *v : fallback;
  }
  // The value stored with `key`, storing `value` first if the key is new;
  // second: whether it was new. Only an insertion can grow the table (and
  // move the values).
  std::pair<Value*, bool> try_emplace(std::uint64_t key, const Value& value) {
    assert(key != kNoKey);
    if (!keys_.empty()) {
      std::size_t i = slot_of(key);
      for (; keys_[i] != kNoKey; i = (i + 1) & (keys_.size() - 1))
        if (keys_[i] == key) return {&values_[i], false};
      if (100 * (size_ + 1) <= kMaxLoadPercent * keys_.size()) return {store(i, key, value), true};
    }
    reserve(2 * size_ + 1);
    std::size_t i = slot_of(key);
    while (keys_[i] != kNoKey) i = (i + 1) & (keys_.size() - 1);
    return {store(i, key, value), true};
  }
  void insert_or_assign(std::uint64_t key, const Value& value) {
    const auto r = try_emplace(key, value);
    if (!r.second) *r.first = value;
  }
  // As a set of keys: false when the key was already there.
  bool insert(std::uint64_t key) { return try_emplace(key, Value{}).second; }
  // Hints the cache to fetch the slot of `key` (loops know their next keys).
  void prefetch(std::uint64_t key) const {
    if (!keys_.empty()) __builtin_prefetch(&keys_[slot_of(key)]);
  }
  // The slots reserve(n) gives a table (a power of two, at least 64), and their bytes.
  static constexpr std::size_t slots_for(std::size_t n) {
    std::size_t slots = 64;
    while (kMaxLoadPercent * slots < 100 * n) slots *= 2;
    return slots;
  }
  static constexpr std::size_t bytes_for(std::size_t n) {
    return slots_for(n) * (sizeof(std::uint64_t) + sizeof(Value));
  }
  // Room for n keys without growing.
  void reserve(std::size_t n) {
    if (n == 0) return;
    const std::size_t capacity = slots_for(n);
    if (capacity <= keys_.size()) return;
    std::vector<std::uint64_t> old_keys(capacity, kNoKey);
    std::vector<Value> old_values(capacity);
    old_keys.swap(keys_);
    old_values.swap(values_);
    shift_ = 64 - unsigned(__builtin_ctzll(capacity));
    for (std::size_t j = 0; j < old_keys.size(); ++j) {
      if (old_keys[j] == kNoKey) continue;
      std::size_t i = slot_of(old_keys[j]);
      while (keys_[i] != kNoKey) i = (i + 1) & (keys_.size() - 1);
      keys_[i] = old_keys[j];
      values_[i] = old_values[j];
    }
  }
  // Forgets every key but keeps the slots: a table filled again and again (a count per
  // trial) is not allocated, and its pages faulted in, each time.
  void forget_keys() {
    std::fill(keys_.begin(), keys_.end(), kNoKey);
    size_ = 0;
  }
  void clear() {
    keys_ = {};
    values_ = {};
    size_ = 0;
    shift_ = 64;
  }
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return keys_.size(); }  // slots
  // Calls f(key) for every key, in slot order, until f returns false.
  template <class F>
  void for_each_key(const F& f) const {
    for (const std::uint64_t key : keys_)
      if (key != kNoKey && !f(key)) return;
  }
  std::size_t memory_bytes() const {
    return keys_.capacity() * sizeof(std::uint64_t) + values_.capacity() * sizeof(Value);
  }

 private:
  std::size_t slot_of(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hashing
  }
  Value* store(std::size_t i, std::uint64_t key, const Value& value) {
    keys_[i] = key;
    values_[i] = value;
    ++size_;
    return &values_[i];
  }

  // Keys and values apart: a slot costs 8 + sizeof(Value) bytes, not a padded
  // pair, and probes read only keys.
  std::vector<std::uint64_t> keys_;  // a power of two of them; kNoKey: free
  std::vector<Value> values_;
  unsigned shift_ = 64;
  std::size_t size_ = 0;
};

// A direct-mapped cache in front of a PackedKeyMap: in each of 2^kBits slots, the last
// key remembered there and its value. Loops over a scan's points, which come in sweep
// order and mostly fall into a cell met a few points before, ask it first and probe the
// table (many megabytes, past the processor's caches) only when it does not know the key.
// It answers for keys remembered, never for others, so a loop that remembers only what
// its table holds gets the table's answers.
template <class Value, unsigned kBits = 12>
class RecentKeys {
 public:
  RecentKeys() : keys_(kSlots, kNoKey), values_(kSlots) {}
  // The value remembered with `key` (not kNoKey) if its slot still holds it, else null.
  const Value* find(std::uint64_t key) const {
    const std::size_t i = slot_of(key);
    return keys_[i] == key ? &values_[i] : nullptr;
  }
  void remember(std::uint64_t key, const Value& value) {
    const std::size_t i = slot_of(key);
    keys_[i] = key;
    values_[i] = value;
  }
  void forget_all() { keys_.assign(kSlots, kNoKey); }

 private:
  static constexpr std::uint64_t kNoKey = ~std::uint64_t(0);
  static constexpr std::size_t kSlots = std::size_t(1) << kBits;
  static std::size_t slot_of(std::uint64_t key) {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> (64 - kBits));
  }
  std::vector<std::uint64_t> keys_;
  std::vector<Value> values_;
};

}  // namespace semioctree
