// A program that names no semioctree symbol at all, only OctoMap's factory: linking
// semioctree::octomap_ext must be enough for AbstractOcTree::read to know the type.
#include <octomap/AbstractOcTree.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

int main(int argc, char** argv) {
  if (argc != 2) return 10;
  std::ifstream in(argv[1], std::ios::binary);
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
  if (!tree) return 11;
  std::printf("read a %s of %zu nodes\n", tree->getTreeType().c_str(), tree->size());
  return tree->getTreeType() == "SemiOcTree" && tree->size() > 0 ? 0 : 12;
}
