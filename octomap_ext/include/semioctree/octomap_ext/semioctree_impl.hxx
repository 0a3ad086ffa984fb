// Template members of SemiOcTree (included from semioctree.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace semioctree {

namespace detail {

inline octomap::OcTreeKey child_key(const octomap::OcTreeKey& parent, unsigned parent_depth,
                                    unsigned idx) {
  const unsigned bit = SemiOcTree::kTreeDepth - 1 - parent_depth;
  octomap::OcTreeKey k = parent;
  for (unsigned a = 0; a < 3; ++a)
    if (idx & (1u << a)) k.k[a] = static_cast<octomap::key_type>(k.k[a] | (1u << bit));
  return k;
}

template <class Tree, class F>
void walk_depth_first(const Tree& tree, const SemiOcTreeNode* node, unsigned depth,
                      const octomap::OcTreeKey& key, F& f) {
  if (!f(node, depth, key)) return;  // f decides whether to descend
  if (!tree.nodeHasChildren(node)) return;
  for (unsigned i = 0; i < 8; ++i)
    if (tree.nodeChildExists(node, i))
      walk_depth_first(tree, tree.getNodeChild(node, i), depth + 1, child_key(key, depth, i), f);
}

}  // namespace detail

template <class F>
void SemiOcTree::for_each_coarse(F&& f) const {
  if (!root) return;
  const unsigned cd = coarse_depth();
  auto visit = [&](const SemiOcTreeNode* node, unsigned depth, const octomap::OcTreeKey& key) {
    if (depth < cd) return true;
    f(coarse_index(key), const_cast<SemiOcTreeNode*>(node));
    return false;
  };
  detail::walk_depth_first(*this, root, 0, octomap::OcTreeKey(0, 0, 0), visit);
}

template <class F>
void SemiOcTree::for_each_octant(F&& f) const {
  if (root) for_each_octant_below(root, 0, octomap::OcTreeKey(0, 0, 0), f);
}

template <class F>
void SemiOcTree::for_each_octant_below(const SemiOcTreeNode* node, unsigned depth,
                                       const octomap::OcTreeKey& key, F& f) const {
  // A node's children are visited; a node without any is a leaf octant (if at or below
  // the coarse depth).
  bool parent = false;
  for (unsigned i = 0; i < 8; ++i)
    if (nodeChildExists(node, i)) {
      parent = true;
      for_each_octant_below(getNodeChild(node, i), depth + 1, detail::child_key(key, depth, i), f);
    }
  if (!parent && depth >= coarse_depth()) f(make_octant(key, depth - coarse_depth(), node));
}

inline Octant SemiOcTree::make_octant(const octomap::OcTreeKey& key, unsigned level,
                                      const SemiOcTreeNode* node) const {
  Octant o;
  const unsigned shift = leaf_level_ - level;
  const unsigned mask = ~((1u << shift) - 1u);
  for (int i = 0; i < 3; ++i) o.key.k[i] = static_cast<octomap::key_type>(key.k[i] & mask);
  o.level = level;
  o.size = octant_size(level);
  const double half = 0.5 * o.size;
  o.center = Point3((double(o.key.k[0]) - double(kKeyOrigin)) * resolution + half,
                    (double(o.key.k[1]) - double(kKeyOrigin)) * resolution + half,
                    (double(o.key.k[2]) - double(kKeyOrigin)) * resolution + half);
  o.node = node;
  return o;
}

// Traversal. Positions are in leaf-cell units relative to the world origin
// (cell i is [i, i+1)), scaled exactly as OctoMap's coordToKey does, so our
// cells are its cells. An axis reaches boundary plane p at
// t = (p − A)·(1/(B − A)); every decision uses this one formula, so ties
// (edges, corners) resolve consistently. Crossing events are ordered by
// (t, phase): moving up, a point on a plane already belongs to the cell above
// (phase 0, at t); moving down it belongs to that cell until just after t
// (phase 1). Only planes between the start and end cells are ever crossed.
struct SemiOcTree::SegmentFrame {
  double A[3], invD[3];
  std::int64_t s[3], e[3];  // start and end cells
  int dir[3], phase[3];
  double cross(int i, std::int64_t plane) const { return (double(plane) - A[i]) * invD[i]; }
};

namespace detail {
// (t1, p1) < (t2, p2)
inline bool event_before(double t1, int p1, double t2, int p2) {
  return t1 < t2 || (t1 == t2 && p1 < p2);
}
}  // namespace detail

template <bool kMarkedOnly, class Visitor>
bool SemiOcTree::traverse_children(const SegmentFrame& f, const SemiOcTreeNode* node,
                                   unsigned level, const std::int64_t base[3], double t_in,
                                   int p_in, double t_out, int p_out, Visitor& visit) const {
  // The segment is inside `node` for events in [in, out). Its children are
  // entered where the segment crosses the node's three mid-planes.
  const std::int64_t half = std::int64_t(1) << (leaf_level_ - level - 1);
  unsigned child = 0;    // bit i: upper half along axis i
  unsigned pending = 0;  // bit i: mid-plane i is crossed after `in`, before `out`
  double tm[3] = {0, 0, 0};
#pragma GCC unroll 3
  for (int i = 0; i < 3; ++i) {
    const std::int64_t mid = base[i] + half;
    const bool start_upper = f.s[i] >= mid;
    const bool crosses = f.dir[i] > 0 ? (f.s[i] < mid && mid <= f.e[i])
                                      : (f.dir[i] < 0 && f.e[i] < mid && mid <= f.s[i]);
    bool upper = start_upper;
    if (crosses) {
      tm[i] = f.cross(i, mid);
      if (!detail::event_before(t_in, p_in, tm[i], f.phase[i])) {
        upper = !start_upper;  // already crossed when the node was entered
      } else if (detail::event_before(tm[i], f.phase[i], t_out, p_out)) {
        pending |= 1u << i;
      }
    }
    child |= unsigned(upper) << i;
  }
  double t_cur = t_in;
  int p_cur = p_in;
  for (;;) {
    // Next event: the earliest pending mid-plane crossing, or leaving the node.
    double t_next = t_out;
    int p_next = p_out;
    unsigned flips = 0;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      if (!(pending & (1u << i))) continue;
      if (detail::event_before(tm[i], f.phase[i], t_next, p_next)) {
        t_next = tm[i];
        p_next = f.phase[i];
        flips = 1u << i;
      } else if (tm[i] == t_next && f.phase[i] == p_next) {
        flips |= 1u << i;
      }
    }
    if (flips && nodeChildExists(node, child ^ flips))
      __builtin_prefetch(getNodeChild(node, child ^ flips));  // the sibling entered next
    std::int64_t child_base[3];
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) child_base[i] = base[i] + ((child >> i) & 1u ? half : 0);
    const SemiOcTreeNode* c = nodeChildExists(node, child) ? getNodeChild(node, child) : nullptr;
    const bool split = c && level + 1 < leaf_level_ && nodeHasChildren(c);
    if (split && (!kMarkedOnly || c->has_flag(SemiOcTreeNode::kMarked))) {
      if (!traverse_children<kMarkedOnly>(f, c, level + 1, child_base, t_cur, p_cur, t_next, p_next,
                                          visit))
        return false;
    } else {
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(child_base[0] + kKeyOrigin),
                                   static_cast<octomap::key_type>(child_base[1] + kKeyOrigin),
                                   static_cast<octomap::key_type>(child_base[2] + kKeyOrigin));
      if (!visit(RayStep{key, level + 1, c,
                         t_cur == -std::numeric_limits<double>::infinity() ? 0.0 : t_cur, split}))
        return false;
    }
    if (!flips) return true;  // left the node
    child ^= flips;
    pending &= ~flips;
    t_cur = t_next;
    p_cur = p_next;
  }
}

namespace detail {
// Narrows the parameter interval (t0, t1] to the t with t·d < c; false when none is left.
inline bool narrow_below(double& t0, double& t1, double d, double c) {
  if (d > 0)
    t1 = std::min(t1, c / d);
  else if (d < 0)
    t0 = std::max(t0, c / d);
  else if (!(c > 0))
    return false;
  return t0 < t1;
}
// Whether the interior of the hull of point a and box [lo, hi] meets the interior of box
// [nlo, nhi]: the hull is the union over t ∈ [0, 1] of the boxes a + t·([lo, hi] − a), so
// it does when for some t in (0, 1] those boxes overlap it with positive volume.
inline bool hull_meets_box(const double a[3], const double lo[3], const double hi[3],
                           const double nlo[3], const double nhi[3]) {
  double t0 = 0, t1 = 1;
  for (int i = 0; i < 3; ++i)
    if (!narrow_below(t0, t1, lo[i] - a[i], nhi[i] - a[i]) ||
        !narrow_below(t0, t1, a[i] - hi[i], a[i] - nlo[i]))
      return false;
  return true;
}
// Where the wedge from a to box [lo, hi] (the boxes a + t·([lo, hi] − a), t ∈ [0, 1])
// crosses the slab [s0, s1] along `axis`: in `low` and `high`, per other axis (`axis` + 1,
// then + 2, modulo 3), the range the wedge spans there. False when it never reaches it.
inline bool wedge_across_slab(const double a[3], const double lo[3], const double hi[3], int axis,
                              double s0, double s1, double low[2], double high[2]) {
  double t0 = 0, t1 = 1;
  const auto reach = [&](double d, double c) {  // t·d <= c
    if (d > 0)
      t1 = std::min(t1, c / d);
    else if (d < 0)
      t0 = std::max(t0, c / d);
    else if (c < 0)
      t1 = -1;
  };
  reach(lo[axis] - a[axis], s1 - a[axis]);
  reach(a[axis] - hi[axis], a[axis] - s0);
  if (t0 > t1) return false;
  for (int j = 0; j < 2; ++j) {
    const int i = (axis + 1 + j) % 3;
    low[j] = std::min(a[i] + t0 * (lo[i] - a[i]), a[i] + t1 * (lo[i] - a[i]));
    high[j] = std::max(a[i] + t0 * (hi[i] - a[i]), a[i] + t1 * (hi[i] - a[i]));
  }
  return true;
}
}  // namespace detail

template <class F>
bool SemiOcTree::hull_children(const double apex[3], const double lo[3], const double hi[3],
                               const SemiOcTreeNode* node, unsigned level,
                               const std::int64_t base[3], F& f) const {
  const std::int64_t half = std::int64_t(1) << (leaf_level_ - level - 1);
  for (unsigned c = 0; c < 8; ++c) {
    if (!nodeChildExists(node, c)) continue;
    const SemiOcTreeNode* child = getNodeChild(node, c);
    const bool split = level + 1 < leaf_level_ && nodeHasChildren(child);
    if (split ? !child->has_flag(SemiOcTreeNode::kMarked)
              : !(marked_labels_ & (1u << unsigned(child->label()))))
      continue;
    std::int64_t child_base[3];
    double nlo[3], nhi[3];
    for (int i = 0; i < 3; ++i) {
      child_base[i] = base[i] + ((c >> i) & 1u ? half : 0);
      nlo[i] = double(child_base[i]);
      nhi[i] = nlo[i] + double(half);
    }
    if (!detail::hull_meets_box(apex, lo, hi, nlo, nhi)) continue;
    if (split) {
      if (!hull_children(apex, lo, hi, child, level + 1, child_base, f)) return false;
      continue;
    }
    const octomap::OcTreeKey key(static_cast<octomap::key_type>(child_base[0] + kKeyOrigin),
                                 static_cast<octomap::key_type>(child_base[1] + kKeyOrigin),
                                 static_cast<octomap::key_type>(child_base[2] + kKeyOrigin));
    if (!f(make_octant(key, level + 1, child))) return false;
  }
  return true;
}

template <class F>
bool SemiOcTree::for_each_marked_in_hull(const Point3& apex, const octomap::OcTreeKey& key,
                                         unsigned level, F&& f) const {
  // In leaf-cell units (cell i is [i, i + 1)), as traverse() scales: the box's bounds and
  // every octant's are integers, so touching is decided exactly.
  const double inv = resolution_factor;
  const double a[3] = {apex.x * inv, apex.y * inv, apex.z * inv};
  const std::int64_t size = std::int64_t(1) << (leaf_level_ - level);
  double lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(a[i])) return true;
    lo[i] = double(std::int64_t(key.k[i]) - kKeyOrigin);
    hi[i] = lo[i] + double(size);
  }
  const unsigned k = leaf_level_;
  const std::int64_t span = std::int64_t(1) << k;
  const auto coarse_of = [&](double u) {
    return static_cast<std::int64_t>(std::floor(u / double(span)));
  };
  // Coarse layers along the axis the hull spans most; per layer, the range of the hull's
  // boxes a + t·([lo, hi] − a) over the t that reach it, on the other two axes.
  int m = 0;
  double extent[3];
  for (int i = 0; i < 3; ++i) {
    extent[i] = std::max(hi[i], a[i]) - std::min(lo[i], a[i]);
    if (extent[i] > extent[m]) m = i;
  }
  const int u = (m + 1) % 3, v = (m + 2) % 3;
  const std::int64_t limit = std::int64_t(1) << (kTreeDepth - k - 1);  // coarse index range
  const std::int64_t first = std::max(-limit, coarse_of(std::min(lo[m], a[m])));
  const std::int64_t last = std::min(limit - 1, coarse_of(std::max(hi[m], a[m])));
  for (std::int64_t layer = first; layer <= last; ++layer) {
    double low[2], high[2];
    if (!detail::wedge_across_slab(a, lo, hi, m, double(layer * span), double((layer + 1) * span),
                                   low, high))
      continue;
    std::int64_t from[2], to[2];
    for (int j = 0; j < 2; ++j) {
      from[j] = std::max(-limit, coarse_of(low[j]));
      to[j] = std::min(limit - 1, coarse_of(high[j]));
    }
    for (std::int64_t cu = from[0]; cu <= to[0]; ++cu)
      for (std::int64_t cv = from[1]; cv <= to[1]; ++cv) {
        std::int64_t cc[3];
        cc[m] = layer;
        cc[u] = cu;
        cc[v] = cv;
        std::int64_t base[3];
        octomap::OcTreeKey ck;
        double nlo[3], nhi[3];
        for (int i = 0; i < 3; ++i) {
          base[i] = cc[i] * span;
          ck.k[i] = static_cast<octomap::key_type>(base[i] + kKeyOrigin);
          nlo[i] = double(base[i]);
          nhi[i] = nlo[i] + double(span);
        }
        const SemiOcTreeNode* node =
            coarse_.value_or(pack_key_parts(ck.k[0] >> k, ck.k[1] >> k, ck.k[2] >> k), nullptr);
        if (!node) continue;
        const bool split = k > 0 && nodeHasChildren(node);
        if (split ? !node->has_flag(SemiOcTreeNode::kMarked)
                  : !(marked_labels_ & (1u << unsigned(node->label()))))
          continue;
        if (!detail::hull_meets_box(a, lo, hi, nlo, nhi)) continue;
        if (split) {
          if (!hull_children(a, lo, hi, node, 0, base, f)) return false;
        } else if (!f(make_octant(ck, 0, node))) {
          return false;
        }
      }
  }
  return true;
}

template <class Visitor>
TraversalEnd SemiOcTree::traverse(const Point3& a, const Point3& b, Visitor&& visit) const {
  return traverse_impl<false>(a, b, visit);
}

template <class Visitor>
TraversalEnd SemiOcTree::traverse_marked(const Point3& a, const Point3& b, Visitor&& visit) const {
  return traverse_impl<true>(a, b, visit);
}

template <bool kMarkedOnly, class Visitor>
TraversalEnd SemiOcTree::traverse_impl(const Point3& a, const Point3& b, Visitor& visit) const {
  SegmentFrame f;
  const double inv = resolution_factor;
  const double P[2][3] = {{a.x * inv, a.y * inv, a.z * inv}, {b.x * inv, b.y * inv, b.z * inv}};
  constexpr double kKeyHalf = double(kKeyOrigin);
  for (int i = 0; i < 3; ++i) {
    const double fa = std::floor(P[0][i]), fb = std::floor(P[1][i]);
    if (!(fa >= -kKeyHalf && fa < kKeyHalf && fb >= -kKeyHalf && fb < kKeyHalf))
      return TraversalEnd::kOutOfRange;  // also catches NaN
    f.A[i] = P[0][i];
    f.s[i] = static_cast<std::int64_t>(fa);
    f.e[i] = static_cast<std::int64_t>(fb);
    f.dir[i] = f.e[i] > f.s[i] ? 1 : (f.e[i] < f.s[i] ? -1 : 0);
    f.phase[i] = f.dir[i] < 0 ? 1 : 0;
    f.invD[i] = f.dir[i] != 0 ? 1.0 / (P[1][i] - P[0][i]) : 0.0;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const unsigned k = leaf_level_;
  const std::int64_t span = std::int64_t(1)
                            << k;  // leaf cells per coarse voxel (no << on negatives)
  // Coarse-level DDA: the coarse cell and the next coarse plane crossing per axis.
  std::int64_t cc[3], ce[3];
  double tn[3];
  for (int i = 0; i < 3; ++i) {
    cc[i] = f.s[i] >> k;  // arithmetic shift: floor division for negative cells too
    ce[i] = f.e[i] >> k;
    tn[i] = cc[i] == ce[i] ? kInf : f.cross(i, (cc[i] + (f.dir[i] > 0 ? 1 : 0)) * span);
  }
  double t_in = -kInf;
  int p_in = 0;
  for (;;) {
    double t_out = kInf;
    int p_out = 2;
    unsigned exits = 0;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      if (cc[i] == ce[i]) continue;
      if (detail::event_before(tn[i], f.phase[i], t_out, p_out)) {
        t_out = tn[i];
        p_out = f.phase[i];
        exits = 1u << i;
      } else if (tn[i] == t_out && f.phase[i] == p_out) {
        exits |= 1u << i;
      }
    }
    std::int64_t base[3];
    octomap::OcTreeKey key;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      base[i] = cc[i] * span;
      key.k[i] = static_cast<octomap::key_type>(base[i] + kKeyOrigin);
    }
    // O(1) access to the coarse voxel through the hashed grid.
    const SemiOcTreeNode* node =
        coarse_.value_or(pack_key_parts(key.k[0] >> k, key.k[1] >> k, key.k[2] >> k), nullptr);
    const bool split = node && k > 0 && nodeHasChildren(node);
    if (split && (!kMarkedOnly || node->has_flag(SemiOcTreeNode::kMarked))) {
      if (!traverse_children<kMarkedOnly>(f, node, 0, base, t_in, p_in, t_out, p_out, visit))
        return TraversalEnd::kStopped;
    } else if (!visit(RayStep{key, 0, node, t_in == -kInf ? 0.0 : t_in, split})) {
      return TraversalEnd::kStopped;
    }
    if (!exits) return TraversalEnd::kReachedEnd;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      if (!(exits & (1u << i))) continue;
      cc[i] += f.dir[i];
      tn[i] = cc[i] == ce[i] ? kInf : f.cross(i, (cc[i] + (f.dir[i] > 0 ? 1 : 0)) * span);
    }
    t_in = t_out;
    p_in = p_out;
  }
}

}  // namespace semioctree
