// Brute-force reference for SemiOcTree::traverse: decides, cell by cell over the
// bounding box of a segment, whether the segment passes through the cell, with
// no stepping and no hierarchy. It shares only the definition of a crossing
// time, t = (plane − A)·(1/(B − A)) in leaf units, and the rule for ties (a
// point on a plane belongs to the cell above it).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::testing {

struct RefStep {
  octomap::OcTreeKey key;  // min-corner key of the octant
  unsigned level;
  bool has_node;
  double t_enter;
  bool operator==(const RefStep& o) const {
    return key == o.key && level == o.level && has_node == o.has_node && t_enter == o.t_enter;
  }
};

inline std::vector<RefStep> reference_traversal(const SemiOcTree& tree, const Point3& a,
                                                const Point3& b) {
  const double inv = 1.0 / tree.getResolution();
  const double A[3] = {a.x * inv, a.y * inv, a.z * inv};
  const double B[3] = {b.x * inv, b.y * inv, b.z * inv};
  std::int64_t s[3], e[3];
  int dir[3];
  double invD[3];
  for (int i = 0; i < 3; ++i) {
    s[i] = std::int64_t(std::floor(A[i]));
    e[i] = std::int64_t(std::floor(B[i]));
    dir[i] = e[i] > s[i] ? 1 : (e[i] < s[i] ? -1 : 0);
    invD[i] = dir[i] ? 1.0 / (B[i] - A[i]) : 0.0;
  }
  using Key = std::pair<double, int>;  // (t, phase), compared lexicographically
  const double inf = std::numeric_limits<double>::infinity();
  const Key kMinus{-inf, 0}, kPlus{inf, 2};
  auto cross = [&](int i, std::int64_t p) { return (double(p) - A[i]) * invD[i]; };
  // Per axis: for each cell index, the key interval [enter, leave) spent in it.
  std::vector<std::tuple<std::int64_t, Key, Key>> axis[3];
  for (int i = 0; i < 3; ++i) {
    const std::int64_t lo = std::min(s[i], e[i]), hi = std::max(s[i], e[i]);
    for (std::int64_t c = lo; c <= hi; ++c) {
      Key enter = kMinus, leave = kPlus;
      if (dir[i] > 0) {
        if (c != s[i]) enter = {cross(i, c), 0};
        if (c != e[i]) leave = {cross(i, c + 1), 0};
      } else if (dir[i] < 0) {
        if (c != s[i]) enter = {cross(i, c + 1), 1};
        if (c != e[i]) leave = {cross(i, c), 1};
      }
      axis[i].emplace_back(c, enter, leave);
    }
  }
  // Octant (key, level) → earliest entry key.
  std::map<std::tuple<unsigned, unsigned, unsigned, unsigned>, std::pair<Key, bool>> octants;
  for (const auto& [cx, ex, lx] : axis[0])
    for (const auto& [cy, ey, ly] : axis[1])
      for (const auto& [cz, ez, lz] : axis[2]) {
        const Key enter = std::max({ex, ey, ez});
        const Key leave = std::min({lx, ly, lz});
        if (!(enter < leave)) continue;
        const octomap::OcTreeKey cell(octomap::key_type(cx + kKeyOrigin),
                                      octomap::key_type(cy + kKeyOrigin),
                                      octomap::key_type(cz + kKeyOrigin));
        unsigned level = 0;
        octomap::OcTreeKey okey;
        bool has_node = false;
        if (auto o = tree.find_octant(cell)) {
          level = o->level;
          okey = o->key;
          has_node = true;
        } else {
          const unsigned mask = ~((1u << tree.leaf_level()) - 1u);
          for (int i = 0; i < 3; ++i) okey.k[i] = octomap::key_type(cell.k[i] & mask);
        }
        const auto id =
            std::make_tuple(unsigned(okey.k[0]), unsigned(okey.k[1]), unsigned(okey.k[2]), level);
        auto it = octants.find(id);
        if (it == octants.end())
          octants.emplace(id, std::make_pair(enter, has_node));
        else
          it->second.first = std::min(it->second.first, enter);
      }
  std::vector<std::pair<Key, RefStep>> seq;
  for (const auto& [id, v] : octants) {
    RefStep st;
    st.key =
        octomap::OcTreeKey(octomap::key_type(std::get<0>(id)), octomap::key_type(std::get<1>(id)),
                           octomap::key_type(std::get<2>(id)));
    st.level = std::get<3>(id);
    st.has_node = v.second;
    st.t_enter = v.first.first == -inf ? 0.0 : v.first.first;
    seq.emplace_back(v.first, st);
  }
  std::sort(seq.begin(), seq.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<RefStep> out;
  for (auto& p : seq) out.push_back(p.second);
  return out;
}

}  // namespace semioctree::testing
