// SemiOcTree::traverse against a brute-force reference, geometric truth and
// OctoMap's own ray keys.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <random>
#include <set>

#include "semioctree/octomap_ext/semioctree.h"
#include "support/ray_reference.h"

namespace semioctree {
namespace {

using testing::RefStep;

std::vector<RefStep> traverse_all(const SemiOcTree& tree, const Point3& a, const Point3& b,
                                  TraversalEnd* end = nullptr) {
  std::vector<RefStep> out;
  const TraversalEnd e = tree.traverse(a, b, [&](const RayStep& s) {
    out.push_back({s.key, s.level, s.node != nullptr, s.t_enter});
    return true;
  });
  if (end) *end = e;
  return out;
}

// A tree with coarse voxels over [-3, 3) × [-3, 3) × [-1, 2) (coarse indices),
// a few coarse holes, random splits down to random depths and random labels.
std::unique_ptr<SemiOcTree> random_tree(double leaf, unsigned k, unsigned seed) {
  auto tree = std::make_unique<SemiOcTree>(leaf, leaf * double(1u << k));
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> label(1, kLabelCount - 1);
  for (int x = -3; x < 3; ++x)
    for (int y = -3; y < 3; ++y)
      for (int z = -1; z < 2; ++z) {
        if ((x * 7 + y * 3 + z * 5 + 64) % 11 == 0) continue;  // leave holes: unknown space
        SemiOcTreeNode* node = tree->create_coarse({x, y, z}, Label(label(rng)));
        (void)node;
      }
  // Random refinement: pick random leaf keys inside the region and label them
  // at a random level.
  std::uniform_real_distribution<double> ux(-3 * tree->coarse_size(), 3 * tree->coarse_size());
  std::uniform_real_distribution<double> uz(-1 * tree->coarse_size(), 2 * tree->coarse_size());
  if (k == 0) return tree;  // homogeneous: nothing to refine
  std::uniform_int_distribution<unsigned> lvl(1, k);
  for (int i = 0; i < 400; ++i) {
    octomap::OcTreeKey key;
    if (!tree->key_of({ux(rng), ux(rng), uz(rng)}, key)) continue;
    if (!tree->find_coarse(tree->coarse_index(key))) continue;
    tree->set_label(key, lvl(rng), Label(label(rng)));
  }
  return tree;
}

// A random segment; a share of them hit the hard cases exactly: end points on
// faces, edges and corners, axis-parallel rays, zero length, exact diagonals.
std::pair<Point3, Point3> random_segment(std::mt19937& rng, double leaf, double span,
                                         double reach) {
  std::uniform_real_distribution<double> u(-span, span);
  std::uniform_real_distribution<double> d(-reach, reach);
  std::uniform_int_distribution<int> kind(0, 9);
  std::uniform_int_distribution<int> cells(-int(reach / leaf), int(reach / leaf));
  auto snap = [&](double v) { return std::round(v / leaf) * leaf; };
  Point3 a(u(rng), u(rng), u(rng) * 0.5);
  Point3 b(a.x + d(rng), a.y + d(rng), a.z + d(rng));
  switch (kind(rng)) {
    case 0:  // both end points on grid corners
      a = {snap(a.x), snap(a.y), snap(a.z)};
      b = {snap(b.x), snap(b.y), snap(b.z)};
      break;
    case 1:  // end points on faces
      a.x = snap(a.x);
      b.y = snap(b.y);
      break;
    case 2:  // parallel to an axis
      b.y = a.y;
      b.z = a.z;
      break;
    case 3:  // in a grid plane, along an edge direction
      a.z = snap(a.z);
      b.z = a.z;
      a.y = snap(a.y);
      b.y = a.y;
      break;
    case 4:  // zero length
      b = a;
      break;
    case 5: {  // exact diagonal through cell corners
      a = {snap(a.x), snap(a.y), snap(a.z)};
      const int n = cells(rng);
      b = {a.x + n * leaf, a.y + n * leaf, a.z - n * leaf};
      break;
    }
    case 6: {  // diagonal in a plane through edges
      a = {snap(a.x), snap(a.y), a.z};
      const int n = cells(rng);
      b = {a.x + n * leaf, a.y - n * leaf, a.z};
      break;
    }
    default:
      break;
  }
  return {a, b};
}

void expect_matches_reference(const SemiOcTree& tree, unsigned seed, int count, double reach) {
  std::mt19937 rng(seed);
  const double span = 2.5 * tree.coarse_size();
  int checked = 0, hard = 0;
  for (int i = 0; i < count; ++i) {
    const auto [a, b] = random_segment(rng, tree.leaf_size(), span, reach);
    TraversalEnd end;
    const auto got = traverse_all(tree, a, b, &end);
    const auto want = testing::reference_traversal(tree, a, b);
    ASSERT_EQ(end, TraversalEnd::kReachedEnd);
    ASSERT_EQ(got.size(), want.size()) << "segment " << i << " (" << a.x << "," << a.y << "," << a.z
                                       << ")→(" << b.x << "," << b.y << "," << b.z << ")";
    for (std::size_t j = 0; j < got.size(); ++j) {
      ASSERT_EQ(got[j].key, want[j].key) << "segment " << i << " step " << j;
      ASSERT_EQ(got[j].level, want[j].level) << "segment " << i << " step " << j;
      ASSERT_EQ(got[j].has_node, want[j].has_node) << "segment " << i << " step " << j;
      ASSERT_EQ(got[j].t_enter, want[j].t_enter) << "segment " << i << " step " << j;
    }
    ++checked;
    hard += (a.x == std::round(a.x / tree.leaf_size()) * tree.leaf_size());
  }
  EXPECT_EQ(checked, count);
  EXPECT_GT(hard, count / 20);  // the hard cases were really exercised
}

int segment_count() {
  // 100 000 in the Release suite; sanitizer builds run a tenth.
  return std::getenv("SEMIOCTREE_SANITIZED") ? 10000 : 100000;
}

TEST(Traversal, MatchesBruteForceOnExactBinaryGrid) {
  // r = 0.25 is exact in binary, so "on a face" is exactly on a face.
  const auto tree = random_tree(0.25, 3, 1);
  expect_matches_reference(*tree, 11, segment_count() / 2, 2.5 * tree->coarse_size());
}

TEST(Traversal, MatchesBruteForceAtFiveCentimetres) {
  const auto tree = random_tree(0.05, 3, 2);
  expect_matches_reference(*tree, 12, segment_count() / 2, 2.5 * tree->coarse_size());
}

TEST(Traversal, HomogeneousGridIsTheSameCodePath) {
  const auto tree = random_tree(0.1, 0, 3);
  EXPECT_EQ(tree->leaf_level(), 0u);
  expect_matches_reference(*tree, 13, 3000, 1.0);
}

// Independent of the crossing formula: every visited octant touches the
// segment, consecutive octants are distinct, and every point sampled along the
// segment lies in a visited octant (located by OctoMap's coordToKey).
TEST(Traversal, GeometricallyCorrect) {
  const auto tree = random_tree(0.05, 4, 4);
  std::mt19937 rng(14);
  for (int i = 0; i < 2000; ++i) {
    const auto [a, b] = random_segment(rng, tree->leaf_size(), 2 * tree->coarse_size(), 2.0);
    std::set<std::tuple<unsigned, unsigned, unsigned, unsigned>> visited;
    std::vector<RayStep> steps;
    tree->traverse(a, b, [&](const RayStep& s) {
      steps.push_back(s);
      visited.emplace(s.key.k[0], s.key.k[1], s.key.k[2], s.level);
      return true;
    });
    ASSERT_EQ(visited.size(), steps.size()) << "an octant was visited twice";
    double prev_t = 0;
    for (const RayStep& s : steps) {
      ASSERT_GE(s.t_enter, prev_t);
      prev_t = s.t_enter;
      // Slab test of the segment against the octant box, with a small tolerance.
      const double size = tree->octant_size(s.level);
      double t0 = 0, t1 = 1;
      for (int ax = 0; ax < 3; ++ax) {
        const double lo = double(leaf_cell(s.key.k[ax])) * tree->leaf_size() - 1e-9;
        const double hi = lo + size + 2e-9;
        const double o = a[ax], d = b[ax] - a[ax];
        if (std::fabs(d) < 1e-15) {
          ASSERT_TRUE(o >= lo && o <= hi) << "octant off the segment";
          continue;
        }
        double ta = (lo - o) / d, tb = (hi - o) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      ASSERT_LE(t0, t1 + 1e-9) << "segment " << i << ": octant does not touch the segment";
    }
    for (int j = 0; j <= 200; ++j) {
      const double t = j / 200.0;
      const Point3 p(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z));
      octomap::OcTreeKey key;
      ASSERT_TRUE(tree->key_of(p, key));
      unsigned level = 0;
      octomap::OcTreeKey okey;
      if (auto o = tree->find_octant(key)) {
        level = o->level;
        okey = o->key;
      } else {
        const unsigned mask = ~((1u << tree->leaf_level()) - 1u);
        for (int ax = 0; ax < 3; ++ax) okey.k[ax] = octomap::key_type(key.k[ax] & mask);
      }
      // Sampled points can round into a neighbour when within an ulp of a face;
      // only accept a miss in that case.
      if (!visited.count({okey.k[0], okey.k[1], okey.k[2], level})) {
        double closest = 1;
        for (int ax = 0; ax < 3; ++ax) {
          const double u = p[ax] / tree->leaf_size();
          closest = std::min(closest, std::fabs(u - std::round(u)));
        }
        ASSERT_LT(closest, 1e-9) << "segment " << i << " sample " << j << " not visited";
      }
    }
  }
}

TEST(Traversal, UnsplitCoarseVoxelIsOneStep) {
  SemiOcTree tree(0.05, 0.8);
  for (int x = 0; x < 4; ++x) tree.create_coarse({x, 0, 0}, Label::kEmpty);
  int steps = 0;
  const auto end = tree.traverse({0.01, 0.4, 0.4}, {3.19, 0.4, 0.4}, [&](const RayStep& s) {
    EXPECT_EQ(s.level, 0u);
    EXPECT_EQ(s.label(), Label::kEmpty);
    ++steps;
    return true;
  });
  EXPECT_EQ(end, TraversalEnd::kReachedEnd);
  EXPECT_EQ(steps, 4);  // 64 leaf cells, 4 steps
}

TEST(Traversal, StopsEarlyOnRequest) {
  SemiOcTree tree(0.05, 0.8);
  for (int x = 0; x < 4; ++x) tree.create_coarse({x, 0, 0}, Label::kEmpty);
  octomap::OcTreeKey wall;
  ASSERT_TRUE(tree.key_of({1.62, 0.41, 0.41}, wall));
  tree.set_label(wall, tree.leaf_level(), Label::kOccupied);
  std::vector<Label> seen;
  const auto end = tree.traverse({0.01, 0.41, 0.41}, {3.19, 0.41, 0.41}, [&](const RayStep& s) {
    seen.push_back(s.label());
    return s.label() != Label::kOccupied;
  });
  EXPECT_EQ(end, TraversalEnd::kStopped);
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), Label::kOccupied);
  EXPECT_EQ(seen.front(), Label::kEmpty);
}

TEST(Traversal, ZeroLengthAndOutOfRange) {
  SemiOcTree tree(0.05, 0.8);
  tree.create_coarse({0, 0, 0}, Label::kEmpty);
  int steps = 0;
  EXPECT_EQ(
      tree.traverse({0.4, 0.4, 0.4}, {0.4, 0.4, 0.4}, [&](const RayStep&) { return ++steps; }),
      TraversalEnd::kReachedEnd);
  EXPECT_EQ(steps, 1);
  steps = 0;
  EXPECT_EQ(tree.traverse({0, 0, 0}, {1e9, 0, 0}, [&](const RayStep&) { return ++steps; }),
            TraversalEnd::kOutOfRange);
  EXPECT_EQ(tree.traverse({0, 0, 0}, {std::nan(""), 0, 0}, [&](const RayStep&) { return ++steps; }),
            TraversalEnd::kOutOfRange);
  EXPECT_EQ(steps, 0);
}

// On a map refined to the leaf everywhere, the cells we visit are OctoMap's
// computeRayKeys cells plus the end cell, except where OctoMap's float DDA
// decides a near-tie the other way. Random generic segments: ties are rare.
TEST(Traversal, AgreesWithOctoMapComputeRayKeys) {
  SemiOcTree tree(0.05, 0.05);  // k = 0: every octant is a leaf cell
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  octomap::KeyRay ray;
  int same = 0;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    const octomap::point3d a(float(u(rng)), float(u(rng)), float(u(rng)));
    const octomap::point3d b(float(u(rng)), float(u(rng)), float(u(rng)));
    ASSERT_TRUE(tree.computeRayKeys(a, b, ray));
    std::vector<octomap::OcTreeKey> theirs(ray.begin(), ray.end());
    theirs.push_back(tree.coordToKey(b));
    std::vector<octomap::OcTreeKey> ours;
    tree.traverse(Point3(a), Point3(b), [&](const RayStep& s) {
      ours.push_back(s.key);
      return true;
    });
    same += ours == theirs;
  }
  EXPECT_GE(same, n * 999 / 1000) << "of " << n << " segments";
}

TEST(Traversal, MarkedTraversalKeepsEveryMarkedOctantAndSkipsTheRest) {
  // traverse_marked must report exactly the octants with a marked label that
  // the full walk reports (same keys, levels, t), in order, and cover the rest
  // of the segment with summary steps of split octants that hold none.
  for (unsigned seed : {3u, 4u}) {
    auto tree = random_tree(0.05, 4, seed);
    const std::uint32_t mask = (1u << unsigned(Label::kOccupied)) | (1u << unsigned(Label::kDoor));
    tree->mark_subtrees(mask);
    std::mt19937 rng(seed);
    std::size_t full_steps = 0, marked_steps = 0, summaries = 0;
    for (int i = 0; i < segment_count() / 10; ++i) {
      const auto [a, b] = random_segment(rng, tree->leaf_size(), 2.5 * tree->coarse_size(), 3.0);
      std::vector<RefStep> want, got;
      double t_last = -1;
      tree->traverse(a, b, [&](const RayStep& s) {
        ++full_steps;
        if ((mask >> unsigned(s.label())) & 1u) want.push_back({s.key, s.level, true, s.t_enter});
        return true;
      });
      tree->traverse_marked(a, b, [&](const RayStep& s) {
        ++marked_steps;
        EXPECT_GE(s.t_enter, t_last);  // still in order along the segment
        t_last = s.t_enter;
        if (s.summary) {
          ++summaries;
          // A summary step is a split octant with nothing marked below.
          EXPECT_TRUE(s.node != nullptr && tree->nodeHasChildren(s.node));
          EXPECT_FALSE(s.node->has_flag(SemiOcTreeNode::kMarked));
          return true;
        }
        if ((mask >> unsigned(s.label())) & 1u) got.push_back({s.key, s.level, true, s.t_enter});
        return true;
      });
      ASSERT_EQ(got.size(), want.size()) << "segment " << i;
      for (std::size_t j = 0; j < got.size(); ++j) {
        ASSERT_EQ(got[j].key, want[j].key) << "segment " << i;
        ASSERT_EQ(got[j].level, want[j].level) << "segment " << i;
        ASSERT_EQ(got[j].t_enter, want[j].t_enter) << "segment " << i;
      }
    }
    EXPECT_GT(summaries, 0u);
    EXPECT_LT(marked_steps, full_steps);  // something was skipped
  }
}

TEST(Traversal, MarksStayValidWhenUnmarkedLeavesAreSplit) {
  auto tree = random_tree(0.05, 4, 9);
  tree->mark_subtrees(1u << unsigned(Label::kOccupied));
  // Split every unmarked non-occupied leaf once (what the occlusion study does).
  std::vector<Octant> leaves;
  tree->for_each_octant([&](const Octant& o) {
    if (o.level < tree->leaf_level() && o.label() != Label::kOccupied) leaves.push_back(o);
  });
  for (const Octant& o : leaves) tree->expandNode(const_cast<SemiOcTreeNode*>(o.node));
  // No new node carries the mark, and every marked node still holds an occupied leaf.
  std::size_t marked = 0;
  std::function<bool(const SemiOcTreeNode*)> holds = [&](const SemiOcTreeNode* n) {
    if (!tree->nodeHasChildren(n)) return n->label() == Label::kOccupied;
    bool any = false;
    for (unsigned i = 0; i < 8; ++i)
      if (tree->nodeChildExists(n, i)) any |= holds(tree->getNodeChild(n, i));
    EXPECT_EQ(any, n->has_flag(SemiOcTreeNode::kMarked));
    marked += any;
    return any;
  };
  tree->for_each_coarse([&](const CoarseIndex&, SemiOcTreeNode* n) {
    if (tree->nodeHasChildren(n)) holds(n);
  });
  EXPECT_GT(marked, 0u);
}

// The wedge from a point to a box: every marked leaf octant whose interior meets it is
// found, nothing else, on random trees; the geometric test itself agrees with the wedge
// sampled at many t.
TEST(Traversal, HullQueryFindsExactlyTheMarkedOctantsTheWedgeMeets) {
  const std::uint32_t marked_labels =
      (1u << unsigned(Label::kOccupied)) | (1u << unsigned(Label::kDoor));
  std::size_t found_total = 0, checked = 0;
  for (unsigned seed = 1; seed <= 3; ++seed)
    for (const unsigned k : {2u, 3u}) {
      auto tree = random_tree(0.1, k, seed);
      tree->mark_subtrees(marked_labels);
      std::vector<Octant> marked;
      tree->for_each_octant([&](const Octant& o) {
        if (marked_labels & (1u << unsigned(o.label()))) marked.push_back(o);
      });
      std::mt19937 rng(seed * 17 + k);
      const double span = 3 * tree->coarse_size();
      std::uniform_real_distribution<double> u(-span, span),
          uz(-tree->coarse_size(), 2 * tree->coarse_size());
      std::uniform_int_distribution<unsigned> level(0, k);
      for (int trial = 0; trial < 40; ++trial) {
        const Point3 apex(u(rng), u(rng), uz(rng));
        octomap::OcTreeKey key;
        ASSERT_TRUE(tree->key_of({u(rng), u(rng), uz(rng)}, key));
        const unsigned lvl = level(rng);
        const Octant box = tree->make_octant(key, lvl, nullptr);  // snaps the key
        const double r = tree->leaf_size();
        const double a[3] = {apex.x / r, apex.y / r, apex.z / r};
        double lo[3], hi[3];
        for (int i = 0; i < 3; ++i) {
          lo[i] = double(box.key.k[i]) - double(kKeyOrigin);
          hi[i] = lo[i] + box.size / r;
        }
        std::set<std::uint64_t> found;
        tree->for_each_marked_in_hull(apex, box.key, lvl, [&](const Octant& o) {
          EXPECT_TRUE(found.insert(pack_octant_key(o.key, o.level)).second) << "visited twice";
          return true;
        });
        std::set<std::uint64_t> expected;
        for (const Octant& o : marked) {
          double nlo[3], nhi[3];
          for (int i = 0; i < 3; ++i) {
            nlo[i] = double(o.key.k[i]) - double(kKeyOrigin);
            nhi[i] = nlo[i] + o.size / r;
          }
          const bool meets = detail::hull_meets_box(a, lo, hi, nlo, nhi);
          if (meets) expected.insert(pack_octant_key(o.key, o.level));
          // Sampled: a t at which the wedge's box overlaps the octant with room to spare
          // means the exact test must say it meets.
          bool sampled = false;
          for (int j = 1; j <= 400 && !sampled; ++j) {
            const double t = j / 400.0;
            bool all = true;
            for (int i = 0; i < 3 && all; ++i)
              all = a[i] + t * (lo[i] - a[i]) < nhi[i] - 1e-6 &&
                    a[i] + t * (hi[i] - a[i]) > nlo[i] + 1e-6;
            sampled = all;
          }
          if (sampled) {
            EXPECT_TRUE(meets);
          }
          ++checked;
        }
        EXPECT_EQ(found, expected) << "seed " << seed << " k " << k << " trial " << trial;
        found_total += found.size();
      }
    }
  EXPECT_GT(found_total, 100u);
  EXPECT_GT(checked, 10000u);
}

// A box standing on an occupied floor only touches it: the wedge from above does not
// meet the floor, but meets an occupied leaf between the point and the box.
TEST(Traversal, HullQuerySkipsOctantsThatOnlyTouchTheWedge) {
  SemiOcTree tree(0.1, 0.8);
  octomap::OcTreeKey k;
  const auto occupy = [&](const Point3& p) {
    ASSERT_TRUE(tree.key_of(p, k));
    tree.set_label(k, tree.leaf_level(), Label::kOccupied);
  };
  for (double x = 0.05; x < 3.2; x += 0.1)
    for (double y = 0.05; y < 1.6; y += 0.1) occupy({x, y, 0.05});  // floor, z ∈ [0, 0.1)
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 3; ++z) tree.create_coarse({x, y, z});
  tree.mark_subtrees(1u << unsigned(Label::kOccupied));
  ASSERT_TRUE(tree.key_of({2.45, 0.85, 0.15}, k));  // the leaf on the floor at x 2.4–2.5
  const Point3 apex(0.53, 0.87, 1.41);
  std::size_t n = 0;
  tree.for_each_marked_in_hull(apex, k, tree.leaf_level(), [&](const Octant&) {
    ++n;
    return true;
  });
  EXPECT_EQ(n, 0u);
  occupy({1.45, 0.85, 0.75});  // on the way: z of the wedge there ≈ 0.75
  tree.mark_subtrees(1u << unsigned(Label::kOccupied));
  std::vector<Point3> met;
  tree.for_each_marked_in_hull(apex, k, tree.leaf_level(), [&](const Octant& o) {
    met.push_back(o.center);
    return true;
  });
  ASSERT_EQ(met.size(), 1u);
  EXPECT_NEAR(met[0].x, 1.45, 1e-9);
  EXPECT_NEAR(met[0].z, 0.75, 1e-9);
}

}  // namespace
}  // namespace semioctree
