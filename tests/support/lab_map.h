// The lab after its first scan as the benchmarks map it: the scan (lab_scan.h) levelled and
// decimated to ~400 000 points (preprocess), and the classified map built from it
// (discretize, openings, occlusion study) at 0.05 m.
#pragma once

#include <chrono>
#include <memory>

#include "semioctree/discretize.h"
#include "semioctree/occlusion.h"
#include "semioctree/openings.h"
#include "semioctree/preprocess.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "support/lab_scan.h"

namespace semioctree::testing {

struct PreprocessedLab {
  std::size_t scan_points = 0;  // before preprocessing
  PreprocessResult pre;
  Point3 origin;  // the scanner's optical centre, levelled frame
  // With `with_returns`: where the scan got returns, and its depths, as a survey's view of
  // it holds them (the lab scanner's limits; open above if no ceiling was found).
  std::shared_ptr<const ReturnDirections> returns;
};

inline PreprocessedLab preprocessed_lab(bool with_returns = false) {
  const LabScan lab = scan_lab();
  PreprocessParams pp;
  pp.target_points = 400000;
  PreprocessedLab out;
  out.scan_points = lab.world.size();
  out.pre = preprocess(lab.world, pp);
  const Eigen::Vector3d o = out.pre.transform * lab.origin;
  out.origin = Point3(o.x(), o.y(), o.z());
  if (with_returns) {
    const sim::Scene scene =
        sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
    Cloud seen;  // the returns from the optical centre, world axes
    seen.reserve(lab.world.size());
    for (const auto& p : lab.world)
      seen.push_back(pcl::PointXYZ{float(p.x - lab.origin.x()), float(p.y - lab.origin.y()),
                                   float(p.z - lab.origin.z())});
    out.returns = return_directions(
        seen, out.pre.transform.linear(),
        returns_options(sim_platform::scanner_limits(scene), !out.pre.ceiling_found));
  }
  return out;
}

// The classified map at leaf 0.05 m with coarse voxels of `coarse` (0.05: the
// homogeneous grid, k = 0) over the same region (the extent snapped to 0.8 m): occupancy,
// doors and windows, the occlusion study from the scan's position on `threads` threads (0:
// one per core), compacted. `seconds`: its wall time, if given.
inline std::unique_ptr<SemiOcTree> classified_lab_map(const PreprocessedLab& lab, double coarse,
                                                      unsigned threads = 0,
                                                      double* seconds = nullptr) {
  const auto t0 = std::chrono::steady_clock::now();
  auto tree = discretize(*lab.pre.cloud, lab.pre.ceiling_height, {0.05, coarse, 0.8});
  const auto openings =
      detect_openings(*lab.pre.cloud, lab.pre.ceiling_height, *tree, {lab.origin});
  label_openings(*tree, openings);
  OcclusionParams op;
  op.threads = threads;
  study_occlusion(*tree, {ScannerView{lab.origin}}, op);
  tree->compact();
  if (seconds)
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return tree;
}

}  // namespace semioctree::testing
