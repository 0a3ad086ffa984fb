// Writing scans as binary PCD or binary PLY (PCL's writers). The points are in the
// scanner frame; the pose goes into the PCD VIEWPOINT / the PLY camera element.
#pragma once

#include <string>

#include "semioctree/sim/scanner.h"

namespace semioctree::sim {

// Fields: x y z (float), intensity (float, if the scan has it), row col (uint32).
// The file is written under a temporary name and renamed, so an interrupted run never
// leaves a half-written file. Throws std::runtime_error naming the file on failure.
void write_pcd(const std::string& path, const Scan& scan);
void write_ply(const std::string& path, const Scan& scan);
// Chooses by extension (.pcd or .ply); throws for any other.
void write_scan(const std::string& path, const Scan& scan);

}  // namespace semioctree::sim
