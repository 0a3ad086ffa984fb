// Next-Best-View scores (paper Eq 3–4) and the stop percentage (Eq 5): scores of
// hand-placed scanner positions against hand-computed Eq 3 sums (direct, through n
// occluded octants, blocked, through a door), the volume weights of method 1, the
// level-ℓ reading of method 2, method 3's frontier faces, agreement with a
// brute-force reference and with the same map stored as a homogeneous grid, the walls'
// shadows (every line they settle is blocked; scores on a floor of rooms unchanged),
// thread-count independence, Eq 5 by hand, both counted inside a room, and the choice
// weighed by the path (travel weight).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "semioctree/nbv.h"
#include "semioctree/occlusion.h"
#include "src/nbv/wall_shadows.h"
#include "support/nbv_maps.h"
#include "support/ray_reference.h"
#include "support/sanitized.h"

namespace semioctree {
namespace {

using testing::kLeaf;
using testing::Map;
using testing::open_limits;
using testing::score_at;

// --- Eq 3–4 by hand -------------------------------------------------------------------

// Scanner at a leaf centre; targets on axis-parallel lines through it, so that
// each line crosses only what is placed on it.
struct LinesMap : Map {
  const Point3 a{0.425, 1.625, 1.225};
  LinesMap() : Map(7, 4, 3) {
    // +x: T1 direct (0.7 m), T2 behind T1, T3 behind T1 and T2, an occupied
    // leaf, T4 behind it.
    leaf(1.125, 1.625, 1.225, Label::kOccluded);
    leaf(1.525, 1.625, 1.225, Label::kOccluded);
    leaf(2.025, 1.625, 1.225, Label::kOccluded);
    leaf(2.525, 1.625, 1.225, Label::kOccupied);
    leaf(3.025, 1.625, 1.225, Label::kOccluded);
    // +y: a door leaf, T5 behind it.
    leaf(0.425, 2.025, 1.225, Label::kDoor);
    leaf(0.425, 2.525, 1.225, Label::kOccluded);
    // −y: an `out` leaf (transparent), T6 behind it (1.1 m).
    leaf(0.425, 1.025, 1.225, Label::kOut);
    leaf(0.425, 0.525, 1.225, Label::kOccluded);
    // +z: T7, an octant of level 3 (0.1 m, 8 leaves), direct (0.83 m).
    set(0.425, 1.625, 2.025, 3, Label::kOccluded);
    // −z: T8 straight below (elevation −90°, 1.0 m).
    leaf(0.425, 1.625, 0.225, Label::kOccluded);
    // Diagonal (+x +y): unknown space, T9 behind it.
    leaf(0.825, 2.025, 1.225, Label::kUnknown);
    leaf(1.225, 2.425, 1.225, Label::kOccluded);
  }
};

TEST(Nbv, ScoreEqualsHandComputedSum) {
  LinesMap m;
  double m2_through_door = 0;
  NbvParams p;  // the scanner's default limits: 0.6–60 m, elevation −60°…90°
  // T1 1, T2 1/2, T3 1/3, T4 0 (occupied), T5 0 (door), T6 1 (through out),
  // T7 8 (level 3), T8 0 (below −60°), T9 0 (unknown).
  const double expected = 1 + 1.0 / 2 + 1.0 / 3 + 1 + 8;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected, 1e-12);
  // Looking straight down is allowed: T8 is seen directly.
  p.limits.elevation_min_deg = -90;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected + 1, 1e-12);
  // Seeing through doors (a doorway scan): T5 is seen behind the door leaf, directly.
  p = NbvParams{};
  p.see_through_doors = true;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected + 1, 1e-12);
  p.method = 2;
  m2_through_door = score_at(m.t, m.a, p);
  // Range limit 1 m: only T1 (0.7 m) and T7 (0.83 m) remain.
  p = NbvParams{};
  p.limits.max_range = 1.0;
  EXPECT_NEAR(score_at(m.t, m.a, p), 1 + 8, 1e-12);
  // Minimum range 0.75 m drops T1: T2 and T3 still cross it.
  p = NbvParams{};
  p.limits.min_range = 0.75;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected - 1, 1e-12);
  // Without T1, T2 is seen directly and T3 through one occluded octant.
  m.leaf(1.125, 1.625, 1.225, Label::kEmpty);
  EXPECT_NEAR(score_at(m.t, m.a, NbvParams{}), 1 + 1.0 / 2 + 1 + 8, 1e-12);
  // Method 1 and method 2 at the leaf agree on leaf targets.
  LinesMap leafy;
  leafy.set(0.425, 1.625, 2.025, 3, Label::kEmpty);  // no octant above the leaf
  NbvParams m2;
  m2.method = 2;
  EXPECT_NEAR(score_at(leafy.t, leafy.a, m2), 1 + 1.0 / 2 + 1.0 / 3 + 1, 1e-12);
  // Method 2 sees T5 through the door as well; T7's 8 leaf cells count 4 direct and 4
  // behind them (1/2 each).
  EXPECT_NEAR(m2_through_door, 1 + 1.0 / 2 + 1.0 / 3 + 1 + (4 + 4.0 / 2) + 1, 1e-12);
}

TEST(Nbv, Method1WeightsAnOctantEightTimesItsChild) {
  std::vector<double> score;
  for (unsigned level = 0; level <= 4; ++level) {
    Map m(7, 4, 3);
    m.set(3.0, 2.0, 1.2, level,
          Label::kOccluded);  // coarse voxel [2.4, 3.2) × [1.6, 2.4) × [0.8, 1.6)
    score.push_back(score_at(m.t, {0.425, 1.625, 1.225}, NbvParams{}));
  }
  for (unsigned level = 0; level <= 4; ++level)
    EXPECT_DOUBLE_EQ(score[level], std::pow(8.0, 4 - level)) << "level " << level;
  for (unsigned level = 0; level < 4; ++level) EXPECT_DOUBLE_EQ(score[level], 8 * score[level + 1]);
}

// An occluded octant of level 3 (0.1 m) straight ahead of the scanner, which
// looks at it along the line through its centre.
struct OctantAheadMap : Map {
  const Point3 a{0.45, 1.65, 1.25};
  OctantAheadMap() : Map(7, 4, 3) { set(1.45, 1.65, 1.25, 3, Label::kOccluded); }
};

TEST(Nbv, Method2CountsAtTheChosenLevel) {
  OctantAheadMap m;
  // Method 1: one target of weight 8.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(1)), 8.0);
  // Level 4 (leaf, the default): 8 leaf targets; the 4 near ones are seen
  // directly, each far one through the near leaf in front of it: 4 + 4/2.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2)), 6.0);
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 4)), 6.0);
  // Level 3: the octant itself, weight 1.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 3)), 1.0);
  // Level 2: its 0.2 m cell is only 1/8 occluded: no target.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 0.0);

  // A bigger occluded octant (level 2) in front of it.
  m.set(0.9, 1.7, 1.3, 2, Label::kOccluded);  // [0.8, 1.0) × [1.6, 1.8) × [1.2, 1.4)
  // Method 1: 64 (direct) + 8 through one octant.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(1)), 64 + 8.0 / 2);
  // Level 3: the front octant is 8 cells (near half direct, far half through
  // one cell: 4 + 4/2); the line to the back one crosses two of its cells.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 3)), 6 + 1.0 / 3);
  // Level 2: the front octant is one target; the back cell is no target.
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 1.0);
}

TEST(Nbv, Method2MergesFinerOctantsIntoCellsOfTheLevel) {
  OctantAheadMap m;
  // Half of the 0.2 m cell [1.4, 1.6) × [1.6, 1.8) × [1.2, 1.4) occluded: a target.
  m.set(1.55, 1.65, 1.25, 3, Label::kOccluded);
  m.set(1.45, 1.75, 1.25, 3, Label::kOccluded);
  m.set(1.45, 1.65, 1.35, 3, Label::kOccluded);
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 1.0);
  // Seen through the level-2 occluded octant in front: one level-2 cell crossed.
  m.set(0.9, 1.7, 1.3, 2, Label::kOccluded);
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 1.0 + 1.0 / 2);
  // Three of eight: no longer a target.
  m.set(1.45, 1.65, 1.35, 3, Label::kEmpty);
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 1.0);
  // Half again, but holding an occupied leaf: no target.
  m.set(1.45, 1.65, 1.35, 3, Label::kOccluded);
  m.leaf(1.575, 1.775, 1.375, Label::kOccupied);
  EXPECT_DOUBLE_EQ(score_at(m.t, m.a, open_limits(2, 2)), 1.0);
}

// Method 3: the area of the free faces of occluded octants that face the
// scanner and are not blocked, whatever occluded space lies on the way.
TEST(Nbv, Method3CountsTheFrontierFacesFacingTheScanner) {
  Map m(4, 2, 2);
  const double face = kLeaf * kLeaf;
  m.leaf(1.125, 0.425, 0.425, Label::kOccluded);
  const NbvParams p = open_limits(3);
  // In line along x: only the −x face faces the scanner.
  EXPECT_NEAR(score_at(m.t, {0.425, 0.425, 0.425}, p), face, 1e-12);
  // Off all three axes: the −x, +y and +z faces.
  const Point3 high{0.425, 1.225, 1.225};
  EXPECT_NEAR(score_at(m.t, high, p), 3 * face, 1e-12);
  // A second occluded leaf at +x: the face the two share is not on free space.
  m.leaf(1.175, 0.425, 0.425, Label::kOccluded);
  EXPECT_NEAR(score_at(m.t, {0.425, 0.425, 0.425}, p), face, 1e-12);
  EXPECT_NEAR(score_at(m.t, high, p), (3 + 2) * face, 1e-12);
  // From beyond the pair along +x: only the second leaf's +x face.
  EXPECT_NEAR(score_at(m.t, {2.425, 0.425, 0.425}, p), face, 1e-12);
  // An occupied leaf on the line blocks it.
  m.leaf(0.775, 0.425, 0.425, Label::kOccupied);
  EXPECT_NEAR(score_at(m.t, {0.425, 0.425, 0.425}, p), 0.0, 1e-12);
  // From straight below the first leaf (between the planes of its x faces),
  // the −z faces of both leaves face the scanner, no x face of the first does.
  EXPECT_NEAR(score_at(m.t, {1.125, 0.425, 0.025}, p), 2 * face, 1e-12);
}

TEST(Nbv, RejectsBadMethodOrLevel) {
  Map m(1, 1, 1);
  NbvParams p;
  p.method = 4;
  EXPECT_THROW(score_at(m.t, {0.4, 0.4, 0.4}, p), std::invalid_argument);
  p.method = 2;
  p.level = 5;  // finer than the leaf (level 4)
  EXPECT_THROW(score_at(m.t, {0.4, 0.4, 0.4}, p), std::invalid_argument);
}

// --- against references ------------------------------------------------------------------

// A 2.4 × 2.4 × 1.6 m block with random occluded octants of every level,
// occupied leaves, doors, windows, out and unknown octants. (Built in place:
// OctoMap's copy constructor drops the custom node data.)
struct RandomMap : Map {
  explicit RandomMap(unsigned seed) : Map(3, 3, 2) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(0.0, 2.4), uz(0.0, 1.6);
    std::uniform_int_distribution<unsigned> level(0, 4);
    for (int i = 0; i < 40; ++i) set(ux(rng), ux(rng), uz(rng), level(rng), Label::kOccluded);
    for (int i = 0; i < 150; ++i) leaf(ux(rng), ux(rng), uz(rng), Label::kOccupied);
    for (int i = 0; i < 6; ++i) leaf(ux(rng), ux(rng), uz(rng), Label::kDoor);
    for (int i = 0; i < 6; ++i) leaf(ux(rng), ux(rng), uz(rng), Label::kWindow);
    for (int i = 0; i < 4; ++i) set(ux(rng), ux(rng), uz(rng), 2, Label::kOut);
    for (int i = 0; i < 2; ++i) set(ux(rng), ux(rng), uz(rng), 3, Label::kUnknown);
  }
};

// Random positions; with `tree`, only positions in empty octants.
std::vector<Point3> random_positions(unsigned seed, int count, const SemiOcTree* tree = nullptr) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.05, 2.35), uz(0.05, 1.55);
  std::vector<Point3> out;
  while (int(out.size()) < count) {
    const Point3 p(ux(rng), ux(rng), uz(rng));
    if (!tree || tree->find_octant(p)->label() == Label::kEmpty) out.push_back(p);
  }
  return out;
}

// The segment a→b by the brute-force traversal: nullopt when blocked (an occupied,
// unknown, window or, unless `doors_pass`, door octant other than the scanner's own),
// else the number of occluded octants crossed between the two ends.
std::optional<int> reference_segment(const SemiOcTree& t, const Point3& a, const Point3& b,
                                     bool doors_pass = false) {
  const auto steps = testing::reference_traversal(t, a, b);
  int n = 0;
  for (std::size_t j = 1; j < steps.size(); ++j) {
    const auto oc = t.find_octant(steps[j].key);
    const Label l = steps[j].has_node && oc ? oc->label() : Label::kUnknown;
    if (l == Label::kOccupied || l == Label::kUnknown || l == Label::kWindow ||
        (l == Label::kDoor && !doors_pass))
      return std::nullopt;
    if (l == Label::kOccluded && j + 1 < steps.size()) ++n;
  }
  return n;
}

// The line a→b: as reference_segment, and nullopt too when b lies outside the scanner's
// limits.
std::optional<int> reference_line(const SemiOcTree& t, const Point3& a, const Point3& b,
                                  const ScannerView& lim) {
  const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (range < lim.min_range || range > lim.max_range || range == 0) return std::nullopt;
  const double elevation = std::asin(dz / range) * 180 / M_PI;
  if (elevation < lim.elevation_min_deg || elevation > lim.elevation_max_deg) return std::nullopt;
  return reference_segment(t, a, b);
}

// Eq 3 (method 1) with the brute-force traversal of tests/support: no cache,
// no hierarchy; the scanner's own octant neither blocks nor counts, the
// target's own octant does not count.
double reference_score(const SemiOcTree& t, const Point3& a, const ScannerView& lim) {
  double sum = 0;
  t.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    if (const auto n = reference_line(t, a, o.center, lim))
      sum += double(std::uint64_t(1) << (3 * (t.leaf_level() - o.level))) / (1.0 + *n);
  });
  return sum;
}

// Method 3 by brute force: per occluded octant, the free faces (the octant a quarter
// leaf beyond the face's centre is empty, scan or nbv) that have `a` beyond their plane,
// each worth the face's area, when the line to the centre is not blocked.
double reference_score_method3(const SemiOcTree& t, const Point3& a, const ScannerView& lim) {
  double sum = 0;
  t.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    const Point3& b = o.center;
    const double half = 0.5 * o.size;
    int faces = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (double side : {-1.0, 1.0}) {
        if ((a[axis] - b[axis]) * side <= half) continue;  // the face does not face a
        Point3 q = b;
        (axis == 0 ? q.x : axis == 1 ? q.y : q.z) += side * (half + 0.25 * t.leaf_size());
        const auto nb = t.find_octant(q);
        if (nb && (nb->label() == Label::kEmpty || nb->label() == Label::kScan ||
                   nb->label() == Label::kNbv))
          ++faces;
      }
    if (faces > 0 && reference_line(t, a, b, lim)) sum += faces * o.size * o.size;
  });
  return sum;
}

TEST(Nbv, Method3ScoresMatchBruteForceReference) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const RandomMap m(seed);
    const auto positions = random_positions(200 + seed, 6);
    const NbvParams p = open_limits(3);
    ScoringStats st;
    const auto scores = score_positions(m.t, positions, p, &st);
    EXPECT_GT(st.visible, 0u);
    EXPECT_GT(st.blocked_by_cache, 0u);
    double total = 0;
    for (std::size_t i = 0; i < positions.size(); ++i) {
      EXPECT_NEAR(scores[i], reference_score_method3(m.t, positions[i], p.limits),
                  1e-9 * std::max(1.0, scores[i]))
          << "seed " << seed << " position " << i;
      total += scores[i];
    }
    EXPECT_GT(total, 0.0);
  }
}

TEST(Nbv, ScoresMatchBruteForceReference) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const RandomMap m(seed);
    const auto positions = random_positions(100 + seed, 6);
    for (const NbvParams& p : {open_limits(1), NbvParams{}}) {
      ScoringStats st;
      const auto scores = score_positions(m.t, positions, p, &st);
      EXPECT_GT(st.visible, 0u);
      EXPECT_GT(st.blocked_by_cache, 0u);  // the shortcut is exercised, and must not matter
      for (std::size_t i = 0; i < positions.size(); ++i)
        EXPECT_NEAR(scores[i], reference_score(m.t, positions[i], p.limits),
                    1e-9 * std::max(1.0, scores[i]))
            << "seed " << seed << " position " << i;
    }
  }
}

// --- the walls' shadows ---------------------------------------------------------------

// Rooms of a floor, 4.8 × 4.8 × 2.4 m, with what the shadows' proof must get right: full-
// height walls one leaf thick; a thick wall whose core is occluded; a door (door octants
// under an occupied lintel) and a window in a wall; a wall built as a diagonal staircase
// of leaves that only touch at their edges; a wall below scanner height; a tall cupboard
// (occupied shell, occluded inside); unknown blocks; occluded octants of every level.
struct FloorMap : Map {
  explicit FloorMap(unsigned seed) : Map(6, 6, 3) {
    walls(4.8, 4.8, 2.4);
    leaves({2.4, 0, 0}, {2.45, 1.0, 2.4}, Label::kOccupied);  // the inner wall, along y
    leaves({2.4, 1.0, 0}, {2.45, 1.9, 2.0}, Label::kDoor);
    leaves({2.4, 1.0, 2.0}, {2.45, 1.9, 2.4}, Label::kOccupied);
    leaves({2.4, 1.9, 0}, {2.45, 4.8, 2.4}, Label::kOccupied);
    leaves({2.4, 3.5, 1.0}, {2.45, 4.0, 1.8}, Label::kWindow);
    leaves({0, 3.2, 0}, {2.4, 3.25, 2.4}, Label::kOccupied);  // the thick wall, along x
    leaves({0, 3.25, 0}, {2.4, 3.3, 2.4}, Label::kOccluded);
    leaves({0, 3.3, 0}, {2.4, 3.35, 2.4}, Label::kOccupied);
    for (int i = 0; i < 24; ++i)  // the staircase
      leaves({3.0 + i * kLeaf, 0.5 + i * kLeaf, 0}, {3.05 + i * kLeaf, 0.55 + i * kLeaf, 2.4},
             Label::kOccupied);
    leaves({3.5, 2.5, 0}, {3.55, 4.0, 1.0}, Label::kOccupied);  // the low wall
    leaves({0.5, 1.0, 0}, {1.1, 1.6, 2.0}, Label::kOccupied);   // the cupboard
    leaves({0.55, 1.05, 0.05}, {1.05, 1.55, 1.95}, Label::kOccluded);
    set(4.2, 4.2, 2.0, 2, Label::kUnknown);
    set(0.4, 4.4, 0.4, 2, Label::kUnknown);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(0.05, 4.75), uz(0.05, 2.35);
    std::uniform_int_distribution<unsigned> level(1, 4);
    for (int i = 0; i < 60; ++i) {
      const Point3 p(ux(rng), ux(rng), uz(rng));
      const unsigned l = level(rng);
      if (t.find_octant(p)->label() == Label::kEmpty) set(p.x, p.y, p.z, l, Label::kOccluded);
    }
  }
};

// What the shadows prove blocked is blocked, whatever the scanner's height within the
// run of a wall, doors shut or open; and they prove much of what the walls hide.
// (A sanitized run, several times slower, checks one floor from fewer positions.)
const bool kSanitized = testing::sanitized();

TEST(Nbv, WallShadowsProveOnlyBlockedLines) {
  for (unsigned seed : {1u, 2u}) {
    if (kSanitized && seed > 1) break;
    const FloorMap m(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(0.05, 4.75), uz(0.05, 2.35), uh(0.9, 1.7);
    std::vector<Point3> positions, ends;
    while (positions.size() < (kSanitized ? 8u : 24u)) {
      const Point3 p(ux(rng), ux(rng), uh(rng));
      if (m.t.find_octant(p)->label() == Label::kEmpty) positions.push_back(p);
    }
    positions.push_back({2.425, 1.45, 1.3});  // in the door
    for (int i = 0; i < (kSanitized ? 200 : 600); ++i) ends.push_back({ux(rng), ux(rng), uz(rng)});
    std::size_t occluded = 0;  // every 7th occluded octant's centre (21st sanitized)
    m.t.for_each_octant([&](const Octant& o) {
      if (o.label() == Label::kOccluded && occluded++ % (kSanitized ? 21 : 7) == 0)
        ends.push_back(o.center);
    });
    for (const bool doors_pass : {false, true}) {
      const nbv_detail::BlockingColumns columns(m.t, doors_pass, 1.3, {0, 0, 0}, {4.8, 4.8, 0}, 0.0,
                                                2.4);
      nbv_detail::WallShadows shadows(columns);
      std::size_t blocked = 0, proven = 0;
      for (const Point3& a : positions) {
        const Label own = m.t.find_octant(a)->label();
        shadows.reset(a, own == Label::kDoor && !doors_pass);
        for (const Point3& b : ends) {
          const bool is_blocked = !reference_segment(m.t, a, b, doors_pass);
          const bool hides = shadows.hides(b);
          blocked += is_blocked;
          proven += hides;
          EXPECT_TRUE(!hides || is_blocked)
              << "seed " << seed << " doors pass " << doors_pass << " from " << a.x << " " << a.y
              << " " << a.z << " to " << b.x << " " << b.y << " " << b.z;
        }
      }
      EXPECT_GT(proven, blocked / 3) << "seed " << seed << ": " << proven << " of " << blocked;
    }
  }
}

// Scores on the floor, the shadows taking most blocked lines, equal the brute force's.
TEST(Nbv, ScoresOnAFloorMatchBruteForceReference) {
  const FloorMap m(3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.05, 4.75), uh(0.9, 1.7);
  std::vector<Point3> positions;
  while (positions.size() < (kSanitized ? 2u : 8u)) {
    const Point3 p(ux(rng), ux(rng), uh(rng));
    if (m.t.find_octant(p)->label() == Label::kEmpty) positions.push_back(p);
  }
  for (const NbvParams& p : {open_limits(1), NbvParams{}}) {
    ScoringStats st;
    const auto scores = score_positions(m.t, positions, p, &st);
    EXPECT_GT(st.visible, 0u);
    EXPECT_GT(st.blocked_by_walls, st.segments / 10);
    for (std::size_t i = 0; i < positions.size(); ++i)
      EXPECT_NEAR(scores[i], reference_score(m.t, positions[i], p.limits),
                  1e-9 * std::max(1.0, scores[i]))
          << "position " << i;
  }
}

TEST(Nbv, Method2AtTheLeafEqualsTheHomogeneousGrid) {
  for (unsigned seed : {4u, 5u}) {
    const RandomMap m(seed);
    // The same labels, one octant per leaf cell (coarse = leaf).
    SemiOcTree homo(kLeaf, kLeaf);
    for (double x = kLeaf / 2; x < 2.4; x += kLeaf)
      for (double y = kLeaf / 2; y < 2.4; y += kLeaf)
        for (double z = kLeaf / 2; z < 1.6; z += kLeaf) {
          octomap::OcTreeKey k;
          ASSERT_TRUE(homo.key_of({x, y, z}, k));
          homo.set_label(k, 0, m.t.find_octant(Point3(x, y, z))->label());
        }
    // (In empty octants: a scanner inside a big octant ignores all of it, one
    // inside a leaf only that leaf.)
    const auto positions = random_positions(200 + seed, 5, &m.t);
    ScoringStats semi_st, homo_st;
    const auto semi = score_positions(m.t, positions, open_limits(2), &semi_st);
    const auto homo1 = score_positions(homo, positions, open_limits(1), &homo_st);
    const auto homo2 = score_positions(homo, positions, open_limits(2));
    EXPECT_EQ(semi_st.targets, homo_st.targets);
    EXPECT_EQ(homo1, homo2);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      EXPECT_GT(semi[i], 0.0);
      EXPECT_NEAR(semi[i], homo1[i], 1e-9 * semi[i]) << "seed " << seed << " position " << i;
    }
  }
}

TEST(Nbv, SameResultForAnyThreadCount) {
  const RandomMap m(7);
  const auto positions = random_positions(8, 12);
  for (const NbvParams& base : {NbvParams{}, open_limits(2), open_limits(2, 3)}) {
    std::vector<double> first;
    for (unsigned threads : {1u, 2u, 3u}) {
      NbvParams p = base;
      p.threads = threads;
      const auto s = score_positions(m.t, positions, p);
      if (threads == 1)
        first = s;
      else
        EXPECT_EQ(s, first) << threads << " threads, method " << p.method;
    }
    EXPECT_GT(*std::max_element(first.begin(), first.end()), 0.0);
  }
}

// --- the stop percentage (Eq 5) and the room ------------------------------------------------

TEST(Nbv, StopPercentageEqualsHandComputation) {
  Map m(5, 5, 3);  // 4 × 4 × 2.4 m = 38.4 m³, every octant labelled
  const Point3 nbv(0.5, 0.6, 1.0);
  m.set(1.0, 2.6, 1.0, 1, Label::kOccluded);  // V1 [0.8, 1.2) × [2.4, 2.8): direct
  m.set(1.0, 3.0, 1.0, 1, Label::kOccluded);  // V2 behind V1: semi-direct, counts 1/(1+1)
  m.set(3.4, 0.6, 1.0, 1, Label::kOccluded);  // H behind an occupied wall
  m.leaves({2.0, 0, 0}, {2.05, 1.6, 2.4}, Label::kOccupied);
  m.set(0.6, 0.6, 2.2, 1, Label::kOccluded);  // D above, seen through a door
  m.leaves({0.5, 0.55, 1.55}, {0.65, 0.7, 1.7}, Label::kDoor);
  m.set(3.4, 3.4, 2.2, 1, Label::kOut);
  const double v = 0.4 * 0.4 * 0.4;
  EXPECT_NEAR(stop_percentage(m.t, nbv), 100.0 * 1.5 * v / 38.4, 1e-9);
  EXPECT_EQ(stop_percentage(m.t, nbv, {}, 1), stop_percentage(m.t, nbv, {}, 3));
  // The scanner's limits apply: V2 (2.4 m away) out of range.
  ScannerView near;
  near.max_range = 2.2;
  EXPECT_NEAR(stop_percentage(m.t, nbv, near), 100.0 * v / 38.4, 1e-9);
  // Unknown space is not part of the room's volume.
  m.set(3.4, 3.4, 1.4, 1, Label::kUnknown);
  EXPECT_NEAR(stop_percentage(m.t, nbv), 100.0 * 1.5 * v / (38.4 - v), 1e-9);
}

// With a room, targets and both volumes of Eq 5 are counted inside it; an
// octant straddling its face counts its part inside.
TEST(Nbv, RoomLimitsTheTargetsAndTheStopPercentage) {
  Map m(5, 5, 3);  // 4 × 4 × 2.4 m
  const Point3 nbv(0.5, 0.6, 1.0);
  m.set(1.0, 2.6, 1.0, 1, Label::kOccluded);  // V1 [0.8, 1.2) × [2.4, 2.8): direct
  m.set(1.0, 3.0, 1.0, 1, Label::kOccluded);  // V2 behind V1: 1/(1+1)
  m.set(3.4, 2.6, 1.0, 1, Label::kOccluded);  // F, direct but beyond x = 2 m
  const double v = 0.4 * 0.4 * 0.4;
  EXPECT_NEAR(stop_percentage(m.t, nbv), 100.0 * 2.5 * v / 38.4, 1e-9);
  NbvParams p;  // the scanner's default limits, as stop_percentage's
  const double leaves = v / std::pow(kLeaf, 3);
  EXPECT_NEAR(score_at(m.t, nbv, p), 2.5 * leaves, 1e-6);

  RoomBox room{{0, 0, 0}, {2.0, 4.0, 2.4}};  // F outside
  EXPECT_NEAR(stop_percentage(m.t, nbv, {}, 0, room), 100.0 * 1.5 * v / (2.0 * 4.0 * 2.4), 1e-9);
  p.room = room;
  EXPECT_NEAR(score_at(m.t, nbv, p), 1.5 * leaves, 1e-6);

  room.max.x = 1.0;  // through the middle of V1 and V2: half of each counts
  EXPECT_NEAR(stop_percentage(m.t, nbv, {}, 0, room), 100.0 * 0.75 * v / (1.0 * 4.0 * 2.4), 1e-9);
  p.room = room;
  EXPECT_NEAR(score_at(m.t, nbv, p), 0.75 * leaves, 1e-6);
  const NbvResult r = next_best_view(m.t, RobotGeometry{}, nbv, {}, p);
  ASSERT_TRUE(r.best);
  EXPECT_NEAR(r.stop_percent, stop_percentage(m.t, r.best->position, p.limits, 0, room), 1e-12);
}

// --- The travel weight ------------------------------------------------------------------

// A 4.8 × 4.8 m room with two occluded targets of 64 leaves, one by the east wall and one
// by the north wall. With a range of 2.5 m, a candidate at (3.6, 2.4) sees both and one
// at (1.2, 2.4) the north one only; their paths are set by hand.
struct TwoTargets : Map {
  TwoTargets() : Map(6, 6, 3) {
    walls(4.8, 4.8, 2.4);
    set(4.4, 2.4, 1.0, 2, Label::kOccluded);
    set(2.0, 4.0, 1.0, 2, Label::kOccluded);
  }
};

NbvParams short_range() {
  NbvParams p;
  p.limits.min_range = 0.3;
  p.limits.max_range = 2.5;
  p.limits.elevation_min_deg = -60;
  p.limits.elevation_max_deg = 60;
  return p;
}

NbvCandidate at(double x, double y, double path_m) {
  NbvCandidate c;
  c.position = Point3(x, y, 1.2);
  c.path_m = path_m;
  return c;
}

TEST(Nbv, TheChoiceWeighsTheScoreByTheTravelWeight) {
  TwoTargets room;
  NbvParams p = short_range();
  // Near the target (higher score) but far by path, and farther from it but near by path.
  const std::vector<NbvCandidate> two = {at(3.6, 2.4, 10.0), at(1.2, 2.4, 1.0)};
  const NbvResult plain = best_view_among(room.t, two, p);
  ASSERT_TRUE(plain.best);
  ASSERT_GT(plain.candidates[0].score, plain.candidates[1].score);
  ASSERT_GT(plain.candidates[1].score, 0);
  EXPECT_EQ(plain.best->position.x, 3.6);
  EXPECT_EQ(plain.candidates[0].value, plain.candidates[0].score);  // unweighed
  const double far_eq5 = plain.stop_percent;

  p.travel_weight = 1.0;  // e^-10 against e^-1
  const NbvResult weighed = best_view_among(room.t, two, p);
  ASSERT_TRUE(weighed.best);
  EXPECT_EQ(weighed.best->position.x, 1.2);
  for (const NbvCandidate& c : weighed.candidates)
    EXPECT_DOUBLE_EQ(c.value, c.score * std::exp(-c.path_m));
  // The far candidate would still see more: it keeps the survey going.
  EXPECT_DOUBLE_EQ(weighed.stop_percent, far_eq5);
  EXPECT_GT(far_eq5, stop_percentage(room.t, weighed.best->position, p.limits));
  // A small weight leaves the choice to the score.
  p.travel_weight = 0.01;
  const NbvResult light = best_view_among(room.t, two, p);
  ASSERT_TRUE(light.best);
  EXPECT_EQ(light.best->position.x, 3.6);
  EXPECT_DOUBLE_EQ(light.stop_percent, far_eq5);
  p.travel_weight = -1;
  EXPECT_THROW(best_view_among(room.t, two, p), std::invalid_argument);
}

// Eq 5 of a method-1 NBV with doors blocking is taken from its score, not traced again:
// in a room with a partition, a door, a table and occluded space of several sizes, every
// candidate's score is in proportion to Eq 5 traced from it (the blocker cache, the
// memo of blockers across candidates and the walls' shadows only prove blocks), and
// with doors passing, Eq 5 still counts doors as blocking.
TEST(Nbv, TheStopPercentageTakenFromTheScoreIsEq5TracedFromTheCandidate) {
  Map m(6, 6, 3);  // 4.8 × 4.8 × 2.4 m
  m.walls(4.8, 4.8, 2.4);
  m.leaves({2.4, 0, 0}, {2.45, 3.2, 2.4}, Label::kOccupied);         // a partition at x = 2.4 m
  m.leaves({2.4, 3.2, 0}, {2.45, 4.0, 2.0}, Label::kDoor);           // its door; a gap beyond
  m.leaves({0.8, 0.8, 0.7}, {1.6, 1.6, 0.75}, Label::kOccupied);     // a table top
  m.leaves({0.85, 0.85, 0.1}, {1.55, 1.55, 0.3}, Label::kOccluded);  // under it
  m.set(4.0, 1.2, 1.2, 1, Label::kOccluded);                         // behind the partition, coarse
  m.leaves({3.0, 0.4, 0.1}, {3.6, 1.2, 0.4}, Label::kOccluded);      // and leaf by leaf
  m.set(3.2, 2.0, 0.4, 2, Label::kOccluded);
  m.set(3.2, 2.4, 0.4, 2, Label::kOccluded);  // behind the one above: 1/(1 + n)
  m.set(3.4, 4.4, 2.2, 3, Label::kOccluded);  // beyond the door
  m.set(0.4, 4.4, 2.2, 2, Label::kOccluded);  // in view of the west room
  m.set(4.4, 4.4, 0.4, 2, Label::kUnknown);
  for (const bool with_room : {false, true}) {
    NbvParams p;  // method 1, the scanner's default limits
    if (with_room) p.room = RoomBox{{0, 0, 0}, {3.0, 4.8, 2.4}};
    std::vector<NbvCandidate> grid;
    for (double x = 0.4; x < 4.6; x += 1.2)
      for (double y = 0.4; y < 4.6; y += 1.2) grid.push_back(at(x, y, 0));
    ASSERT_GE(grid.size(), 8u);  // scored a candidate at a time, the memo shared
    const NbvResult all = best_view_among(m.t, grid, p);
    ASSERT_TRUE(all.best);
    const double best_eq5 = stop_percentage(m.t, all.best->position, p.limits, 1, p.room);
    ASSERT_GT(best_eq5, 0);
    EXPECT_NEAR(all.stop_percent, best_eq5, 1e-9 * best_eq5);
    EXPECT_GT(all.scoring.blocked_by_walls, 0u);
    EXPECT_GT(all.scoring.blocked_by_cache, 0u);
    bool door_matters = false;
    for (const NbvCandidate& c : all.candidates) {
      const double eq5 = stop_percentage(m.t, c.position, p.limits, 1, p.room);
      EXPECT_NEAR(c.score / all.best->score, eq5 / best_eq5, 1e-9)
          << "at " << c.position.x << ", " << c.position.y;
      // One candidate at a time (blocks of targets spread over the threads), doors
      // passing for the score: Eq 5 keeps them blocking.
      NbvParams doors = p;
      doors.see_through_doors = true;
      doors.threads = 2;
      const NbvResult one = best_view_among(m.t, {c}, doors);
      ASSERT_TRUE(one.best);
      EXPECT_NEAR(one.stop_percent, eq5, 1e-9 * std::max(eq5, 1.0));
      door_matters = door_matters || one.best->score > c.score * (1 + 1e-9);
    }
    EXPECT_TRUE(door_matters);  // else the last check could not fail
  }
}

}  // namespace
}  // namespace semioctree
