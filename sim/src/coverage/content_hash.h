// A content hash for the coverage cache's key and checksum (internal).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <type_traits>

namespace semioctree::sim::detail {

// Two independent 64-bit hashes of a byte stream, taken 8 bytes at a time through a
// full-avalanche mix, printed as 32 hex digits. The same sequence of calls gives the
// same hash on any run of the same build. Changing it changes every cache key and
// checksum (old cache files are then recomputed, never misread).
class ContentHash {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (; n >= 8; p += 8, n -= 8) {
      std::uint64_t w;
      std::memcpy(&w, p, 8);
      word(w);
    }
    std::uint64_t tail = 0x80;  // marks the end, so that trailing zero bytes count
    for (std::size_t i = 0; i < n; ++i) tail = (tail << 8) | p[i];
    if (n) word(tail);
  }
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof v);
  }
  void text(const std::string& s) {
    value(static_cast<std::uint64_t>(s.size()));
    bytes(s.data(), s.size());
  }
  std::uint64_t first() const { return mix(a_ ^ count_); }
  std::string hex() const {
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(first()),
                  static_cast<unsigned long long>(mix(b_ + count_)));
    return buf;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static std::uint64_t mix(std::uint64_t x) {  // splitmix64's finalizer
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
  }
  void word(std::uint64_t w) {
    ++count_;
    a_ = rotl(a_ ^ mix(w), 29) * 0x9e3779b97f4a7c15ull;
    b_ = rotl(b_ + mix(w ^ 0x6a09e667f3bcc909ull), 37) * 0xc2b2ae3d27d4eb4full;
  }
  std::uint64_t a_ = 0xcbf29ce484222325ull;
  std::uint64_t b_ = 0x84222325cbf29ce4ull;
  std::uint64_t count_ = 0;
};

}  // namespace semioctree::sim::detail
