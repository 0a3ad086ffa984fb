// Next-Best-View (paper 2.2 "NBV calculation", Eq 3–5): scores of hand-placed
// scanner positions against hand-computed Eq 3 sums (direct, through n
// occluded octants, blocked, through a door), the volume weights of method 1,
// the level-ℓ reading of method 2, agreement with a brute-force reference and
// with the same map stored as a homogeneous grid, candidates (safety cylinder
// checked against a brute-force rule, reachability, the blind zone under past
// scans), the stop percentage, thread-count independence, and the lab.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "semioctree/discretize.h"
#include "semioctree/nbv.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/import.h"
#include "support/ray_reference.h"
#include "support/synthetic_clouds.h"

#ifdef SEMIOCTREE_HAVE_SIM
#include "semioctree/openings.h"
#include "semioctree/preprocess.h"
#include "semioctree/sim/ground_truth.h"
#include "support/lab_scan.h"
#endif

namespace semioctree {
namespace {

constexpr double kLeaf = 0.05;

// A map built by hand: a block of coarse voxels (0.8 m) and labelled octants.
struct Map {
  SemiOcTree t{kLeaf, 0.8};

  Map(int nx, int ny, int nz) {
    for (int x = 0; x < nx; ++x)
      for (int y = 0; y < ny; ++y)
        for (int z = 0; z < nz; ++z) t.create_coarse({x, y, z}, Label::kEmpty);
  }
  octomap::OcTreeKey key(double x, double y, double z) const {
    octomap::OcTreeKey k;
    EXPECT_TRUE(t.key_of({x, y, z}, k));
    return k;
  }
  // The octant at `level` holding the point.
  void set(double x, double y, double z, unsigned level, Label l) {
    t.set_label(key(x, y, z), level, l);
  }
  void leaf(double x, double y, double z, Label l) { set(x, y, z, t.coarse_level(), l); }
  // Every leaf whose centre lies in [lo, hi).
  void leaves(const Point3& lo, const Point3& hi, Label l) {
    for (double x = lo.x + kLeaf / 2; x < hi.x; x += kLeaf)
      for (double y = lo.y + kLeaf / 2; y < hi.y; y += kLeaf)
        for (double z = lo.z + kLeaf / 2; z < hi.z; z += kLeaf) leaf(x, y, z, l);
  }
  // Occupied walls (one leaf thick, full height) on the four sides of [0, X) × [0, Y).
  void walls(double X, double Y, double Z) {
    leaves({0, 0, 0}, {X, kLeaf, Z}, Label::kOccupied);
    leaves({0, Y - kLeaf, 0}, {X, Y, Z}, Label::kOccupied);
    leaves({0, 0, 0}, {kLeaf, Y, Z}, Label::kOccupied);
    leaves({X - kLeaf, 0, 0}, {X, Y, Z}, Label::kOccupied);
  }
};

NbvParams open_limits(int method = 1, unsigned level = NbvParams::kLeafLevel) {
  NbvParams p;
  p.method = method;
  p.level = level;
  p.limits.min_range = 0;
  p.limits.elevation_min_deg = -90;
  p.limits.elevation_max_deg = 90;
  return p;
}

double score_at(const SemiOcTree& t, const Point3& p, const NbvParams& params) {
  return score_positions(t, {p}, params).at(0);
}

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
  NbvParams p;  // the scanner's default limits: 0.6–60 m, elevation −60°…90°
  // T1 1, T2 1/2, T3 1/3, T4 0 (occupied), T5 0 (door), T6 1 (through out),
  // T7 8 (level 3), T8 0 (below −60°), T9 0 (unknown).
  const double expected = 1 + 1.0 / 2 + 1.0 / 3 + 1 + 8;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected, 1e-12);
  // Looking straight down is allowed: T8 is seen directly.
  p.limits.elevation_min_deg = -90;
  EXPECT_NEAR(score_at(m.t, m.a, p), expected + 1, 1e-12);
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

// The line a→b by the brute-force traversal: nullopt when blocked (an occupied, unknown,
// door or window octant other than the scanner's own, or b outside the scanner's limits),
// else the number of occluded octants crossed between the two ends.
std::optional<int> reference_line(const SemiOcTree& t, const Point3& a, const Point3& b,
                                  const ScannerView& lim) {
  const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (range < lim.min_range || range > lim.max_range || range == 0) return std::nullopt;
  const double elevation = std::asin(dz / range) * 180 / M_PI;
  if (elevation < lim.elevation_min_deg || elevation > lim.elevation_max_deg) return std::nullopt;
  const auto steps = testing::reference_traversal(t, a, b);
  int n = 0;
  for (std::size_t j = 1; j < steps.size(); ++j) {
    const auto oc = t.find_octant(steps[j].key);
    const Label l = steps[j].has_node && oc ? oc->label() : Label::kUnknown;
    if (l == Label::kOccupied || l == Label::kUnknown || l == Label::kDoor || l == Label::kWindow)
      return std::nullopt;
    if (l == Label::kOccluded && j + 1 < steps.size()) ++n;
  }
  return n;
}

// Eq 3 (method 1) with the brute-force traversal of tests/support: no cache,
// no hierarchy; the scanner's own octant neither blocks nor counts, the
// target's own octant does not count.
double reference_score(const SemiOcTree& t, const Point3& a, const ScannerView& lim) {
  double sum = 0;
  t.for_each_octant([&](const Octant& o) {
    if (o.label() != Label::kOccluded) return;
    if (const auto n = reference_line(t, a, o.center, lim))
      sum += double(std::uint64_t(1) << (3 * (t.coarse_level() - o.level))) / (1.0 + *n);
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

// --- candidates ---------------------------------------------------------------------------

// A 4 × 4 × 2.4 m room: walls, an occupied pillar, a small occluded octant low
// down, an occluded octant above the scanner's top and an occupied leaf on the
// floor (below the ground clearance).
struct FurnishedRoom : Map {
  FurnishedRoom() : Map(5, 5, 3) {
    walls(4.0, 4.0, 2.4);
    leaves({1.0, 1.0, 0.5}, {1.1, 1.1, 1.0}, Label::kOccupied);  // pillar
    set(3.05, 3.05, 0.25, 3, Label::kOccluded);                  // low, in reach
    set(2.05, 3.05, 2.05, 3, Label::kOccluded);                  // above 1.6 m
    leaf(3.025, 1.025, 0.025, Label::kOccupied);                 // on the floor
  }
};

struct Cell {
  int x, y;
  bool operator<(const Cell& o) const { return std::tie(x, y) < std::tie(o.x, o.y); }
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
};

// The candidates of a leaf-spacing grid by the rule, brute force: obstacle
// columns from every octant meeting [clearance, top), cylinder clear when no
// obstacle column centre is within radius + leaf/2, reachable by a 4-connected
// fill over clear cells, empty at scanner height.
std::vector<Cell> brute_force_candidates(const SemiOcTree& t, const RobotGeometry& robot,
                                         const Point3& start, int cells) {
  std::set<Cell> obstacles;
  t.for_each_octant([&](const Octant& o) {
    const Label l = o.label();
    if (l != Label::kOccupied && l != Label::kOccluded && l != Label::kUnknown) return;
    const double z0 = o.center.z - o.size / 2, z1 = o.center.z + o.size / 2;
    if (z1 <= robot.ground_clearance + 1e-9 || z0 >= robot.top() - 1e-9) return;
    const int n = int(std::lround(o.size / kLeaf));
    const int x0 = int(std::lround((o.center.x - o.size / 2) / kLeaf));
    const int y0 = int(std::lround((o.center.y - o.size / 2) / kLeaf));
    for (int x = x0; x < x0 + n; ++x)
      for (int y = y0; y < y0 + n; ++y) obstacles.insert({x, y});
  });
  const double reach = robot.radius / kLeaf + 0.5;
  std::vector<char> clear(cells * cells, 0);
  for (int x = 0; x < cells; ++x)
    for (int y = 0; y < cells; ++y) {
      bool ok = true;
      for (const Cell& o : obstacles)
        if (double(o.x - x) * (o.x - x) + double(o.y - y) * (o.y - y) <= reach * reach) {
          ok = false;
          break;
        }
      // Outside the map is unknown: the nearest outside cell is an obstacle too.
      for (int d : {x + 1, y + 1, cells - x, cells - y}) ok &= double(d) > reach;
      clear[x * cells + y] = ok;
    }
  std::vector<char> reached(cells * cells, 0);
  const int sx = int(start.x / kLeaf), sy = int(start.y / kLeaf);
  std::vector<Cell> stack{{sx, sy}};
  reached[sx * cells + sy] = 1;
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    for (const Cell& d : {Cell{1, 0}, Cell{-1, 0}, Cell{0, 1}, Cell{0, -1}}) {
      const int x = c.x + d.x, y = c.y + d.y;
      if (x < 0 || y < 0 || x >= cells || y >= cells) continue;
      if (reached[x * cells + y] || !clear[x * cells + y]) continue;
      reached[x * cells + y] = 1;
      stack.push_back({x, y});
    }
  }
  std::vector<Cell> out;
  for (int y = 0; y < cells; ++y)
    for (int x = 0; x < cells; ++x) {
      const auto o =
          t.find_octant(Point3((x + 0.5) * kLeaf, (y + 0.5) * kLeaf, robot.scanner_height));
      if (o && o->label() == Label::kEmpty && clear[x * cells + y] && reached[x * cells + y])
        out.push_back({x, y});
    }
  return out;
}

std::vector<Cell> cells_of(const std::vector<Point3>& ps) {
  std::vector<Cell> out;
  for (const Point3& p : ps)
    out.push_back({int(std::floor(p.x / kLeaf)), int(std::floor(p.y / kLeaf))});
  return out;
}

bool has_candidate_near(const std::vector<Point3>& ps, double x, double y, double tol = 1e-6) {
  for (const Point3& p : ps)
    if (std::hypot(p.x - x, p.y - y) < tol) return true;
  return false;
}

TEST(Nbv, CandidatesKeepTheSafetyCylinderFreeOfObstacles) {
  FurnishedRoom m;
  RobotGeometry robot;
  NbvParams p;
  p.candidate_spacing = kLeaf;  // every leaf cell is a grid point
  const Point3 start(2.0, 2.0, 0);
  CandidateReport rep;
  const auto got = find_candidates(m.t, robot, start, {}, p, &rep);
  const auto expected = brute_force_candidates(m.t, robot, start, 80);
  EXPECT_GT(expected.size(), 500u);
  auto sorted = [](std::vector<Cell> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_TRUE(sorted(cells_of(got)) == sorted(expected))
      << got.size() << " candidates, brute force " << expected.size();
  EXPECT_EQ(rep.feasible, got.size());
  EXPECT_GT(rep.cylinder_blocked, 0u);
  for (const Point3& c : got) EXPECT_DOUBLE_EQ(c.z, robot.scanner_height);
  // Spot checks: clear in the middle, too near the pillar (0.3 m), the low
  // occluded octant (0.35 m) or a wall (0.4 m); the occluded octant above the
  // scanner's top and the floor leaf do not count.
  EXPECT_TRUE(has_candidate_near(got, 2.025, 2.025));
  EXPECT_FALSE(has_candidate_near(got, 1.375, 1.025));
  EXPECT_FALSE(has_candidate_near(got, 3.425, 3.075));
  EXPECT_FALSE(has_candidate_near(got, 0.425, 2.025));
  EXPECT_TRUE(has_candidate_near(got, 2.075, 3.025));
  EXPECT_TRUE(has_candidate_near(got, 3.025, 1.025));
  // Without ground clearance the floor leaf is an obstacle.
  RobotGeometry no_clearance;
  no_clearance.ground_clearance = 0;
  EXPECT_FALSE(has_candidate_near(find_candidates(m.t, no_clearance, start, {}, p), 3.025, 1.025));
  // A slimmer robot fits nearer the pillar.
  RobotGeometry slim;
  slim.radius = 0.2;
  EXPECT_TRUE(has_candidate_near(find_candidates(m.t, slim, start, {}, p), 1.375, 1.025));
}

// At a 0.1 m leaf the floor's layer [0, 0.1) holds the floor's points (all of them in an
// OctoMap map, what the floor cut leaves in ours). Below the leaf the map cannot tell an
// obstacle from the floor: that layer is driven over, a taller obstacle is not. Before,
// a leaf above the 5 cm clearance made the floor an obstacle everywhere: `survey --leaf
// 0.1` stopped after its first scan with no feasible candidate.
TEST(Nbv, FloorLayerOfACoarseLeafIsDrivenOver) {
  SemiOcTree t{0.1, 0.8};
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 3; ++z) t.create_coarse({x, y, z}, Label::kEmpty);
  auto leaf = [&](double x, double y, double z, Label l) {
    octomap::OcTreeKey k;
    ASSERT_TRUE(t.key_of({x, y, z}, k));
    t.set_label(k, t.coarse_level(), l);
  };
  for (double x = 0.05; x < 4.8; x += 0.1)
    for (double y = 0.05; y < 4.8; y += 0.1) leaf(x, y, 0.05, Label::kOccupied);  // the floor
  leaf(1.25, 2.45, 0.15, Label::kOccupied);  // a box 0.2 m tall on the floor
  leaf(1.25, 2.45, 0.05, Label::kOccupied);
  NbvParams p;
  p.candidate_spacing = 0.1;
  const Point3 start(2.45, 2.45, 0);
  RobotGeometry robot;
  EXPECT_DOUBLE_EQ(floor_layer_clearance(robot, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(floor_layer_clearance(robot, 0.05), 0.05);
  const std::vector<Point3> got = find_candidates(t, robot, start, {}, p);
  // Clear of the map's border (unknown beyond it) by radius + leaf/2 = 0.55 m.
  EXPECT_TRUE(has_candidate_near(got, 2.45, 2.45));
  EXPECT_TRUE(has_candidate_near(got, 3.95, 3.95));
  EXPECT_FALSE(has_candidate_near(got, 1.65, 2.45));  // 0.4 m from the box
  EXPECT_TRUE(has_candidate_near(got, 1.85, 2.45));   // 0.6 m from it
  EXPECT_GT(got.size(), 300u);
  // No clearance: nothing is driven over, the floor blocks every cylinder.
  RobotGeometry strict;
  strict.ground_clearance = 0;
  EXPECT_DOUBLE_EQ(floor_layer_clearance(strict, 0.1), 0.0);
  EXPECT_TRUE(find_candidates(t, strict, start, {}, p).empty());
}

TEST(Nbv, CandidateGridGivesSeveralPositionsPerLargeOctant) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  NbvParams p;
  p.candidate_spacing = 0.4;
  const auto got = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  // The coarse voxel [1.6, 2.4)² at scanner height is one empty octant.
  int inside = 0;
  for (const Point3& c : got) inside += c.x > 1.6 && c.x < 2.4 && c.y > 1.6 && c.y < 2.4;
  EXPECT_EQ(inside, 4);
  // World-aligned grid at leaf centres, 0.4 m apart.
  for (const Point3& c : got) {
    EXPECT_NEAR(std::remainder(c.x - 0.225, 0.4), 0.0, 1e-9);
    EXPECT_NEAR(std::remainder(c.y - 0.225, 0.4), 0.0, 1e-9);
  }
  // 4 × 4 m with walls (leaf cells 0 and 79), clearance 10.5 cells: cells
  // 12, 20, ..., 68 (x, y = 0.625 ... 3.425): 8 × 8.
  EXPECT_EQ(got.size(), 64u);
}

TEST(Nbv, CandidateGridPassesThroughItsAnchor) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  NbvParams p;
  p.candidate_spacing = 0.4;
  const std::vector<Point3> fixed = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  p.grid_anchor = Point3(1.93, 2.11, 1.5);  // leaf cell centre (1.925, 2.125)
  const std::vector<Point3> got = find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p);
  EXPECT_TRUE(has_candidate_near(got, 1.925, 2.125));
  EXPECT_FALSE(has_candidate_near(fixed, 1.925, 2.125));
  for (const Point3& c : got) {
    EXPECT_NEAR(std::remainder(c.x - 1.925, 0.4), 0.0, 1e-9);
    EXPECT_NEAR(std::remainder(c.y - 2.125, 0.4), 0.0, 1e-9);
  }
  // Clear from 0.625 to 3.425 (see above): x 0.725 ... 3.125 (7), y 0.925 ... 3.325 (7).
  EXPECT_EQ(got.size(), 49u);
  p.grid_anchor = Point3(-1e6, 0, 0);  // beyond OctoMap's key range
  EXPECT_THROW(find_candidates(m.t, RobotGeometry{}, {2.0, 2.0, 0}, {}, p), std::invalid_argument);
}

TEST(Nbv, UnreachablePocketOfFreeFloorGivesNoCandidates) {
  Map m(5, 5, 3);
  m.walls(4.0, 4.0, 2.4);
  // A closet [2.4, 4) × [2.4, 4) walled off to the ceiling.
  m.leaves({2.4, 2.4, 0}, {2.45, 4.0, 2.4}, Label::kOccupied);
  m.leaves({2.4, 2.4, 0}, {4.0, 2.45, 2.4}, Label::kOccupied);
  NbvParams p;
  p.candidate_spacing = 0.1;
  auto in_closet = [](const Point3& c) { return c.x > 2.4 && c.y > 2.4; };
  CandidateReport rep;
  const auto outside = find_candidates(m.t, RobotGeometry{}, {1.0, 1.0, 0}, {}, p, &rep);
  EXPECT_FALSE(outside.empty());
  EXPECT_GT(rep.unreachable, 0u);
  for (const Point3& c : outside) EXPECT_FALSE(in_closet(c)) << c.x << ", " << c.y;
  // From inside the closet only the closet is reachable.
  const auto inside = find_candidates(m.t, RobotGeometry{}, {3.2, 3.2, 0}, {}, p);
  EXPECT_FALSE(inside.empty());
  for (const Point3& c : inside) EXPECT_TRUE(in_closet(c)) << c.x << ", " << c.y;
  // A robot outside the map has nowhere to go.
  const auto lost = find_candidates(m.t, RobotGeometry{}, {9.0, 9.0, 0}, {}, p, &rep);
  EXPECT_TRUE(lost.empty());
  EXPECT_FALSE(rep.robot_in_map);
}

using testing::room_with_pillar;

TEST(Nbv, BlindZoneUnderPastScansIsNotAnObstacle) {
  const auto tree = discretize(room_with_pillar(), 2.4, {0.05, 0.8});
  const Point3 scan(1.0, 2.0, 1.5);
  study_occlusion(*tree, {ScannerView{scan}});  // default limits: blind below −60°
  // The occlusion study did label the cone under the scanner occluded.
  ASSERT_EQ(tree->find_octant(Point3(1.0, 2.0, 0.3))->label(), Label::kOccluded);
  NbvParams p;
  p.candidate_spacing = 0.1;
  CandidateReport rep;
  const auto with_rule = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p, &rep);
  EXPECT_GT(rep.blind_octants_freed, 0u);
  ASSERT_FALSE(with_rule.empty());
  // The robot can move off the spot it scanned from, and candidates close to
  // it are feasible: nearer than the cone's floor radius (0.87 m) plus the
  // robot's radius, which would be the limit if the cone were an obstacle.
  // (Within 0.6 m the scanner-height octant itself is in the minimum-range
  // sphere, not empty, so no candidate.)
  double nearest = 1e9;
  for (const Point3& c : with_rule) nearest = std::min(nearest, std::hypot(c.x - 1.0, c.y - 2.0));
  EXPECT_LT(nearest, 0.8);
  // The pillar's real shadow is still an obstacle: nothing right behind it.
  for (const Point3& c : with_rule)
    EXPECT_FALSE(c.x > 2.6 && c.x < 3.4 && c.y > 1.8 && c.y < 2.2) << c.x << ", " << c.y;
  // The paper's rule alone: the cone around the robot encloses it.
  p.blind_zone_is_free = false;
  EXPECT_TRUE(find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p).empty());
  // And a blind zone of another scan position does not free this one's.
  p.blind_zone_is_free = true;
  EXPECT_TRUE(
      find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {Point3(3.0, 3.2, 1.5)}, p).empty());
}

// A pruned map (siblings with one label merged, as every occlusion study
// leaves it) frees the same blind zone as the map before pruning: the rule must not
// depend on how the cone is subdivided.
TEST(Nbv, BlindZoneRuleGivesTheSameCandidatesOnAPrunedMap) {
  const auto tree = discretize(room_with_pillar(), 2.4, {0.05, 0.8});
  const Point3 scan(1.0, 2.0, 1.5);
  OcclusionParams unmerged;
  unmerged.prune = false;
  study_occlusion(*tree, {ScannerView{scan}}, unmerged);
  NbvParams p;
  p.candidate_spacing = 0.1;
  const auto before = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p);
  ASSERT_FALSE(before.empty());
  const std::size_t nodes = tree->calcNumNodes();
  tree->prune();
  ASSERT_LT(tree->calcNumNodes(), nodes);  // blind leaves did merge
  CandidateReport rep;
  const auto after = find_candidates(*tree, RobotGeometry{}, {1.0, 2.0, 0}, {scan}, p, &rep);
  EXPECT_GT(rep.blind_octants_freed, 0u);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].x, before[i].x);
    EXPECT_EQ(after[i].y, before[i].y);
  }
}

// --- the NBV and the stop percentage --------------------------------------------------------

// 4.8 × 4.8 × 2.4 m, a full-height partition at x = 2.4 for y ∈ [1.6, 3.2),
// an occluded pocket (0.2 m) right behind it.
struct PocketRoom : Map {
  PocketRoom() : Map(6, 6, 3) {
    walls(4.8, 4.8, 2.4);
    leaves({2.4, 1.6, 0}, {2.45, 3.2, 2.4}, Label::kOccupied);
    set(2.7, 2.3, 0.9, 2, Label::kOccluded);  // [2.6, 2.8) × [2.2, 2.4) × [0.8, 1.0)
  }
};

TEST(Nbv, BestCandidateSeesThePocket) {
  PocketRoom m;
  NbvParams p;
  p.candidate_spacing = 0.2;
  const Point3 robot(1.2, 2.4, 0);
  const NbvResult r = next_best_view(m.t, RobotGeometry{}, robot, {}, p);
  ASSERT_TRUE(r.best.has_value());
  EXPECT_GT(r.candidates.size(), 50u);
  EXPECT_EQ(r.scoring.targets, 1u);
  // Seen directly: the pocket's full weight (level 2: 64 leaves).
  EXPECT_DOUBLE_EQ(r.best->score, 64.0);
  auto behind_partition = [](const Point3& c) { return c.x < 2.4 && c.y >= 1.6 && c.y <= 3.2; };
  EXPECT_FALSE(behind_partition(r.best->position));
  int behind = 0, seeing = 0;
  for (const NbvCandidate& c : r.candidates) {
    if (behind_partition(c.position)) {
      ++behind;
      EXPECT_EQ(c.score, 0.0) << c.position.x << ", " << c.position.y;
    }
    seeing += c.score > 0;
    EXPECT_LE(c.score, r.best->score);
  }
  EXPECT_GT(behind, 10);  // the robot's side
  EXPECT_GT(seeing, 0);
  // The first best in grid order.
  for (const NbvCandidate& c : r.candidates) {
    if (c.score == r.best->score) {
      EXPECT_EQ(c.position.x, r.best->position.x);
      EXPECT_EQ(c.position.y, r.best->position.y);
      break;
    }
  }
  // Eq 5: the pocket's volume over the room's.
  EXPECT_NEAR(r.stop_percent, 100.0 * 0.008 / (4.8 * 4.8 * 2.4), 1e-9);
}

// Drop-in for OctoMap users: a map built with OctoMap's own insertPointCloud,
// imported, its unobserved space classified from the scanner position, gives the
// shadow behind the pillar and an NBV that looks into it, as our own pipeline does.
TEST(Nbv, MapBuiltWithOctomapGivesTheNbvBehindThePillar) {
  const Point3 scanner(1.0, 2.0, 1.2);
  // What a scanner there records of room_with_pillar: the points it has a line of
  // sight to (the segment, less its last 2 cm, misses the pillar).
  Cloud cloud;
  for (const auto& p : room_with_pillar()) {
    const Point3 q(p.x, p.y, p.z);
    const double len = std::hypot(q.x - scanner.x, q.y - scanner.y, q.z - scanner.z);
    const double f = (len - 0.02) / len;
    const Point3 end(scanner.x + f * (q.x - scanner.x), scanner.y + f * (q.y - scanner.y),
                     scanner.z + f * (q.z - scanner.z));
    if (!testing::hits_pillar(scanner, end)) cloud.push_back(p);
  }
  octomap::OcTree map(0.05);
  octomap::Pointcloud scan;
  for (const auto& p : cloud) scan.push_back(p.x, p.y, p.z);
  map.insertPointCloud(scan, octomap::point3d(1.0f, 2.0f, 1.2f));
  const auto tree = from_occupancy_octree(map, 0.8);
  const ScannerView view{scanner};
  OcclusionParams unknown_only;
  unknown_only.scope = OcclusionScope::kUnknown;
  study_occlusion(*tree, {view}, unknown_only);
  const Point3 behind(3.0, 2.0, 0.8);  // behind the pillar (x 2.0–2.6, y 1.7–2.3, z < 1.6)
  ASSERT_TRUE(tree->find_octant(behind));
  EXPECT_EQ(tree->find_octant(behind)->label(), Label::kOccluded);
  EXPECT_EQ(tree->find_octant(Point3(1.5, 3.0, 1.0))->label(), Label::kEmpty);
  EXPECT_EQ(tree->find_octant(Point3(0.025, 2.0, 1.0))->label(), Label::kOccupied);

  // The same scan through our pipeline: inside the room (its grid may reach beyond the
  // walls differently) the same cells are hidden, but for the rays' discretisation.
  const auto ours = discretize(cloud, 2.4, {0.05, 0.8});
  study_occlusion(*ours, {view});
  std::size_t cells = 0, agree = 0, hidden = 0;
  for (double x = 0.075; x < 3.95; x += 0.05)
    for (double y = 0.075; y < 3.95; y += 0.05)
      for (double z = 0.025; z < 2.4; z += 0.05, ++cells) {
        const Label a = tree->find_octant(Point3(x, y, z))->label();
        const Label b = ours->find_octant(Point3(x, y, z))->label();
        agree += a == b;
        hidden += a == Label::kOccluded;
      }
  std::printf("OctoMap map imported vs pipeline: %zu of %zu cells agree, %zu hidden\n", agree,
              cells, hidden);
  EXPECT_GT(hidden, cells / 50);
  EXPECT_GT(agree, cells * 97 / 100);

  RobotGeometry robot;
  robot.scanner_height = scanner.z;
  NbvParams params;
  params.candidate_spacing = 0.1;
  const NbvResult r = next_best_view(*tree, robot, scanner, {scanner}, params);
  ASSERT_TRUE(r.best.has_value());
  EXPECT_GT(r.best->score, 0.0);
  // The NBV sees into the shadow, which the first position does not.
  EXPECT_EQ(point_visibility(*tree, {view}, behind), Visibility::kHidden);
  EXPECT_EQ(point_visibility(*tree, {ScannerView{r.best->position}}, behind), Visibility::kDirect)
      << r.best->position.x << ", " << r.best->position.y;
}

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

// The room is what the scanners' free space reaches: a labelled door stops the
// fill, a hole in the wall does not; the scanner's own cell (its blind zone,
// occluded) does not stop the seeding.
TEST(Nbv, RoomBoxIsTheFreeSpaceTheScannersStandIn) {
  Map m(8, 5, 3);  // 6.4 × 4 × 2.4 m
  m.walls(6.4, 4.0, 2.4);
  m.leaves({4.0, 0, 0}, {4.05, 4.0, 2.4}, Label::kOccupied);  // a wall at x = 4 m
  m.leaves({4.0, 1.6, 0}, {4.05, 2.4, 2.0}, Label::kDoor);    // and a door in it
  m.leaf(2.025, 2.025, 1.525, Label::kOccluded);              // the scanner's blind zone
  const std::vector<Point3> scanner{{2.025, 2.025, 1.525}};
  const auto box = room_box(m.t, scanner, 1.525, 0.0, 2.4);
  ASSERT_TRUE(box);
  // Free cells x, y ∈ [0.05, 4.0) × [0.05, 3.95), grown by a leaf.
  EXPECT_NEAR(box->min.x, 0.0, 1e-9);
  EXPECT_NEAR(box->min.y, 0.0, 1e-9);
  EXPECT_NEAR(box->max.x, 4.05, 1e-9);
  EXPECT_NEAR(box->max.y, 4.0, 1e-9);
  EXPECT_EQ(box->min.z, 0.0);
  EXPECT_EQ(box->max.z, 2.4);
  // A plane above the door (z = 2.2) holds the same room.
  const auto above = room_box(m.t, scanner, 2.2, 0.0, 2.4);
  ASSERT_TRUE(above);
  EXPECT_NEAR(above->max.x, 4.05, 1e-9);
  // Not labelled as a door, the hole lets the fill through to the far wall.
  m.leaves({4.0, 1.6, 0}, {4.05, 2.4, 2.0}, Label::kEmpty);
  const auto leaky = room_box(m.t, scanner, 1.525, 0.0, 2.4);
  ASSERT_TRUE(leaky);
  EXPECT_NEAR(leaky->max.x, 6.4, 1e-9);
  // No scanner in free space, or no height between floor and ceiling: no room.
  EXPECT_FALSE(room_box(m.t, {}, 1.525, 0.0, 2.4));
  EXPECT_FALSE(room_box(m.t, {{1.0, 1.0, 9.0}}, 9.0, 0.0, 2.4));
  EXPECT_FALSE(room_box(m.t, scanner, 1.525, 2.4, 2.4));
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

TEST(Nbv, NextBestViewSameForAnyThreadCount) {
  PocketRoom m;
  m.set(1.0, 4.0, 0.5, 3, Label::kOccluded);
  m.set(4.0, 1.0, 1.9, 2, Label::kOccluded);
  m.leaves({3.6, 0.8, 0.5}, {3.65, 1.6, 1.5}, Label::kOccupied);
  std::vector<NbvResult> runs;
  for (unsigned threads : {1u, 2u, 3u}) {
    NbvParams p;
    p.candidate_spacing = 0.2;
    p.threads = threads;
    runs.push_back(next_best_view(m.t, RobotGeometry{}, {1.2, 2.4, 0}, {}, p));
  }
  for (const NbvResult& r : runs) {
    ASSERT_TRUE(r.best.has_value());
    ASSERT_EQ(r.candidates.size(), runs[0].candidates.size());
    for (std::size_t i = 0; i < r.candidates.size(); ++i) {
      EXPECT_EQ(r.candidates[i].position.x, runs[0].candidates[i].position.x);
      EXPECT_EQ(r.candidates[i].position.y, runs[0].candidates[i].position.y);
      EXPECT_EQ(r.candidates[i].score, runs[0].candidates[i].score);
    }
    EXPECT_EQ(r.best->score, runs[0].best->score);
    EXPECT_EQ(r.stop_percent, runs[0].stop_percent);
  }
}

// --- the lab --------------------------------------------------------------------------------

#ifdef SEMIOCTREE_HAVE_SIM
TEST(NbvLab, FirstScanHasAFeasibleBestCandidateInTheRoom) {
  if (std::getenv("SEMIOCTREE_SANITIZED")) GTEST_SKIP() << "heavy lab test skipped when sanitized";
  const testing::LabScan lab = testing::scan_lab(1, {}, testing::kTestStepDeg);
  PreprocessParams pp;
  pp.target_points = 400000;
  const PreprocessResult pre = preprocess(lab.world, pp);
  const Eigen::Vector3d o = pre.transform * lab.origin;
  const Point3 start(o.x(), o.y(), o.z());
  auto tree = discretize(*pre.cloud, pre.ceiling_height, {0.05, 0.8, 0.8});
  label_openings(*tree, detect_openings(*pre.cloud, pre.ceiling_height, *tree, {start}));
  study_occlusion(*tree, {ScannerView{start}});
  tree->compact();
  RobotGeometry robot;
  robot.scanner_height = start.z;
  NbvParams params;
  std::atomic<std::size_t> progress_calls{0}, last_done{0}, last_total{0};
  params.progress = [&](std::size_t done, std::size_t total) {
    ++progress_calls;
    if (done == total) last_done = done, last_total = total;
  };
  const auto t0 = std::chrono::steady_clock::now();
  const NbvResult r = next_best_view(*tree, robot, start, {start}, params);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(r.best.has_value());
  const Point3& b = r.best->position;
  // In the main room (interior 10.4 × 8.5 m), away from the start.
  EXPECT_GT(b.x, 0.0);
  EXPECT_LT(b.x, 10.4);
  EXPECT_GT(b.y, 0.0);
  EXPECT_LT(b.y, 8.5);
  EXPECT_GE(std::hypot(b.x - start.x, b.y - start.y), 0.5);
  EXPECT_GT(r.best->score, 0.0);
  EXPECT_GT(r.stop_percent, 0.1);
  // Every candidate is in the main room too (doors are narrower than the robot), and
  // the robot can really stand there: the map's cylinder test is stricter than the
  // scene's (radius + leaf/2, occluded space counts as an obstacle).
  const sim::GroundTruth truth(
      sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json"));
  const Eigen::Isometry3d to_world = pre.transform.inverse();
  double best_score = 0;
  for (const NbvCandidate& c : r.candidates) {
    EXPECT_GT(c.position.x, 0.0);
    EXPECT_LT(c.position.x, 10.4);
    EXPECT_GT(c.position.y, 0.0);
    EXPECT_LT(c.position.y, 8.5);
    const Eigen::Vector3d w = to_world * Eigen::Vector3d(c.position.x, c.position.y, c.position.z);
    EXPECT_TRUE(truth.standing_free(w.head<2>())) << w.transpose();
    best_score = std::max(best_score, c.score);
  }
  // The best is the highest score, and scoring it alone gives the same.
  EXPECT_EQ(r.best->score, best_score);
  EXPECT_DOUBLE_EQ(score_positions(*tree, {b}, NbvParams{}).at(0), r.best->score);
  // Progress: once per candidate, the last call (n, n).
  EXPECT_EQ(progress_calls.load(), r.candidates.size());
  EXPECT_EQ(last_done.load(), r.candidates.size());
  EXPECT_EQ(last_total.load(), r.candidates.size());
  // Printed for information only (shared machine): nothing is asserted on time.
  std::printf(
      "lab NBV: %zu grid points, %zu candidates, %zu occluded targets, %zu segments (%zu "
      "blocked by cache, %zu visible); best (%.3f, %.3f) score %.1f, stop %.3f %%; candidates "
      "%.3f s, scoring %.3f s (%.3f CPU s), stop %.3f s, total %.3f s\n",
      r.candidate_report.grid_points, r.candidates.size(), r.scoring.targets, r.scoring.segments,
      r.scoring.blocked_by_cache, r.scoring.visible, b.x, b.y, r.best->score, r.stop_percent,
      r.seconds_candidates, r.seconds_scoring, r.scoring.cpu_seconds, r.seconds_stop, seconds);
}
#endif

}  // namespace
}  // namespace semioctree
