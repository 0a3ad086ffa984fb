// Uses the installed library: builds a SemiOcTree, writes it, reads it back
// through OctoMap's factory, and traverses a ray; with an argument, also writes
// the tree to that .ot file (for reader.cpp). Then discretizes a PCL cloud with
// the pipeline (PCL's headers, definitions and libraries come with the package).
// Exit code 0 on success.
#include <octomap/AbstractOcTree.h>
#include <semioctree/discretize.h>
#include <semioctree/octomap_ext/semioctree.h>
#include <semioctree/version.h>

#include <cstdio>
#include <memory>
#include <sstream>

int main(int argc, char** argv) {
  semioctree::SemiOcTree tree(0.05, 0.8);
  tree.create_coarse({0, 0, 0}, semioctree::Label::kEmpty);
  std::stringstream buf;
  if (!tree.write(buf)) return 1;
  if (argc > 1 && !tree.write(argv[1])) return 4;
  std::unique_ptr<octomap::AbstractOcTree> back(octomap::AbstractOcTree::read(buf));
  auto* semi = dynamic_cast<semioctree::SemiOcTree*>(back.get());
  if (!semi || semi->leaf_level() != 4) return 2;
  int steps = 0;
  semi->traverse({0.1, 0.1, 0.1}, {0.7, 0.7, 0.7},
                 [&](const semioctree::RayStep&) { return ++steps > 0; });
  std::printf("semioctree %s: %d step(s)\n", semioctree::version(), steps);
  if (steps != 1) return 3;
  // A 1 m wall of points at x = 0.5: one layer of occupied leaves.
  semioctree::Cloud wall;
  for (float y = 0.01f; y < 1.0f; y += 0.02f)
    for (float z = 0.01f; z < 1.0f; z += 0.02f) wall.push_back(pcl::PointXYZ{0.51f, y, z});
  semioctree::DiscretizeReport report;
  const auto map = semioctree::discretize(wall, 1.0, {0.05, 0.8}, &report);
  std::printf("discretized %zu points: %zu occupied leaves\n", wall.size(), report.occupied_leaves);
  return map && report.occupied_leaves == 20 * 20 ? 0 : 5;
}
