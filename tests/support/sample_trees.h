// Small SemiOcTrees with every label, shared by the file and export tests.
#pragma once

#include <memory>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::testing {

// A 3 × 2 × 2 block of coarse voxels (L = 0.4, r = 0.05): walls of occupied
// leaves at x ≈ 0, empty and occluded space, a door, a window, out, a scan
// position and an NBV, at several levels.
inline std::unique_ptr<SemiOcTree> sample_tree() {
  auto tree = std::make_unique<SemiOcTree>(0.05, 0.4);
  SemiOcTree& t = *tree;
  for (int x = 0; x < 3; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) t.create_coarse({x, y, z}, Label::kEmpty);
  auto key = [&](double x, double y, double z) {
    octomap::OcTreeKey k;
    t.key_of({x, y, z}, k);
    return k;
  };
  const unsigned leaf = t.leaf_level();
  for (double y = 0.025; y < 0.8; y += 0.05)
    for (double z = 0.025; z < 0.8; z += 0.05)
      t.set_label(key(0.025, y, z), leaf, Label::kOccupied);
  t.set_label(key(0.5, 0.1, 0.1), 1, Label::kOccluded);
  t.set_label(key(0.5, 0.3, 0.1), 2, Label::kOccluded);
  t.set_label(key(1.1, 0.1, 0.1), leaf, Label::kDoor);
  t.set_label(key(1.1, 0.1, 0.6), leaf, Label::kWindow);
  t.set_label(key(1.0, 0.6, 0.6), 0, Label::kOut);
  t.set_label(key(0.6, 0.6, 0.3), leaf, Label::kScan);
  t.set_label(key(0.7, 0.5, 0.3), leaf, Label::kNbv);
  t.set_label(key(0.9, 0.5, 0.5), 1, Label::kUnknown);
  return tree;
}

}  // namespace semioctree::testing
