// Predicted overlap of a candidate's scan with the map (src/nbv/overlap.cpp) on hand-built
// rooms whose answer is known, and the NBV passing over candidates predicted too low.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "semioctree/nbv.h"
#include "support/nbv_maps.h"

namespace semioctree {
namespace {

using testing::kLeaf;
using testing::Map;

constexpr double kTolerance = 0.1;  // m, two leaves

// A 4.8 × 4.8 × 2.4 m room of occupied walls, free inside; `open_east`: no east wall,
// and no map beyond it (space never seen).
struct Room : Map {
  explicit Room(bool open_east) : Map(6, 6, 3) {
    leaves({0, 0, 0}, {4.8, kLeaf, 2.4}, Label::kOccupied);
    leaves({0, 4.8 - kLeaf, 0}, {4.8, 4.8, 2.4}, Label::kOccupied);
    leaves({0, 0, 0}, {kLeaf, 4.8, 2.4}, Label::kOccupied);
    if (!open_east) leaves({4.8 - kLeaf, 0, 0}, {4.8, 4.8, 2.4}, Label::kOccupied);
  }
};

ScannerView all_round(double max_range = 60) {
  ScannerView v;
  v.min_range = 0.3;
  v.max_range = max_range;
  v.elevation_min_deg = -60;
  v.elevation_max_deg = 60;
  return v;
}

const Point3 kCentre(2.4, 2.4, 1.2);

TEST(NbvOverlap, EveryReturnOfAClosedRoomIsMapped) {
  Room room(false);
  const OverlapPrediction p =
      predict_overlap(room.t, kCentre, all_round(), 0.0, 2.4, kTolerance, 1.5, 2);
  EXPECT_EQ(p.unmapped, 0u);
  EXPECT_GT(p.mapped, 1000u);
  EXPECT_DOUBLE_EQ(p.share, 1.0);
  EXPECT_DOUBLE_EQ(p.unweighted_share, 1.0);
  // Rays that meet floor or ceiling first (±60° from 1.2 m: the steep ones) are no
  // returns: preprocessing cuts those.
  EXPECT_LT(p.mapped, p.rays);
}

// One wall of four missing, nothing mapped behind it: by symmetry a quarter of the
// returns (by count and by area) come from space the map has not seen.
TEST(NbvOverlap, AWallNeverSeenIsAQuarterOfASquareRoom) {
  Room room(true);
  const OverlapPrediction p =
      predict_overlap(room.t, kCentre, all_round(), 0.0, 2.4, kTolerance, 1.0, 2);
  EXPECT_NEAR(p.share, 0.75, 0.02);
  EXPECT_NEAR(p.unweighted_share, 0.75, 0.02);
  EXPECT_GT(p.unmapped, 0u);
}

// Unseen space thinner than the tolerance in front of a wall (a leaf of occluded space
// the occlusion study left) does not hide the mapped wall behind it; thicker, it does.
TEST(NbvOverlap, UnseenSpaceCountsOnlyBeyondTheTolerance) {
  Room thin(false);
  thin.leaves({4.8 - 2 * kLeaf, 0, 0}, {4.8 - kLeaf, 4.8, 2.4}, Label::kOccluded);
  EXPECT_DOUBLE_EQ(
      predict_overlap(thin.t, kCentre, all_round(), 0.0, 2.4, kTolerance, 1.5, 2).share, 1.0);
  Room thick(false);
  thick.leaves({4.8 - 8 * kLeaf, 0, 0}, {4.8 - kLeaf, 4.8, 2.4}, Label::kOccluded);
  const double share =
      predict_overlap(thick.t, kCentre, all_round(), 0.0, 2.4, kTolerance, 1.5, 2).share;
  EXPECT_GT(share, 0.65);
  EXPECT_LT(share, 0.85);
}

TEST(NbvOverlap, NothingWithinRangeIsNoReturn) {
  Room room(false);
  const OverlapPrediction p =
      predict_overlap(room.t, kCentre, all_round(1.0), 0.0, 2.4, kTolerance, 1.5, 2);
  EXPECT_EQ(p.mapped + p.unmapped, 0u);
  EXPECT_EQ(p.share, 0.0);
}

TEST(NbvOverlap, ThreadCountDoesNotChangeTheResult) {
  Room room(true);
  const OverlapPrediction a =
      predict_overlap(room.t, Point3(1.3, 3.1, 1.2), all_round(), 0.0, 2.4, kTolerance, 1.5, 1);
  const OverlapPrediction b =
      predict_overlap(room.t, Point3(1.3, 3.1, 1.2), all_round(), 0.0, 2.4, kTolerance, 1.5, 3);
  EXPECT_EQ(a.mapped, b.mapped);
  EXPECT_EQ(a.unmapped, b.unmapped);
  EXPECT_DOUBLE_EQ(a.share, b.share);
}

TEST(NbvOverlap, BadBandOrStepIsRefused) {
  Room room(false);
  EXPECT_THROW(predict_overlap(room.t, kCentre, all_round(), 0.0, 2.4, kTolerance, 0.0),
               std::invalid_argument);
  EXPECT_THROW(predict_overlap(room.t, kCentre, all_round(), 2.4, 2.4, kTolerance),
               std::invalid_argument);
}

// An occluded target by the open side of the room, and a wall hiding it from some of
// the candidates (which then see little of the map); the NBV's parameters that predict
// the overlap on this room.
void hide_a_target(Room& room) {
  room.set(4.4, 2.4, 1.0, 2, Label::kOccluded);
  room.leaves({3.6, 1.6, 0}, {3.65, 3.2, 2.4}, Label::kOccupied);
}
NbvParams predicting_params() {
  NbvParams p;
  p.candidate_spacing = 0.4;
  p.limits = all_round();
  p.overlap_top = 2.4;
  return p;
}

// The NBV with a minimum predicted overlap passes over the best-scoring candidates below
// it, best first; with a minimum nothing reaches there is no best.
TEST(NbvOverlap, CandidatesPredictedTooLowArePassedOver) {
  Room room(true);
  hide_a_target(room);
  NbvParams p = predicting_params();
  const Point3 robot(1.2, 2.4, 0);
  const NbvResult free = next_best_view(room.t, RobotGeometry{}, robot, {}, p);
  ASSERT_TRUE(free.best && free.best_overlap);
  EXPECT_EQ(free.low_overlap, 0u);
  EXPECT_DOUBLE_EQ(*free.best->predicted_overlap, free.best_overlap->share);
  // Ask for a little more than the best one has.
  p.min_overlap = free.best_overlap->share + 0.02;
  const NbvResult safe = next_best_view(room.t, RobotGeometry{}, robot, {}, p);
  ASSERT_TRUE(safe.best && safe.best_overlap);
  EXPECT_GE(safe.low_overlap, 1u);
  EXPECT_GE(safe.best_overlap->share, p.min_overlap);
  EXPECT_LE(safe.best->score, free.best->score);
  // Every candidate scoring above the chosen one was tried and found too low.
  std::size_t above = 0;
  for (const NbvCandidate& c : safe.candidates)
    if (c.score > safe.best->score) {
      ++above;
      ASSERT_TRUE(c.predicted_overlap);
      EXPECT_LT(*c.predicted_overlap, p.min_overlap);
    }
  EXPECT_GE(safe.low_overlap, above);
  // Nothing reaches 101 %: no best, every candidate that sees the target tried; those
  // that see nothing are not (as the best they would only end the survey).
  p.min_overlap = 1.01;
  const NbvResult none = next_best_view(room.t, RobotGeometry{}, robot, {}, p);
  EXPECT_FALSE(none.best);
  std::size_t seeing = 0;
  for (const NbvCandidate& c : none.candidates) {
    seeing += c.score > 0;
    EXPECT_EQ(c.predicted_overlap.has_value(), c.score > 0);
  }
  EXPECT_GT(seeing, 0u);
  EXPECT_LT(seeing, none.candidates.size());
  EXPECT_EQ(none.low_overlap, seeing);
}

// A room with nothing left to see: the best candidate scores 0 and is taken without a
// prediction, whatever the minimum (Eq 5 is 0 there: the survey is done).
TEST(NbvOverlap, ARoomWithNothingLeftToSeeStillHasItsBest) {
  Room room(false);
  NbvParams p;
  p.candidate_spacing = 0.4;
  p.limits = all_round();
  p.overlap_top = 2.4;
  p.min_overlap = 1.01;
  const NbvResult r = next_best_view(room.t, RobotGeometry{}, Point3(1.2, 2.4, 0), {}, p);
  ASSERT_TRUE(r.best);
  EXPECT_EQ(r.best->score, 0.0);
  EXPECT_FALSE(r.best_overlap);
  EXPECT_EQ(r.low_overlap, 0u);
  EXPECT_EQ(r.stop_percent, 0.0);
}

// Predicting every candidate's overlap first and scoring only those predicted to register
// (NbvParams::predict_first_factor) chooses what predicting after scoring chooses: the
// same best, prediction and Eq 5, with fewer candidates scored; no best when none is safe;
// the unpredicted best when nothing is left to see.
TEST(NbvOverlap, PredictingFirstChoosesTheSameBest) {
  Room room(true);
  hide_a_target(room);
  NbvParams p = predicting_params();
  const Point3 robot(1.2, 2.4, 0);
  const NbvResult free = next_best_view(room.t, RobotGeometry{}, robot, {}, p);
  ASSERT_TRUE(free.best_overlap);
  p.min_overlap = free.best_overlap->share + 0.02;
  auto with_factor = [&](double factor) {
    NbvParams q = p;
    q.predict_first_factor = factor;
    return next_best_view(room.t, RobotGeometry{}, robot, {}, q);
  };
  const NbvResult after = with_factor(std::numeric_limits<double>::infinity());
  const NbvResult first = with_factor(0.0);
  ASSERT_TRUE(after.best && first.best && after.best_overlap && first.best_overlap);
  EXPECT_EQ(first.best->position.x, after.best->position.x);
  EXPECT_EQ(first.best->position.y, after.best->position.y);
  EXPECT_DOUBLE_EQ(first.best->score, after.best->score);
  EXPECT_DOUBLE_EQ(first.best_overlap->share, after.best_overlap->share);
  EXPECT_DOUBLE_EQ(first.stop_percent, after.stop_percent);
  EXPECT_GE(first.low_overlap, after.low_overlap);
  EXPECT_LT(first.scoring.segments, after.scoring.segments);
  // Every candidate has its prediction, and only those predicted to register a score.
  for (const NbvCandidate& c : first.candidates) {
    ASSERT_TRUE(c.predicted_overlap);
    if (*c.predicted_overlap < p.min_overlap) {
      EXPECT_EQ(c.score, 0.0);
    }
  }
  // Nothing reaches 101 %: no best either way.
  p.min_overlap = 1.01;
  EXPECT_FALSE(with_factor(0.0).best);
  EXPECT_FALSE(with_factor(std::numeric_limits<double>::infinity()).best);
  // Nothing left to see: the best scores 0 and is taken unpredicted either way.
  Room empty(false);
  NbvParams e = p;
  e.predict_first_factor = 0.0;
  const NbvResult done = next_best_view(empty.t, RobotGeometry{}, robot, {}, e);
  ASSERT_TRUE(done.best);
  EXPECT_EQ(done.best->score, 0.0);
  EXPECT_FALSE(done.best_overlap);
  EXPECT_EQ(done.low_overlap, 0u);
}

}  // namespace
}  // namespace semioctree
