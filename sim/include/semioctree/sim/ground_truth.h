// What a simulated survey is judged against: the true openings, samples of the surfaces
// a complete survey should see, line-of-sight queries, and the floor plan.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "semioctree/sim/geometry.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/scene.h"
#include "semioctree/sim/solids.h"

namespace semioctree::sim {

struct OpeningRect {
  OpeningKind kind = OpeningKind::door;
  int wall = 0;  // walls[wall].openings[index]
  int index = 0;
  std::array<Eigen::Vector3d, 4> corners;  // bottom-near, bottom-far, top-far, top-near
  double width = 0.0;
  double height = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // wall normal (left of from→to)
};

struct SurfaceSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, pointing out of the solid
  PartRef part;
};

// Every opening of every wall as a rectangle in world coordinates.
std::vector<OpeningRect> opening_rects(const Scene& scene);

// Points about `spacing` apart on the surfaces of walls (opening jambs included), boxes,
// cylinders and meshes; floors and ceilings (slabs) excluded, as the survey removes them.
// Samples buried in another solid (e.g. the bottom of a box standing on the floor, a
// wall end inside the next wall) are left out. Deterministic.
std::vector<SurfaceSample> surface_samples(const Scene& scene, double spacing = 0.02);
// The same samples, in the same order, handed to `f` one at a time and not kept (a large
// scene's samples run to hundreds of MB; a caller that needs a few of them keeps those).
void for_each_surface_sample(const Scene& scene, double spacing,
                             const std::function<void(const SurfaceSample&)>& f);
// The samples of surface_samples(scene, spacing) at `indices` (ascending), in that order,
// without holding the others (indices beyond the last sample are left out); `total`, if
// given, gets the number of all the samples.
std::vector<SurfaceSample> surface_samples_at(const Scene& scene, double spacing,
                                              const std::vector<std::uint32_t>& indices,
                                              std::size_t* total = nullptr);

// Rooms and walkable floor, on a square grid of `cell` metres covering the scene.
struct FloorPlan {
  double cell = 0.05;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // corner of cell (0, 0)
  int nx = 0, ny = 0;
  // Room id of each cell (row-major, y then x): rooms are the regions enclosed by walls
  // (openings count as wall); -1 for wall footprint and for the region around the
  // building. Rooms are numbered by decreasing area.
  std::vector<int> room;
  std::vector<double> room_area;  // m², floor area within the walls
  // Cells the robot can reach: free floor (something to stand on, nothing above up to
  // the scanner) with every cell centre within the robot's radius free too, connected
  // to robot.start's cell through such cells (4-neighbours). Whatever survey_area says:
  // a pocket the robot fits in but cannot drive into is not reachable.
  std::vector<bool> reachable;
  // Cells where the robot may stand: inside survey_area if the scene gives it, else
  // the reachable cells.
  std::vector<bool> survey;
  double survey_area_m2 = 0.0;
  int start_room = -1;  // room of robot.start

  // Row-major index of the cell holding p, moved by (dx, dy) cells; -1 off the grid.
  std::ptrdiff_t index_of(const Eigen::Vector2d& p, int dx = 0, int dy = 0) const;
  bool in_survey_area(const Eigen::Vector2d& p) const;
  // True if the cell of p or one of its 8 neighbours is reachable (a point a cell's
  // width from a reachable cell centre: the grid cannot tell closer).
  bool reachable_near(const Eigen::Vector2d& p) const;
  int room_at(const Eigen::Vector2d& p) const;
};

class GroundTruth {
 public:
  explicit GroundTruth(const Scene& scene);

  const Scene& scene() const { return scene_; }
  const SceneTriangles& triangles() const { return triangles_; }
  const RayCaster& ray_caster() const { return *caster_; }
  const SolidModel& solids() const { return solids_; }

  std::vector<OpeningRect> openings() const { return opening_rects(scene_); }
  std::vector<SurfaceSample> surface_samples(double spacing = 0.02) const {
    return sim::surface_samples(scene_, spacing);
  }
  // True if the segment a→b crosses no geometry (its end points may lie on a surface:
  // the first and last millimetre are not tested).
  bool segment_free(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  // True if a robot of the scene's radius can stand at p: no solid in its cylinder from
  // just above the floor to the scanner height.
  bool standing_free(const Eigen::Vector2d& p) const;

  // Throws std::invalid_argument beyond kMaxFloorPlanCells cells.
  FloorPlan floor_plan(double cell = 0.05) const;
  static constexpr double kMaxFloorPlanCells = 4e7;

 private:
  Scene scene_;
  SceneTriangles triangles_;
  std::unique_ptr<RayCaster> caster_;
  SolidModel solids_;
};

}  // namespace semioctree::sim
