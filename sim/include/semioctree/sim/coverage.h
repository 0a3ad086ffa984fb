// Survey coverage (simulation only): which of the scene's ground-truth surface samples a
// survey measured, as a percentage of the samples that a dense grid of scan positions
// over the survey area could see at all. That reference is computed with the scanner's
// visibility rule, less what is seen only through a door or window (the pipeline labels
// that space `out`), and cached per scene.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/sim/ground_truth.h"

namespace semioctree::sim {

// The surface samples that are visible from at least one scan position of a grid.
struct CoverageReference {
  double grid_spacing = 0.5;     // metres between scan positions
  double sample_spacing = 0.02;  // spacing passed to GroundTruth::surface_samples
  std::size_t sample_count = 0;  // all surface samples of the scene at that spacing
  // Optical centres of the grid positions (world frame, z = scanner height): on a grid
  // anchored at robot.start, inside the survey area, where the robot can stand and can
  // drive to from robot.start (FloorPlan::reachable): a pocket it fits in but cannot
  // enter is no scan position of any survey.
  std::vector<Eigen::Vector3d> positions;
  // Indices into GroundTruth::surface_samples(sample_spacing) of the visible samples,
  // ascending, and their positions (what measure_coverage compares with).
  std::vector<std::uint32_t> visible;
  std::vector<Eigen::Vector3d> points;

  std::string key;  // hash of everything the result depends on (coverage_cache_key)
  bool from_cache = false;
  std::string cache_file;             // the file read or written ("" if none)
  std::uint64_t segment_queries = 0;  // ray-caster queries made (0 when loaded)
  double seconds = 0.0;               // wall time of this call (compute or load)
};

// Visibility of a sample p from a scan position with optical centre c (the rule of the
// reference): p lies within the scanner's range limits [min_range, max_range] and
// elevation limits [elevation_min_deg, elevation_max_deg] seen from c, faces c
// (dot(normal, c − p) > 0), and the segment from c to p + kCoverageSampleOffset · normal
// crosses no geometry and does not pass through a door or window opening
// (segment_through_opening). So space beyond an opening (a corridor, the next room, the
// street outside a window) is not in the reference even where a scan position sees it
// through the hole, while the opening's own jambs, sill and lintel are, as seen from the
// room: a segment that ends on them enters the hole without leaving it.
constexpr double kCoverageSampleOffset = 0.005;
bool sample_visible_from(const GroundTruth& truth, const SurfaceSample& sample,
                         const Eigen::Vector3d& optical_centre);

// The same rule without the condition on openings: what the scanner itself measures.
bool sample_in_line_of_sight(const GroundTruth& truth, const SurfaceSample& sample,
                             const Eigen::Vector3d& optical_centre);

// True if the segment a→b passes through a door or window of the scene: its ends lie
// strictly beyond the two faces of a wall, on opposite sides, and it crosses each face
// (the plane of the opening's rectangle of opening_rects, offset by ±thickness/2 along the
// wall normal) within an opening of that wall — the same opening, unless two openings
// touch and make one hole (the rectangles cut to the wall's extent, 1 mm tolerance: a
// segment that close to the edge is through the hole or blocked by the jamb anyway). A
// segment with an end inside the hole (on a jamb, the sill or the lintel) or on a face
// plane crosses at most one face and does not pass through. A cheap test: a few dot
// products per wall, no ray query.
bool segment_through_opening(const Scene& scene, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b);

// The scan positions of the reference grid (see CoverageReference::positions).
std::vector<Eigen::Vector3d> coverage_grid_positions(const GroundTruth& truth,
                                                     double grid_spacing = 0.5);

// Computes the reference on `threads` threads (0: one per hardware thread). The result
// does not depend on the number of threads, and is sample_visible_from applied to every
// sample and position: where a wall decides it (every segment from a group of positions
// to a sample crosses the wall through a hole or, a millimetre or more from any edge,
// through its solid part) the ray query is skipped, which leaves out most of the
// surfaces behind the room's walls at little cost.
CoverageReference compute_coverage_reference(const GroundTruth& truth, double grid_spacing = 0.5,
                                             double sample_spacing = 0.02, unsigned threads = 0);

// Cache key: a hash of the surface samples, the scene's triangles, the scanner and robot
// parameters, the survey area, both spacings and the version of the visibility rule. Any
// change to the scene gives another key (and file name), so a stale file is never used.
std::string coverage_cache_key(const GroundTruth& truth, double grid_spacing = 0.5,
                               double sample_spacing = 0.02);

// `<cache_dir>/coverage-<key>.bin` if present and intact (size, header, key and checksum
// are checked), else computes the reference and writes that file (temporary name, then
// rename; a cache that cannot be written is not an error, cache_file is then ""). An
// empty `cache_dir` means no cache: the reference is computed and nothing is written.
CoverageReference load_or_compute_coverage_reference(const GroundTruth& truth,
                                                     const std::string& cache_dir,
                                                     double grid_spacing = 0.5,
                                                     double sample_spacing = 0.02,
                                                     unsigned threads = 0);

// $XDG_CACHE_HOME/semioctree if XDG_CACHE_HOME is set to an absolute path, else
// $HOME/.cache/semioctree, else <temp dir>/semioctree-cache. Not created here.
std::string default_cache_dir();

struct Coverage {
  std::size_t reference_points = 0;
  std::size_t covered = 0;  // reference samples with a measured point within the tolerance
  double percent = 0.0;     // 100 · covered / reference_points (0 for an empty reference)
};

// Counts the reference samples with a measured point (world frame) within `tolerance`
// metres. Non-finite points are ignored.
Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3d>& measured_points_world,
                          double tolerance = 0.03);
Coverage measure_coverage(const CoverageReference& reference,
                          const std::vector<Eigen::Vector3f>& measured_points_world,
                          double tolerance = 0.03);

// The counts of covered_samples' flags (what measure_coverage returns).
Coverage count_covered(const std::vector<bool>& covered);

// One flag per reference sample (in the order of reference.points): a measured point
// (world frame) within `tolerance` metres. measure_coverage counts these flags.
std::vector<bool> covered_samples(const CoverageReference& reference,
                                  const std::vector<Eigen::Vector3f>& measured_points_world,
                                  double tolerance = 0.03);

// Why a survey missed the reference samples it did not cover, from the optical centres of
// its scans (world frame, true poses). A missed sample is either in view of some scan (the
// reference's rule, sample_visible_from: facing it, within the scanner's limits, nothing in
// the way) and so sampled too sparsely there, too far or too oblique for the angular step;
// or hidden from every scan: the survey never stood where it could be seen. Per scene
// element too, so that a survey's misses can be found in the scene.
struct MissedPart {
  PartRef part;
  std::string label;  // the element's place in the scene file, e.g. "boxes[2] (bench-3)"
  std::size_t in_view = 0;
  std::size_t hidden = 0;
};
struct MissedSamples {
  std::size_t in_view = 0;
  std::size_t hidden = 0;
  std::vector<MissedPart> parts;  // elements with missed samples, most missed first
  // The missed samples themselves, as indices into reference.points, ascending: where to
  // look in the scene (the survey writes them as coverage_missed.ply).
  std::vector<std::uint32_t> in_view_samples;
  std::vector<std::uint32_t> hidden_samples;
};

// `covered` is covered_samples of the survey's points (one flag per reference sample).
// Throws std::invalid_argument if it does not match the reference, or if the reference was
// not made from this scene's samples (their count differs).
MissedSamples explain_missed_samples(const GroundTruth& truth, const CoverageReference& reference,
                                     const std::vector<bool>& covered,
                                     const std::vector<Eigen::Vector3d>& optical_centres,
                                     unsigned threads = 0);

// "boxes[2] (bench-3)": where a scene element is in the scene file, with its name if any.
std::string part_label(const Scene& scene, const PartRef& part);

// Survey plans made with perfect knowledge of what each scan position would cover: an
// upper reference for a planner that only knows what it has scanned so far.
// `covered[v]` holds the covered_samples of a scan from position v (all the same size).
struct CoveragePlan {
  std::vector<std::size_t> views;  // positions, in scan order; views[0] is the given first
  double percent = 0.0;            // samples covered by their union, % of all samples
};

// Greedy: after `first`, each scan is the position that adds most samples (lowest index on
// ties), until `scans` scans. Throws std::invalid_argument on empty or unequal sets.
CoveragePlan greedy_coverage_plan(const std::vector<std::vector<bool>>& covered, std::size_t first,
                                  std::size_t scans);

// Local search from `plan`: replaces one scan (never views[0]) at a time by the position
// that covers most together with the others, while that strictly improves the union. The
// result covers at least as much as `plan`; it is a local optimum, not necessarily the best.
CoveragePlan improve_coverage_plan(const std::vector<std::vector<bool>>& covered,
                                   CoveragePlan plan);

}  // namespace semioctree::sim
