// libFuzzer target: an OctoMap .ot/.bt file through read_tree_stream (the core of
// read_tree_file, which `info`, `export` and `map-nbv` call); a SemiOcTree read
// is then summarised and converted as `info` and `export` do, an occupancy tree
// walked as `info` does. A FileError is the reader's clear answer; anything else
// is a finding. The seed corpus holds SemiOcTree .ot files.
#include <octomap/ColorOcTree.h>

#include <sstream>
#include <string>

#include "semioctree/octomap_ext/export.h"
#include "semioctree/octomap_ext/file_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  semioctree::TreeFile file;
  try {
    file = semioctree::read_tree_stream(in, "fuzz.ot");
  } catch (const semioctree::FileError&) {
    return 0;
  }
  if (const auto* semi = dynamic_cast<const semioctree::SemiOcTree*>(file.tree.get())) {
    semi->statistics();
    semioctree::to_occupancy_octree(*semi);
    semioctree::to_color_octree(*semi);
  } else if (const auto* occ = dynamic_cast<const octomap::OcTree*>(file.tree.get())) {
    for (auto it = occ->begin_leafs(), end = occ->end_leafs(); it != end; ++it)
      occ->isNodeOccupied(*it);
    occ->memoryUsage();
  }
  return 0;
}
