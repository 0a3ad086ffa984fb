// Hand-built SemiOcTree maps and scoring shortcuts shared by the NBV tests.
#pragma once

#include <gtest/gtest.h>

#include "semioctree/nbv.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::testing {

inline constexpr double kLeaf = 0.05;  // m, the leaf of the hand-built maps

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
  void leaf(double x, double y, double z, Label l) { set(x, y, z, t.leaf_level(), l); }
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

// Method `method` (level ℓ = `level`) with the scanner's limits opened: no minimum
// range, every elevation.
inline NbvParams open_limits(int method = 1, unsigned level = NbvParams::kLeafLevel) {
  NbvParams p;
  p.method = method;
  p.level = level;
  p.limits.min_range = 0;
  p.limits.elevation_min_deg = -90;
  p.limits.elevation_max_deg = 90;
  return p;
}

// The score of the one position p.
inline double score_at(const SemiOcTree& t, const Point3& p, const NbvParams& params) {
  return score_positions(t, {p}, params).at(0);
}

}  // namespace semioctree::testing
