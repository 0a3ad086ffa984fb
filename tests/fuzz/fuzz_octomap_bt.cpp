// libFuzzer target: an OctoMap occupancy map (.bt, or an OcTree .ot) read by
// read_tree_stream and imported as a SemiOcTree by from_occupancy_octree, as
// `map-nbv --map` does (coarse voxels of 8 leaves), allowed 2^16 octants (what a
// small map makes) so that each input runs fast. A FileError, or the import's
// std::invalid_argument or std::length_error (too many octants), is a clear answer;
// anything else is a finding. The seed corpus holds .bt files and an OcTree .ot.
#include <octomap/OcTree.h>

#include <sstream>
#include <stdexcept>
#include <string>

#include "semioctree/octomap_ext/file_io.h"
#include "semioctree/octomap_ext/import.h"

constexpr std::uint64_t kMaxOctants = 1u << 16;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const semioctree::TreeFile file = semioctree::read_tree_stream(in, "fuzz.bt");
    if (const auto* occ = dynamic_cast<const octomap::OcTree*>(file.tree.get()))
      semioctree::from_occupancy_octree(*occ, occ->getResolution() * 8, semioctree::Label::kUnknown,
                                        nullptr, kMaxOctants);
  } catch (const semioctree::FileError&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::length_error&) {
  }
  return 0;
}
