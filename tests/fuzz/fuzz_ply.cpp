// libFuzzer target: a .ply point file through read_scans (see fuzz_point_file.h).
#include "fuzz_point_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return semioctree::fuzz::read_point_file(".ply", data, size);
}
