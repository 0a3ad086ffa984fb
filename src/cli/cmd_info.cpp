// `semioctree info FILE`: what a .ot/.bt file holds.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <iomanip>
#include <iostream>
#include <map>
#include <memory>

#include "commands.h"
#include "semioctree/octomap_ext/file_io.h"

namespace semioctree::cli {

namespace {

void print_semioctree(const SemiOcTree& t) {
  const OctantStatistics st = t.statistics();
  std::cout << "leaf size:      " << t.leaf_size() << " m\n"
            << "coarse size:    " << t.coarse_size() << " m (k = " << t.leaf_level() << ")\n"
            << "coarse voxels:  " << st.coarse_voxels << "\n"
            << "octants:        " << st.total() << "\n\n";
  std::cout << std::left << std::setw(8) << "level" << std::setw(10) << "size[m]";
  for (int l = 0; l < kLabelCount; ++l) std::cout << std::right << std::setw(10) << kLabelNames[l];
  std::cout << std::setw(11) << "total"
            << "\n";
  for (unsigned lv = 0; lv <= t.leaf_level(); ++lv) {
    std::cout << std::left << std::setw(8) << lv << std::setw(10) << t.octant_size(lv);
    for (int l = 0; l < kLabelCount; ++l)
      std::cout << std::right << std::setw(10) << st.count[lv][l];
    std::cout << std::setw(11) << st.at_level(lv) << "\n";
  }
  std::cout << "\nvolume per label (m³, % of labelled octants):\n";
  const double total = st.total_volume();
  for (int l = 0; l < kLabelCount; ++l) {
    if (st.volume[l] == 0) continue;
    std::cout << "  " << std::left << std::setw(10) << kLabelNames[l] << std::right << std::fixed
              << std::setprecision(3) << std::setw(12) << st.volume[l] << std::setw(9)
              << std::setprecision(2) << 100.0 * st.volume[l] / total << " %\n";
  }
  std::cout.unsetf(std::ios::floatfield);
  std::cout << "memory:         " << t.memory_bytes() << " bytes (" << sizeof(SemiOcTreeNode)
            << " B per node, " << t.size() << " nodes incl. inner)\n";
}

template <class TREE>
void print_occupancy(const TREE& t) {
  std::map<unsigned, std::pair<std::size_t, std::size_t>> by_depth;  // depth → (occ, free)
  double occ_vol = 0, free_vol = 0;
  for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
    const double s = it.getSize();
    if (t.isNodeOccupied(*it)) {
      ++by_depth[it.getDepth()].first;
      occ_vol += s * s * s;
    } else {
      ++by_depth[it.getDepth()].second;
      free_vol += s * s * s;
    }
  }
  std::cout << "resolution:     " << t.getResolution() << " m\n"
            << "nodes:          " << t.size() << " (" << t.getNumLeafNodes() << " leaves)\n"
            << "leaves per depth (depth, size[m], occupied, free):\n";
  for (const auto& [d, c] : by_depth)
    std::cout << "  " << std::setw(3) << d << std::setw(10) << t.getNodeSize(d) << std::setw(10)
              << c.first << std::setw(10) << c.second << "\n";
  std::cout << "volume:         occupied " << occ_vol << " m³, free " << free_vol << " m³\n"
            << "memory:         " << t.memoryUsage() << " bytes\n";
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "info",
      "Describe a .ot / .bt file: tree type, leaf and coarse size, octants per level "
      "and label, volumes, memory.");
  auto file = std::make_shared<std::string>();
  cmd->add_option("FILE", *file,
                  "OctoMap file (.ot of type SemiOcTree, OcTree or ColorOcTree, or .bt)")
      ->required();
  cmd->callback([file] {
    const TreeFile tf = read_tree_file(*file);
    std::cout << "file:           " << *file << "\n"
              << "tree type:      " << tf.type << (tf.binary ? " (binary .bt occupancy)" : " (.ot)")
              << "\n";
    if (const auto* s = dynamic_cast<const SemiOcTree*>(tf.tree.get()))
      print_semioctree(*s);
    else if (const auto* c = dynamic_cast<const octomap::ColorOcTree*>(tf.tree.get()))
      print_occupancy(*c);
    else if (const auto* o = dynamic_cast<const octomap::OcTree*>(tf.tree.get()))
      print_occupancy(*o);
  });
}

}  // namespace semioctree::cli
