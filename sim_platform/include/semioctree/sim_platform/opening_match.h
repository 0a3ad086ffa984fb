// Detected doors and windows (the pipeline's DetectedOpening) against a scene's true
// openings (sim::OpeningRect): overlap in the wall plane, a one-to-one matching, and
// precision and recall. docs/generated-scenes.md tells which truths a survey is held to.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "semioctree/openings.h"
#include "semioctree/sim/ground_truth.h"

namespace semioctree::sim_platform {

// Intersection over union of the two rectangles in the true opening's wall plane (along
// the wall and in z); 0 for another kind, a wall not parallel (normals more than ~18°
// apart) or a plane more than 0.3 m away. `world_to_detection` takes the scene's frame to
// the detection's (the survey frame, a levelled scan's frame).
double opening_iou(const DetectedOpening& detected, const sim::OpeningRect& truth,
                   const Eigen::Isometry3d& world_to_detection);

struct OpeningsMatch {
  std::size_t detections = 0, truths = 0;
  std::size_t matched = 0;            // pairs with IoU ≥ the threshold, one-to-one
  double precision = 1.0;             // matched / detections (1 with no detection)
  double recall = 1.0;                // matched / truths (1 with no truth)
  std::vector<double> truth_iou;      // per truth: IoU of its match, 0 if none
  std::vector<double> detection_iou;  // per detection: IoU of its match, 0 if none
};

// Pairs detections with truths greedily by decreasing IoU, each used once, pairs below
// `min_iou` left unmatched.
OpeningsMatch match_openings(const std::vector<DetectedOpening>& detected,
                             const std::vector<sim::OpeningRect>& truths,
                             const Eigen::Isometry3d& world_to_detection, double min_iou = 0.5);

// The true openings in the walls around room `room` of `plan` (FloorPlan::room ids): those
// with that room on one side of the wall, 0.1 m beyond its face.
std::vector<sim::OpeningRect> openings_of_room(const sim::GroundTruth& truth,
                                               const sim::FloorPlan& plan, int room);

}  // namespace semioctree::sim_platform
