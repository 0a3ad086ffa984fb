// PCL allocates what a PCD or PLY header claims before it looks at the data,
// and reads some malformed files silently wrong. These checks read the header
// themselves and compare it with the file before PCL sees the file. Internal
// to src/ (scan_io.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace semioctree::detail {

// PCL indexes points with a signed 32-bit int.
constexpr std::uint64_t kMaxFilePoints = 2147483647;

// Throw ScanReadError naming the file and what is wrong with it. check_pcd_file
// returns the DATA line's format ("ascii", "binary", "binary_compressed").
std::string check_pcd_file(const std::string& path);
void check_ply_file(const std::string& path);

}  // namespace semioctree::detail
