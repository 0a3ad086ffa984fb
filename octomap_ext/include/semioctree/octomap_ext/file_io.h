// Reading and writing OctoMap files safely: every file is validated before
// OctoMap's readers see it, and every file is written to a temporary name and
// renamed, so an interrupted run never leaves a half-written file behind.
#pragma once

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <functional>
#include <istream>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

// An I/O or format problem, with the file's path in the message.
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TreeFile {
  std::unique_ptr<octomap::AbstractOcTree> tree;
  bool binary = false;  // a .bt occupancy file (always read as octomap::OcTree)
  std::string type;     // "OcTree", "ColorOcTree", "SemiOcTree"
  std::size_t header_size = 0;
};

// Reads a .ot (OcTree, ColorOcTree, SemiOcTree) or .bt file, recognised by its
// first line, not its name. Throws FileError naming the file on a missing,
// truncated, corrupted or unsupported file.
TreeFile read_tree_file(const std::string& path);
// The same from a stream holding a whole file; `name` stands for the file in messages.
TreeFile read_tree_stream(std::istream& in, const std::string& name);
// Same, and requires a SemiOcTree.
std::unique_ptr<SemiOcTree> read_semioctree_file(const std::string& path);

// Writes via `path + ".tmp-<pid>"` and rename(); throws FileError on failure.
// The first write into a directory removes its stale temporaries (below).
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write);
// Removes the temporaries interrupted writers left in `dir`: files named
// NAME.tmp-PID (write_file_atomically) or NAME.tmp-PID-N (the simulator's
// writer) whose process PID is not running. Nothing else; never throws.
// Returns how many were removed.
std::size_t remove_stale_temporaries(const std::string& dir);
// The lines OctoMap writes before a tree's nodes: AbstractOcTree::write's for a .ot
// file of `type`, and the .bt header (writeBinaryConst's, with a comment of ours).
void write_ot_header(std::ostream& s, const std::string& type, std::size_t size, double resolution);
void write_bt_header(std::ostream& s, std::size_t size, double resolution);

// .ot of any tree type (the tree is not modified: no pruning).
void write_tree_file(const octomap::AbstractOcTree& tree, const std::string& path);
// .bt occupancy file (OctoMap's writeBinaryConst: the tree is not pruned).
void write_binary_file(const octomap::OcTree& tree, const std::string& path);

}  // namespace semioctree
