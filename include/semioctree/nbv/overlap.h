// Predicted overlap of a scan not yet taken with the map: how much of what a
// scanner at a candidate would return lies on surfaces already mapped, which is
// what registration needs (docs/nbv.md, "Registration-safe candidates").
#pragma once

#include <cstddef>

#include "semioctree/nbv/params.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct OverlapPrediction {
  // Share of the returns on mapped surfaces, each return weighted by the square of its
  // range (the surface area a ray stands for, as the registration's voxel-downsampled
  // clouds count area); 0 when no ray returns.
  double share = 0;
  double unweighted_share = 0;  // the same share counting every return alike
  std::size_t rays = 0;         // rays cast
  std::size_t mapped = 0;       // of which ending on an occupied leaf
  std::size_t unmapped = 0;     // of which entering space the map has not seen
};

// Casts rays from `scanner` over the scanner's field of view (all azimuths, its
// elevation limits), `step_deg` apart on the sphere, up to its maximum range, through
// the tree. Free, out, door and window octants are passed, and so is unseen space
// (occluded or unknown) that the ray leaves into free space again: on its line that
// space was air. A ray ends mapped on an occupied leaf reached from free space (or
// through less than `tolerance` metres of unseen space); unmapped when it reaches an
// occupied leaf or space the map holds nothing of (no coarse voxel) through more unseen
// space than that, its range counted from where it entered that space (the surface
// facing it lies there, and nothing has seen it), or when it leaves the band through
// such space (a return from outside the room: ground below a window, a building above
// the map's top), its range counted to the band. Rays that meet nothing but free space
// before the band (floor and ceiling returns, which preprocessing cuts) or the maximum
// range, and mapped returns nearer than the minimum range, are no returns. `threads` as
// NbvParams::threads. Throws std::invalid_argument for step_deg <= 0 or top_z <= floor_z.
OverlapPrediction predict_overlap(const SemiOcTree& tree, const Point3& scanner,
                                  const ScannerView& limits, double floor_z, double top_z,
                                  double tolerance, double step_deg = 1.5, unsigned threads = 0);

// The prediction the NBV makes with `params` (NbvParams::overlap_top must be set): the
// band from the floor (z = 0) to overlap_top, a tolerance of two leaves, the params'
// ray step, scanner limits and threads. Throws std::invalid_argument without overlap_top.
OverlapPrediction predict_overlap(const SemiOcTree& tree, const Point3& scanner,
                                  const NbvParams& params);
// The number of rays that prediction casts (0 for a step that is not > 0).
std::size_t prediction_rays(const NbvParams& params);

}  // namespace semioctree
