// Stage 5 (paper 2.2.3): the occlusion study. Labels every non-occupied octant
// empty (seen directly from a scanner position), out (seen only through a door
// or window) or occluded (hidden from every position), by casting segments
// through the SemiOcTree; partly visible octants are split down to the leaf.
// The rules (sample points, scopes, doorway scans, return directions): docs/occlusion.md.
#pragma once

#include <octomap/OcTree.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/scan_io.h"

namespace semioctree {

// The space around a scanner that only its platform occupies: a vertical cylinder about
// the optical centre's axis, `radius` wide, from `below` under the optical centre to
// `above` over it (a robot's safety cylinder above its ground clearance). All 0: none.
struct PlatformBody {
  double radius = 0, below = 0, above = 0;  // m
};

// The directions in which a scan got returns, seen from its optical centre in the map
// frame: rows of 1° of elevation, each cut into bins about 1° wide (fewer towards the
// poles, so that every bin spans about 1° × 1° and a sparse scan fills the rows near
// the zenith too). A surface nearer than the scanner's minimum range gives no returns
// (the scanner drops them), so the map holds no occupied leaves there: without this the
// study's lines passed through it (a scan taken in a doorway saw through its jambs into
// the wall and beyond). A line in a direction without returns is hidden. With their
// neighbours (close_gaps) the bins tolerate scans as sparse as about 1°; a hole in the
// returns must span a few degrees to count.
class ReturnDirections {
 public:
  ReturnDirections();
  // `d`: from the optical centre, map frame, any length > 0 (a zero or non-finite
  // vector is ignored).
  void add(const Eigen::Vector3d& d);
  // After the last add: a bin next to one with returns (in its row or the rows above
  // and below) counts as having them, so that a bin the scan's angular step happens to
  // skip is no hole.
  void close_gaps();
  // For a scan open above (no ceiling found: open-plan, an atrium, a ceiling beyond the
  // scanner's range): every direction above the horizon that lies above the highest
  // return of its azimuth counts as having returns. Its beam went over everything the
  // scan saw and met nothing within range: the space along it is free, not hidden.
  // Below the highest return (a window, a door) a direction without returns stays hidden.
  void open_above();
  // For a scan taken from a platform: every direction whose segment from the optical
  // centre to `min_range` lies inside `body` counts as having returns. Only the platform
  // occupies its body (and the elevation limits keep the scanner's beam off the
  // platform), so no surface can lie nearer than the minimum range there: a direction
  // without returns met nothing within the maximum range (an opening, the open sky),
  // and the space along it is free, not hidden. A body narrower than the minimum range
  // opens only the steep directions it holds (docs/occlusion.md).
  void open_within(const PlatformBody& body, double min_range);
  // For a scan taken where the map of the scans before already holds the space around
  // it: every direction without returns whose segment from `optical_centre` to
  // `min_range` lies in space `map` holds as free (seen empty, directly or through an
  // opening, or an opening's own octants) counts as having returns. As in open_within,
  // nothing can lie nearer than the minimum range there, so the beam met nothing within
  // the maximum range: it left through a window or a door the map does not see beyond.
  // A bin is judged by its centre direction.
  void open_where_free(const SemiOcTree& map, const Point3& optical_centre, double min_range);
  // For any scan: every hole in the returns (a connected region of directions that got
  // none, judged before close_gaps) whose edge returns all lie at least twice the
  // minimum range away, and which stays within the elevation limits, counts as having
  // returns. A surface nearer than the minimum range that hid the hole would cross the
  // minimum range at the hole's edge (a wall, a jamb, a post: returns there lie just
  // beyond it) unless it floats wholly inside the hole's cone, held by nothing thicker
  // than the scan's step: the beam left through an opening (docs/occlusion.md).
  // Needs the nearest returns add_scan records.
  void open_far_edged_holes(double min_range, double elevation_min_deg, double elevation_max_deg);
  bool has(double dx, double dy, double dz) const;
  std::size_t bins_with_returns() const;

  // Adds the direction of every return of a scan (given in the scanner's frame, optical
  // centre at the origin, turned into the map frame by `scanner_to_map`) and records how
  // far the scan saw in each direction: per bin of about twice the scan's angular step (k
  // bins a degree, k from how many returns a 1° bin holds: 1 ≤ k ≤ 8), the depth beyond
  // which every beam of the bin had met a surface. That is the bin's farthest return
  // plus the spread of its returns (a beam between two of the bin's may reach that much
  // further on a surface seen at a grazing angle); a bin with fewer than 4 returns
  // records none. Replaces the depths recorded before. `threads`: 0, one per core.
  // `expected_depth_bins_per_degree`: the k this scan is expected to get (the scan
  // before's, say; 0: none). When it is right the returns are read once, not twice; the
  // result is the same either way.
  void add_scan(const Cloud& scan, const Eigen::Matrix3d& scanner_to_map, unsigned threads = 0,
                int expected_depth_bins_per_degree = 0);
  // Whether a point at (dx, dy, dz) from the optical centre (map frame) lies more than
  // `tolerance` (m) beyond the depth of its bin: every beam around its direction met a
  // surface before it, so the scan cannot have seen it, whatever the map holds there.
  bool behind_surface(double dx, double dy, double dz, double tolerance) const;
  // has(dx, dy, dz) and not behind_surface(dx, dy, dz, tolerance), in one look-up of the
  // direction (true for a zero vector: the optical centre itself).
  bool may_see(double dx, double dy, double dz, double tolerance) const;
  // may_see for each of n vectors (out[i] = 1 or 0): the same answers, the angles and bins
  // worked out lanes at a time.
  void may_see_each(std::size_t n, const double* dx, const double* dy, const double* dz,
                    double tolerance, std::uint8_t* out) const;
  // The depths' bins per degree (0: no depths recorded).
  int depth_bins_per_degree() const { return depth_per_degree_; }

  // may_see over every point of a box given by its corners lo ≤ hi relative to the
  // optical centre (map frame): `all` when it holds for every one, `none` when for none
  // (judged on the bins the box's directions touch, returns by the degree and depths by
  // their own bins: both are false when some bins disagree, or when the box holds the
  // optical centre).
  struct BoxSight {
    bool all = false, none = false;
  };
  BoxSight may_see_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                       double tolerance) const;

 private:
  std::vector<std::uint8_t> bins_;
  int depth_per_degree_ = 0;
  std::vector<std::uint16_t> depth_cm_;  // per depth bin, rounded up; 0: none
  // Per row of the depth bins, runs of kDepthRun columns (from the row's first): the least
  // and the greatest of their depths and whether one has none (0 or the largest value),
  // so that may_see_box reads a long run of a row a summary at a time.
  static constexpr int kDepthRun = 16;
  struct DepthSummary {
    std::uint16_t least = 65535, greatest = 0;  // among the depths recorded (none: these)
    bool some_missing = false;
    void add(std::uint16_t cm) {  // without a branch: rows are summarized in lane loops
      const bool none = cm == 0 || cm == 65535;  // (as beyond_depth)
      some_missing |= none;
      least = std::min(least, none ? std::uint16_t(65535) : cm);
      greatest = std::max(greatest, none ? std::uint16_t(0) : cm);
    }
    void add(const DepthSummary& o) {
      least = std::min(least, o.least);
      greatest = std::max(greatest, o.greatest);
      some_missing |= o.some_missing;
    }
  };
  std::vector<DepthSummary> depth_runs_;
  std::vector<std::uint32_t> first_depth_run_;  // per row of the depth bins
  // Per 1° bin, the summary of the depth bins that may hold any of its directions (with a
  // bin's margin around it), so that may_see_box first reads a box's depths a degree at a
  // time: a bound on them, not their value.
  std::vector<DepthSummary> degree_depths_;
  void summarize_degree_depths();
  // Adds to `s` the depths of columns c0 ≤ c ≤ c1 (c1 < the row's count) of a row of depth
  // bins, given its depths and its runs' summaries.
  static void summarize_depths(const std::uint16_t* row, const DepthSummary* runs, int c0, int c1,
                               DepthSummary& s);
  // may_see's depth test: a point at `length` in depth bin `depth_bin` (depths recorded)
  // lies no more than `tolerance` beyond its depth.
  bool within_depth(int depth_bin, double length, double tolerance) const;
  std::vector<std::uint16_t> nearest_cm_;  // per bin, the nearest return, rounded down; 0: none
};

// How return_directions completes the directions of a scan.
struct ReturnDirectionsOptions {
  bool open_above = false;  // the scan found no ceiling: open_above()
  PlatformBody body;        // the platform it was taken from: open_within(body, min_range)
  double min_range = 0.6;   // the scanner's minimum range, m
  // The scanner's elevation limits (degrees, 0 = horizontal) and whether holes with far
  // edges open: open_far_edged_holes(min_range, elevation_min_deg, elevation_max_deg).
  double elevation_min_deg = -60, elevation_max_deg = 90;
  bool open_far_edged_holes = true;
  // The map of the scans before and the scan's optical centre in it:
  // open_where_free(*map, optical_centre, min_range). Null: not used (a first scan).
  const SemiOcTree* map = nullptr;
  Point3 optical_centre;
  unsigned threads = 0;  // reading the scan's returns (0: one per core)
  // add_scan's expected k (the scan before's depth_bins_per_degree(); 0: none): reads
  // the returns once instead of twice when right, the same result either way.
  int expected_depth_bins_per_degree = 0;
};

// The returns of a scan given in the scanner's frame (optical centre at the origin),
// turned into the map frame by `scanner_to_map` (its translation is ignored), gaps closed,
// then opened as `options` say (open_above, open_within, open_where_free); with their
// depths (add_scan).
std::shared_ptr<const ReturnDirections> return_directions(
    const Cloud& scan, const Eigen::Matrix3d& scanner_to_map,
    const ReturnDirectionsOptions& options = {});

struct ScannerView {
  ScannerView() = default;
  explicit ScannerView(const Point3& optical_centre) : position(optical_centre) {}

  Point3 position;                 // optical centre, map frame
  double min_range = 0.6;          // m
  double max_range = 60.0;         // m
  double elevation_min_deg = -60;  // 0 = horizontal
  double elevation_max_deg = 90;
  // Where the scan got returns; null: in every direction (the paper's assumption, and
  // all a map without its scans, such as an OctoMap map, can say).
  std::shared_ptr<const ReturnDirections> returns;
};

// Options for a scan whose platform is not known (a tripod, a file): the scanner's
// limits and open_above; no body, no map.
inline ReturnDirectionsOptions returns_options(const ScannerView& limits, bool open_above) {
  ReturnDirectionsOptions o;
  o.open_above = open_above;
  o.min_range = limits.min_range;
  o.elevation_min_deg = limits.elevation_min_deg;
  o.elevation_max_deg = limits.elevation_max_deg;
  return o;
}

struct MapReturnsReport {
  bool origin_free = false;      // the map holds the optical centre's leaf as free
  std::size_t bins_tested = 0;   // bins within the scanner's elevation limits
  std::size_t bins_reached = 0;  // of which a ray reached an occupied leaf (before gaps closed)
};

// The directions in which a scan from `optical_centre` got returns, read from an
// occupancy map that was built by casting its rays (OctoMap's insertPointCloud, or
// octomap_server): one ray per bin (its centre direction, within the elevation limits of
// `limits`), cast with OctoMap's castRay through the space the map holds as free, has
// returns if it reaches an occupied leaf within max_range; one that meets space the map
// does not hold got none, since every return would have carved its ray free. A map of
// several scans may have carved a direction with another scan's rays, which only makes a
// direction count as having returns (as if no directions were known). A map holding no
// free space around the optical centre says nothing: see MapReturnsReport.
std::shared_ptr<const ReturnDirections> return_directions_in_map(
    const octomap::OcTree& map, const Point3& optical_centre, const ScannerView& limits,
    unsigned threads = 0, MapReturnsReport* report = nullptr);

enum class Visibility : std::uint8_t { kHidden = 0, kThroughOpening = 1, kDirect = 2 };

// Which octants a study (re)classifies.
enum class OcclusionScope : std::uint8_t {
  // Every empty, occluded, out or unknown octant, from all the views given.
  kAll,
  // Only unknown octants (space new to the map), from all the views given.
  kUnknown,
  // Only occluded and out octants, from the views given (the new scanner
  // positions), keeping what their label already says: occluded means hidden
  // from the earlier positions, out means seen through an opening. The direct
  // view from a new position wins, so out can become empty and occluded
  // anything (docs/data-flow.md, later scans).
  kNewViews,
  // Only empty octants: those seen through a door or window, and not directly,
  // become out; the rest stay empty. For a map whose free space was known
  // before its openings were labelled (an imported OctoMap map): what was seen
  // through them lies outside the room.
  kFreeThroughOpenings,
};

struct OcclusionParams {
  OcclusionScope scope = OcclusionScope::kAll;
  // false: an octant larger than a leaf keeps one label when its 9 samples (centre and
  // corners) agree (the paper's test, which a shadow or a gap thinner than the octant can
  // slip between). true: only when that label is also proven for every point of it (one
  // view sees all of it so, and every view sees none of it better: docs/occlusion.md,
  // "Exact octants"), or, for an octant of 2 × 2 × 2 leaves, when its leaves' centres all
  // agree; else it is split. The result then matches every leaf judged alone, at about
  // 1.5 times the time (twice in a hall of columns under a mezzanine).
  bool exact_octants = false;
  // Worker threads (0: one per core); the result is the same for any count.
  unsigned threads = 0;
  // Not empty: only the candidates that a segment from some view may reach through one of
  // these octants (min-corner key and level ≤ the leaf level, else std::invalid_argument)
  // are judged; the others keep their label. For a study after a change confined to them
  // (door or window leaves labelled since the last study): what no segment reaches through
  // them is seen as it was.
  std::vector<std::pair<octomap::OcTreeKey, unsigned>> changed_octants;
  // Afterwards merge the siblings left with one label (SemiOcTree::prune):
  // labels and volumes are unchanged, in fewer octants. (The NBV scores count
  // per octant, so they see the merged octants.)
  bool prune = true;
};

struct OcclusionReport {
  std::size_t octants_tested = 0;
  std::size_t octants_split = 0;
  std::size_t octants_unproven = 0;  // split although their samples agreed (exact_octants)
  std::size_t segments = 0;          // segments cast
  std::size_t empty = 0, occluded = 0, out = 0;  // leaf octants labelled (before merging)
};

// One view per scanner position, each with the range and elevation limits of `limits`
// (its position and returns ignored), and the directions its scan got returns in:
// `returns[i]` for position i (none given: every direction).
std::vector<ScannerView> scanner_views(
    const std::vector<Point3>& positions, const ScannerView& limits,
    const std::vector<std::shared_ptr<const ReturnDirections>>& returns = {});

// How well `p` is seen from the best of `views`. Each call first looks around every
// view for a door it stands in (a few thousand look-ups): for many points, use
// study_occlusion.
Visibility point_visibility(const SemiOcTree& tree, const std::vector<ScannerView>& views,
                            const Point3& p);

OcclusionReport study_occlusion(SemiOcTree& tree, const std::vector<ScannerView>& views,
                                const OcclusionParams& params = {});

}  // namespace semioctree
