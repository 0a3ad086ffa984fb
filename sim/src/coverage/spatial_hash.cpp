// Points hashed by cubic cell (see spatial_hash.h).
#include "coverage/spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

namespace semioctree::sim::detail {

namespace {

// The slot a key starts probing at (murmur3's 64-bit finalizer).
std::uint64_t slot_hash(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

}  // namespace

PointHash::PointHash(const std::vector<Eigen::Vector3d>& points, double cell)
    : cell_(cell), points_(points) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    keyed.emplace_back(cell_key(points[i]), static_cast<std::uint32_t>(i));
  std::sort(keyed.begin(), keyed.end());
  by_cell_.reserve(points.size());
  for (const auto& k : keyed) by_cell_.push_back(k.second);
  std::size_t capacity = 16;
  std::size_t cells = 0;
  for (std::size_t i = 0; i < keyed.size(); ++i)
    if (i == 0 || keyed[i].first != keyed[i - 1].first) ++cells;
  while (capacity < 2 * cells) capacity *= 2;
  slots_.assign(capacity, Slot{});
  for (std::size_t i = 0; i < keyed.size();) {
    std::size_t j = i;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    std::size_t h = slot_hash(keyed[i].first) & (capacity - 1);
    while (slots_[h].count) h = (h + 1) & (capacity - 1);
    slots_[h] = {keyed[i].first, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j - i)};
    i = j;
  }
}

long PointHash::index(double v) const {
  return static_cast<long>(std::floor(v / cell_));
}

std::uint64_t PointHash::cell_key(const Eigen::Vector3d& p) const {
  return grid_cell_key(index(p.x()), index(p.y()), index(p.z()));
}

const PointHash::Slot* PointHash::find(std::uint64_t key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t h = slot_hash(key) & mask;; h = (h + 1) & mask) {
    if (!slots_[h].count) return nullptr;
    if (slots_[h].key == key) return &slots_[h];
  }
}

}  // namespace semioctree::sim::detail
