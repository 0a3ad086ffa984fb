// Open-addressing hash index of 64-bit packed keys (cells, lattice points) for
// the pipeline's per-point loops: a multiply and a probe or two per lookup,
// where std::unordered_map would chase pointers. Internal to the library.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace semioctree::detail {

class PackedKeyIndex {
 public:
  // Sized for `expected` keys without growing (it grows past that).
  explicit PackedKeyIndex(std::size_t expected = 0) { reserve(expected); }

  // The id stored with `key`; a new key is stored with `next_id`, which is
  // returned (so "inserted" is: the result equals next_id).
  std::uint32_t find_or_add(std::uint64_t key, std::uint32_t next_id) {
    if (4 * (size_ + 1) > 3 * keys_.size()) reserve(2 * size_ + 1);
    for (std::size_t i = slot_of(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (keys_[i] == key) return ids_[i];
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        ids_[i] = next_id;
        ++size_;
        return next_id;
      }
    }
  }
  // False when the key was already there (a set of keys).
  bool insert(std::uint64_t key) {
    const std::size_t before = size_;
    find_or_add(key, 0);
    return size_ != before;
  }
  // Hints the cache to fetch the slot of `key` (loops know their next keys).
  void prefetch(std::uint64_t key) const {
    if (!keys_.empty()) __builtin_prefetch(&keys_[slot_of(key)]);
  }
  std::size_t size() const { return size_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);  // never a packed key

  std::size_t slot_of(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hashing
  }
  void reserve(std::size_t n) {
    std::size_t capacity = 1024;
    while (3 * capacity < 4 * n) capacity *= 2;
    if (capacity <= keys_.size()) return;
    std::vector<std::uint64_t> keys = std::move(keys_);
    std::vector<std::uint32_t> ids = std::move(ids_);
    keys_.assign(capacity, kEmpty);
    ids_.assign(capacity, 0);
    shift_ = 64 - unsigned(__builtin_ctzll(capacity));
    size_ = 0;
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) find_or_add(keys[i], ids[i]);
  }

  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> ids_;
  unsigned shift_ = 64;
  std::size_t size_ = 0;
};

}  // namespace semioctree::detail
