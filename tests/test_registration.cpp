// Registration (stage 2): a known rigid error is undone on a synthetic room; clouds that
// do not match are refused with a message; and on the lab scene a second scan placed by
// the robot's drifting odometry is brought back to the true scanner pose.
#include <gtest/gtest.h>
#include <pcl/common/transforms.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>

#include "semioctree/registration.h"
#include "src/planar_point_to_plane.h"
#include "support/synthetic_clouds.h"

#ifdef SEMIOCTREE_HAVE_SIM
#include "semioctree/preprocess.h"
#include "semioctree/sim/geometry.h"
#include "semioctree/sim/ground_truth.h"
#include "semioctree/sim/raycaster.h"
#include "semioctree/sim/robot.h"
#include "semioctree/sim/scanner.h"
#include "semioctree/sim/scene.h"
#include "support/sanitized.h"
#endif

namespace semioctree {
namespace {

constexpr double kDeg = 180.0 / M_PI;

Cloud::Ptr transformed(const Cloud& in, const Eigen::Isometry3d& t) {
  Cloud::Ptr out(new Cloud);
  pcl::transformPointCloud(in, *out, t.matrix().cast<float>());
  return out;
}

// Translation (m) and rotation angle (°) of a rigid transform.
struct Size {
  double translation, rotation_deg;
};
Size size_of(const Eigen::Isometry3d& t) {
  return {t.translation().norm(), Eigen::AngleAxisd(t.rotation()).angle() * kDeg};
}

// Points on the faces of an axis-aligned box (bottom face excluded), with noise.
void add_box(Cloud& c, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double spacing,
             std::mt19937& rng, double noise = 0.002) {
  std::normal_distribution<double> n(0.0, noise);
  auto add = [&](double x, double y, double z) {
    c.push_back(pcl::PointXYZ{float(x + n(rng)), float(y + n(rng)), float(z + n(rng))});
  };
  for (double x = lo.x(); x <= hi.x(); x += spacing)
    for (double y = lo.y(); y <= hi.y(); y += spacing) add(x, y, hi.z());
  for (double z = lo.z(); z <= hi.z(); z += spacing) {
    for (double x = lo.x(); x <= hi.x(); x += spacing) {
      add(x, lo.y(), z);
      add(x, hi.y(), z);
    }
    for (double y = lo.y(); y <= hi.y(); y += spacing) {
      add(lo.x(), y, z);
      add(hi.x(), y, z);
    }
  }
}

// An 8 × 6 × 3 m room (floor at z = 0) with a table, two cabinets and a crate, as
// `preprocess` leaves it: floor and ceiling points removed. Different spacings give
// different samplings of the same surfaces.
Cloud::Ptr room(double spacing, unsigned seed) {
  const Cloud::Ptr all =
      testing::synthetic_room(8.0, 6.0, 3.0, spacing, 0.002, seed, 0.0, 0.0, 0.0);
  std::mt19937 rng(seed + 100);
  add_box(*all, {0.0, 4.0, 0.0}, {0.6, 5.5, 2.0}, spacing, rng);  // cabinet on the west wall
  add_box(*all, {6.5, 5.4, 0.0}, {7.7, 6.0, 1.8}, spacing, rng);  // cabinet in a corner
  add_box(*all, {2.0, 2.5, 0.0}, {2.6, 3.0, 0.5}, spacing, rng);  // a crate
  Cloud::Ptr cut(new Cloud);
  for (const auto& p : *all)
    if (p.z > 0.02f && p.z < 2.98f) cut->push_back(p);
  return cut;
}

// The error of a guess: `planar` (x, y, yaw) about the room's centre, as a robot's
// drift turns the scan about the scanner rather than about the room's corner.
Eigen::Isometry3d error_about(const Eigen::Vector3d& centre, const Eigen::Isometry3d& e) {
  return Eigen::Translation3d(centre) * e * Eigen::Translation3d(-centre);
}

TEST(Registration, RecoversAKnownPlanarError) {
  const Cloud::Ptr target = room(0.03, 1);
  const Cloud::Ptr truth = room(0.037, 2);  // the same room, sampled differently
  const Eigen::Isometry3d error = error_about({4.0, 3.0, 0.0}, planar_pose(0.25, -0.15, 4.0));
  const Cloud::Ptr source = transformed(*truth, error);

  const RegistrationResult r = register_scan(*source, *target);
  // correction · error should be the identity.
  const Size residual = size_of(r.correction * error);
  std::printf(
      "planar: residual %.2f mm, %.4f°; fitness %.3g m², overlap %.3f, %d iterations, "
      "%.3f s\n",
      residual.translation * 1e3, residual.rotation_deg, r.fitness, r.overlap, r.iterations,
      r.seconds);
  EXPECT_LT(residual.translation, 0.01);
  EXPECT_LT(residual.rotation_deg, 0.1);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.translation_m, size_of(error.inverse()).translation, 0.01);
  EXPECT_NEAR(r.rotation_deg, 4.0, 0.1);
  EXPECT_GT(r.overlap, 0.9);
  EXPECT_LT(r.fitness, RegistrationParams{}.max_fitness);
  EXPECT_GT(r.source_points, 1000u);
  EXPECT_LT(r.source_points, source->size());  // downsampled
  // Planar: z, roll and pitch are left as levelled.
  EXPECT_NEAR(r.correction.translation().z(), 0.0, 1e-9);
  EXPECT_NEAR(r.correction.linear()(2, 2), 1.0, 1e-12);
}

// ICP's planar step (x, y, yaw; src/planar_point_to_plane.h). Points on three walls (their
// normals along x, along y and at 30° between) and a floor, moved by a planar motion: a
// step from the exact pairs takes it most of the way (the yaw's linearisation leaves its
// second order), and a few steps to the floats' precision. Walls all facing x do not constrain y: the step leaves y where it
// was. No pairs: no step.
TEST(Registration, PlanarPointToPlaneStepRecoversAPlanarMotion) {
  using detail::PlanarPointToPlane;
  using CloudN = PlanarPointToPlane::CloudN;
  CloudN target;
  auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    pcl::PointNormal q;
    q.x = float(p.x()), q.y = float(p.y()), q.z = float(p.z());
    q.normal_x = float(n.x()), q.normal_y = float(n.y()), q.normal_z = float(n.z());
    target.push_back(q);
  };
  const Eigen::Vector3d slanted(std::cos(M_PI / 6), std::sin(M_PI / 6), 0);
  for (int i = 0; i < 40; ++i)
    for (int k = 0; k < 10; ++k) {
      const double t = 0.1 * i, z = 0.25 * k;
      add({4.0, t - 2.0, z}, {1, 0, 0});
      add({t - 2.0, 3.0, z}, {0, 1, 0});
      add(Eigen::Vector3d(-3.0, 0.0, z) + t * Eigen::Vector3d(-slanted.y(), slanted.x(), 0),
          slanted);
      add({t - 2.0, 0.1 * k - 0.5, 0.0}, {0, 0, 1});
    }
  // The source: the target moved by the inverse of the motion to recover.
  const Eigen::Isometry3d motion = planar_pose(0.03, -0.02, 1.5);
  auto moved = [](const CloudN& in, const Eigen::Isometry3d& t) {
    CloudN out;
    pcl::transformPointCloudWithNormals(in, out, t.matrix());
    return out;
  };
  CloudN source = moved(target, motion.inverse());
  const PlanarPointToPlane step;
  Eigen::Matrix4d total = Eigen::Matrix4d::Identity();
  for (int it = 0; it < 4; ++it) {
    Eigen::Matrix4d m;
    step.estimateRigidTransformation(source, target, m);
    source = moved(source, Eigen::Isometry3d(m));
    total = m * total;
    if (it == 0) {  // 36 mm and 1.5° to go: what is left is the yaw's second order
      const Size off = size_of(Eigen::Isometry3d(total).inverse() * motion);
      EXPECT_LT(off.translation, 3e-3) << "one step";
      EXPECT_LT(off.rotation_deg, 0.05) << "one step";
    }
    // A rotation about z alone, orthonormal, and no move along z.
    EXPECT_EQ(m(2, 2), 1.0);
    EXPECT_EQ(m(2, 3), 0.0);
    EXPECT_NEAR(m(0, 0) * m(0, 0) + m(1, 0) * m(1, 0), 1.0, 1e-12);
  }
  const Size off = size_of(Eigen::Isometry3d(total).inverse() * motion);
  EXPECT_LT(off.translation, 1e-5);  // (the points are floats)
  EXPECT_LT(off.rotation_deg, 1e-4);

  // Walls all facing x: y is not moved; x and the yaw still are.
  CloudN facing_x;
  for (const pcl::PointNormal& q : target)
    if (q.normal_x == 1.0f) facing_x.push_back(q);
  const CloudN facing_x_source = moved(facing_x, planar_pose(-0.02, 0.05, 0.5));
  Eigen::Matrix4d m;
  step.estimateRigidTransformation(facing_x_source, facing_x, m);
  EXPECT_TRUE(m.allFinite());
  EXPECT_EQ(m(1, 3), 0.0);
  EXPECT_NEAR(std::atan2(m(1, 0), m(0, 0)) * kDeg, -0.5, 0.05);

  // No pairs: no step.
  step.estimateRigidTransformation(CloudN(), CloudN(), m);
  EXPECT_TRUE(m.isIdentity());
}

TEST(Registration, SixDofRecoversTiltAndHeightToo) {
  const Cloud::Ptr target = room(0.03, 3);
  const Cloud::Ptr truth = room(0.037, 4);
  Eigen::Isometry3d e = planar_pose(0.2, 0.1, -3.0);
  e.translate(Eigen::Vector3d(0, 0, 0.03));
  e.rotate(Eigen::AngleAxisd(0.8 / kDeg, Eigen::Vector3d::UnitX()));
  const Eigen::Isometry3d error = error_about({4.0, 3.0, 1.5}, e);
  RegistrationParams p;
  p.planar = false;
  const RegistrationResult r = register_scan(*transformed(*truth, error), *target, p);
  const Size residual = size_of(r.correction * error);
  std::printf("6 DoF: residual %.2f mm, %.4f°, %.3f s\n", residual.translation * 1e3,
              residual.rotation_deg, r.seconds);
  EXPECT_LT(residual.translation, 0.01);
  EXPECT_LT(residual.rotation_deg, 0.1);
}

TEST(Registration, PlanarLeavesHeightAlone) {
  // The planar mode leaves z (and tilt) as levelled: a cloud 4 cm too high stays so,
  // and fits worse than with the 6 DoF mode, which brings it down.
  const Cloud::Ptr target = room(0.03, 5);
  Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
  error.translate(Eigen::Vector3d(0.0, 0.0, 0.04));
  const Cloud::Ptr source = transformed(*room(0.037, 6), error);
  RegistrationParams p;
  p.max_fitness = 1.0;  // report, do not judge
  p.min_overlap = 0.0;
  const RegistrationResult planar = register_scan(*source, *target, p);
  p.planar = false;
  const RegistrationResult full = register_scan(*source, *target, p);
  EXPECT_NEAR(planar.correction.translation().z(), 0.0, 1e-9);
  EXPECT_NEAR(full.correction.translation().z(), -0.04, 0.005);
  EXPECT_LT(full.fitness, planar.fitness);
}

TEST(Registration, FarOutliersDoNotDefeatTheDownsampling) {
  // Two stray returns kilometres away make a 0.05 m grid over the bounding box
  // larger than PCL's VoxelGrid accepts (it would then return every point).
  const Cloud::Ptr target = room(0.03, 12);
  const Eigen::Isometry3d error = error_about({4.0, 3.0, 0.0}, planar_pose(-0.1, 0.2, 2.0));
  const Cloud::Ptr source = transformed(*room(0.037, 13), error);
  const std::size_t clean = register_scan(*source, *target).source_points;
  source->push_back(pcl::PointXYZ{2500.f, -1800.f, 40.f});
  source->push_back(pcl::PointXYZ{-900.f, 2200.f, -30.f});
  const RegistrationResult r = register_scan(*source, *target);
  // Downsampled as much as without the outliers (the grid's origin may differ).
  EXPECT_LT(double(r.source_points), 1.1 * double(clean));
  EXPECT_GT(double(r.source_points), 0.9 * double(clean));
  const Size residual = size_of(r.correction * error);
  EXPECT_LT(residual.translation, 0.01);
  EXPECT_LT(residual.rotation_deg, 0.1);
}

TEST(Registration, NoOverlapFailsNamingOverlap) {
  const Cloud::Ptr target = room(0.03, 7);
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translate(Eigen::Vector3d(30.0, 0.0, 0.0));
  const Cloud::Ptr source = transformed(*room(0.037, 8), far);
  try {
    register_scan(*source, *target);
    FAIL() << "a cloud 30 m away was registered";
  } catch (const RegistrationError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("overlap"), std::string::npos) << m;
  }
}

TEST(Registration, NoiseFailsNamingFitnessAndOverlap) {
  const Cloud::Ptr target = room(0.03, 9);
  // Uniform noise filling the room's volume: a few points fall near a surface by
  // chance, far too few to pass for a scan of it. (Kept small: ICP never settles
  // on noise and runs every stage to max_iterations.)
  Cloud noise;
  std::mt19937 rng(10);
  std::uniform_real_distribution<float> x(0.f, 8.f), y(0.f, 6.f), z(0.f, 3.f);
  for (int i = 0; i < 5000; ++i) noise.push_back(pcl::PointXYZ{x(rng), y(rng), z(rng)});
  try {
    const RegistrationResult r = register_scan(noise, *target);
    FAIL() << "noise was registered: overlap " << r.overlap << ", fitness " << r.fitness;
  } catch (const RegistrationError& e) {
    const std::string m = e.what();
    std::printf("noise: %s\n", m.c_str());
    EXPECT_NE(m.find("fitness"), std::string::npos) << m;
    EXPECT_NE(m.find("overlap"), std::string::npos) << m;
  }
}

// Room B (x 0..4, y 0.12..4) north of a 0.12 m partition (y 0..0.12), which by default
// runs on 4 m to either side, as a corridor's wall does: which of the walls a cloud holds.
struct PartitionWalls {
  bool south_face = false;              // the partition's south face (y = 0), seen from the south
  bool north_face = false;              // its north face (y = 0.12), seen from room B
  double partition_x[2] = {-4.0, 8.0};  // the partition's extent along x
  bool far_wall = true;                 // room B's north wall (y = 4)
  double side_walls_from = 0.12;        // room B's side walls (x = 0 and 4) run from this y to 4
};

Cloud::Ptr partitioned(const PartitionWalls& walls, double spacing, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  Cloud::Ptr c(new Cloud);
  auto add = [&](double x, double y, double z) {
    c->push_back(
        pcl::PointXYZ{float(x + noise(rng)), float(y + noise(rng)), float(z + noise(rng))});
  };
  for (double z = 0.2; z <= 2.4; z += spacing) {
    for (double x = walls.partition_x[0]; x <= walls.partition_x[1]; x += spacing) {
      if (walls.south_face) add(x, 0.0, z);
      if (walls.north_face) add(x, 0.12, z);
    }
    if (walls.far_wall)
      for (double x = 0.0; x <= 4.0; x += spacing) add(x, 4.0, z);
    for (double y = walls.side_walls_from; y <= 4.0; y += spacing) {
      add(0.0, y, z);
      add(4.0, y, z);
    }
  }
  return c;
}

// The clouds of the partition's two faces: the map saw its south face, and room B's other
// walls through a door; the scan sees its north face all along, and room B's walls.
PartitionWalls map_with_south_face() {
  PartitionWalls walls;
  walls.south_face = true;
  return walls;
}
PartitionWalls scan_from_room_b() {
  PartitionWalls walls;
  walls.north_face = true;
  return walls;
}

// The side each wall was seen from: the partition's south face from the south, every
// other wall from room B.
int side_seen(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
  Eigen::Vector3d towards;  // from the surface to where it was seen from
  if (std::abs(p.y()) < 0.06)
    towards = {0, -1, 0};
  else if (std::abs(p.y() - 0.12) < 0.06 && std::abs(n.y()) > std::abs(n.x()))  // not a side wall
    towards = {0, 1, 0};
  else if (std::abs(p.y() - 4.0) < 0.06)
    towards = {0, -1, 0};
  else
    towards = {p.x() < 2.0 ? 1.0 : -1.0, 0, 0};
  const double d = n.dot(towards);
  return d > 0.5 ? 1 : (d < -0.5 ? -1 : 0);
}

// Without the facing, the scan's side of the partition is laid onto the other side: a
// shift by the wall's thickness that fits well. With it, the faces are told apart.
TEST(Registration, TheTwoFacesOfAWallAreNotConfused) {
  const Cloud::Ptr target = partitioned(map_with_south_face(), 0.03, 1);
  const Cloud::Ptr truth = partitioned(scan_from_room_b(), 0.037, 2);
  const Eigen::Isometry3d error = planar_pose(0.0, 0.06, 0.0);  // half the wall's thickness
  const Cloud::Ptr source = transformed(*truth, error);
  SurfaceFacing facing;
  facing.source_viewpoint = error * Eigen::Vector3d(2.0, 2.0, 1.5);
  facing.target_side = side_seen;

  const RegistrationResult blind = register_scan(*source, *target);
  const RegistrationResult faced = register_scan(*source, *target, {}, &facing);
  const double blind_error = (blind.correction * error).translation().norm();
  const double faced_error = (faced.correction * error).translation().norm();
  std::printf(
      "partition: error %.1f mm without the facing (fitness %.3g m², overlap %.2f), "
      "%.1f mm with it (fitness %.3g m², overlap %.2f)\n",
      1e3 * blind_error, blind.fitness, blind.overlap, 1e3 * faced_error, faced.fitness,
      faced.overlap);
  EXPECT_GT(blind_error, 0.1);  // the thickness of the wall
  EXPECT_LT(faced_error, 0.01);
  // With the faces told apart, the partition (half the scan) pairs with nothing.
  EXPECT_LT(faced.overlap, 0.6);
  EXPECT_GT(faced.overlap, 0.4);
}

// A scan placed 7 cm south of the truth lays the partition's north face 5 cm from the
// map's south face, which faces the other way, and 7 cm from its own: the nearest target
// point of a source point there faces the wrong way, the next ones include its own face.
// Only the partition fixes y: a source point must pair with the nearest target point
// facing its way among the few nearest, not just with the nearest if it does.
TEST(Registration, PairsWithTheNearestFacingItsWayNotJustTheNearest) {
  // Room B without its far wall, its side walls from y = 0.6 (doorways at both of its
  // corners): they fix x and the yaw, not y. The partition, only as long as the room is
  // wide, is seen from both sides in the map.
  PartitionWalls map_walls = map_with_south_face(), scan_walls = scan_from_room_b();
  map_walls.north_face = true;
  map_walls.far_wall = scan_walls.far_wall = false;
  for (PartitionWalls* walls : {&map_walls, &scan_walls}) {
    walls->partition_x[0] = 0.0;
    walls->partition_x[1] = 4.0;
  }
  map_walls.side_walls_from = scan_walls.side_walls_from = 0.6;
  const Cloud::Ptr target = partitioned(map_walls, 0.03, 3);
  const Cloud::Ptr truth = partitioned(scan_walls, 0.037, 4);
  const Eigen::Isometry3d error = planar_pose(0.0, -0.07, 0.0);
  const Cloud::Ptr source = transformed(*truth, error);
  SurfaceFacing facing;
  facing.source_viewpoint = error * Eigen::Vector3d(2.0, 2.0, 1.5);
  facing.target_side = side_seen;
  const RegistrationResult r = register_scan(*source, *target, {}, &facing);
  const double residual = (r.correction * error).translation().norm();
  std::printf(
      "thin partition: error %.1f mm after registration, %d iterations (fitness %.3g m², "
      "overlap %.2f)\n",
      1e3 * residual, r.iterations, r.fitness, r.overlap);
  EXPECT_LT(residual, 0.01);
  // Paired with its own face from the first iteration, the partition brings y back at
  // once: 5 iterations in all. Paired only where the nearest faces its way, it pairs with
  // nothing at first, and the coarse stage creeps along y to its 50-iteration limit.
  EXPECT_LT(r.iterations, 20);
}

// The surface normals are estimated on the threads asked for, each point's its own: the
// same placement, to the bit, on 1, 2 or 5 threads (with the facing, whose source normals
// are estimated too).
TEST(Registration, SamePlacementOnAnyNumberOfThreads) {
  const Cloud::Ptr target = partitioned(map_with_south_face(), 0.03, 1);
  const Cloud::Ptr truth = partitioned(scan_from_room_b(), 0.037, 2);
  const Eigen::Isometry3d error = planar_pose(0.05, 0.06, 2.0);
  const Cloud::Ptr source = transformed(*truth, error);
  SurfaceFacing facing;
  facing.source_viewpoint = error * Eigen::Vector3d(2.0, 2.0, 1.5);
  facing.target_side = side_seen;
  RegistrationParams p;
  p.threads = 1;
  const RegistrationResult one = register_scan(*source, *target, p, &facing);
  for (unsigned threads : {2u, 5u}) {
    p.threads = threads;
    const RegistrationResult many = register_scan(*source, *target, p, &facing);
    EXPECT_TRUE(many.correction.matrix() == one.correction.matrix()) << threads << " threads";
    EXPECT_EQ(many.fitness, one.fitness);
    EXPECT_EQ(many.overlap, one.overlap);
    EXPECT_EQ(many.iterations, one.iterations);
  }
}

TEST(Registration, EmptyOrTinyCloudsFail) {
  const Cloud::Ptr target = room(0.05, 11);
  const Cloud empty;
  EXPECT_THROW(register_scan(empty, *target), RegistrationError);
  EXPECT_THROW(register_scan(*target, empty), RegistrationError);
  Cloud few;
  for (int i = 0; i < 20; ++i) few.push_back(pcl::PointXYZ{0.1f * float(i), 0.f, 1.f});
  try {
    register_scan(few, *target);
    FAIL() << "20 points were registered";
  } catch (const RegistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("too few points"), std::string::npos) << e.what();
  }
  RegistrationParams bad;
  bad.final_correspondence = 1.0;  // above max_correspondence
  EXPECT_THROW(register_scan(*target, *target, bad), std::invalid_argument);
}

// A target of isolated points beside one small patch of wall: only the patch's points
// get a surface normal (3 neighbours within 4 voxels), too few for the point-to-plane
// error. Refused, naming how many of the target's points have one.
TEST(Registration, ATargetWithTooFewNormalsIsRefusedCountingThem) {
  const Cloud::Ptr source = room(0.05, 11);
  Cloud target;
  for (int x = 0; x < 9; ++x)  // 0.3 m apart: no neighbour within 0.2 m
    for (int y = 0; y < 7; ++y)
      for (int z = 0; z < 4; ++z)
        target.push_back(pcl::PointXYZ{0.3f + 0.9f * x, 0.3f + 0.9f * y, 0.4f + 0.7f * z});
  for (int y = 0; y < 6; ++y)  // a patch of wall on x = 0.02, 0.06 m apart
    for (int z = 0; z < 6; ++z)
      target.push_back(pcl::PointXYZ{0.02f, 2.0f + 0.06f * y, 1.0f + 0.06f * z});
  try {
    register_scan(*source, target);
    FAIL() << "a target of isolated points was registered";
  } catch (const RegistrationError& e) {
    const std::string what = e.what();
    const auto at = what.find("only ");
    ASSERT_NE(at, std::string::npos) << what;
    EXPECT_NE(what.find("have a surface normal"), std::string::npos) << what;
    unsigned with_normal = 0, points = 0;
    ASSERT_EQ(std::sscanf(what.c_str() + at, "only %u of %u", &with_normal, &points), 2) << what;
    EXPECT_EQ(points, 9u * 7u * 4u + 36u);
    EXPECT_EQ(with_normal, 36u);  // the patch, and none of the isolated points
  }
}

#ifdef SEMIOCTREE_HAVE_SIM

using semioctree::testing::sanitized;

// The lab scene scanned from the robot's start and from a second free position in the
// main room, each preprocessed in its own scanner frame (so independent of the
// odometry); computed once for all the lab tests. The simulated scanner stands
// perfectly level; a real one does not, so each scan is tilted by a fraction of a
// degree (the scanner frame is then tilted against the world: the truth follows),
// and the levelling of `preprocess` is part of what is tested.
struct LabData {
  sim::Scene scene;
  sim::Pose2 second;  // true pose of the second scan
  struct Prepared {
    PreprocessResult pre;               // scanner frame → levelled
    Eigen::Isometry3d sensor_to_world;  // the truth
  };
  Prepared first, second_scan;
};

const LabData& lab_data() {
  static const LabData data = [] {
    LabData d;
    d.scene = sim::load_scene(std::string(SEMIOCTREE_SOURCE_DIR) + "/sim/scenes/lab.scene.json");
    const sim::GroundTruth truth(d.scene);
    const sim::Pose2 start{d.scene.robot.start.x(), d.scene.robot.start.y(),
                           d.scene.robot.start_yaw_deg};
    // 2.4 m east of the start, between the benches and the column, turned by 35°.
    d.second = {7.6, 3.3, 35.0};
    EXPECT_TRUE(truth.standing_free({d.second.x, d.second.y}));
    EXPECT_EQ(truth.floor_plan().room_at({d.second.x, d.second.y}),
              truth.floor_plan().room_at({start.x, start.y}));
    const auto caster = sim::make_ray_caster(sim::tessellate(d.scene));
    PreprocessParams pp;
    pp.target_points = 400000;
    auto take = [&](const sim::Pose2& pose, std::uint64_t seed, double alpha_deg, double beta_deg) {
      sim::ScanOptions options;
      options.seed = seed;
      options.with_intensity = false;
      const sim::Scan s = sim::scan(*caster, d.scene.scanner, pose, options);
      Cloud level;  // level scanner frame
      level.reserve(s.points.size());
      for (const auto& p : s.points) level.push_back(pcl::PointXYZ{p.x(), p.y(), p.z()});
      const Cloud::Ptr tilted = testing::tilt(level, alpha_deg, beta_deg);  // scanner frame
      const Eigen::Isometry3d tilt(Eigen::AngleAxisd(beta_deg / kDeg, Eigen::Vector3d::UnitX()) *
                                   Eigen::AngleAxisd(alpha_deg / kDeg, Eigen::Vector3d::UnitY()));
      return LabData::Prepared{preprocess(*tilted, pp), s.sensor_to_world() * tilt.inverse()};
    };
    d.first = take(start, 1, 0.4, -0.3);
    d.second_scan = take(d.second, 2, -0.7, 0.5);
    return d;
  }();
  return data;
}

struct PoseError {
  double translation_m, yaw_deg, rotation_deg;
};
PoseError pose_error(const Eigen::Isometry3d& estimated, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d d = truth.inverse() * estimated;
  const Eigen::Vector3d xe = estimated.rotation().col(0), xt = truth.rotation().col(0);
  double yaw = (std::atan2(xe.y(), xe.x()) - std::atan2(xt.y(), xt.x())) * kDeg;
  yaw = std::remainder(yaw, 360.0);
  return {(estimated.translation() - truth.translation()).norm(), yaw,
          Eigen::AngleAxisd(d.rotation()).angle() * kDeg};
}

// The survey recipe for a second scan reported at `reported`; returns the pose error
// of the estimated scanner pose against the true one, both in the survey frame.
struct LabOutcome {
  PoseError odometry, registered;
  RegistrationResult result;
  double cpu_seconds = 0;  // of register_scan, this thread (the machine may be busy)
};

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
LabOutcome register_second(const LabData& d, const sim::Pose2& reported) {
  const sim::Pose2 start{d.scene.robot.start.x(), d.scene.robot.start.y(),
                         d.scene.robot.start_yaw_deg};
  // Scan 0 defines the survey frame: its reported pose (the start, exactly) placing
  // its levelled cloud. World → survey is therefore (nearly) the identity; use it
  // exactly to map the true poses.
  const Eigen::Isometry3d place0 = planar_pose(start.x, start.y, start.yaw_deg);
  const Eigen::Isometry3d world_to_survey =
      place0 * d.first.pre.transform * d.first.sensor_to_world.inverse();
  const Cloud::Ptr target = transformed(*d.first.pre.cloud, place0);

  const Eigen::Isometry3d place1 = planar_pose(reported.x, reported.y, reported.yaw_deg);
  const Cloud::Ptr source = transformed(*d.second_scan.pre.cloud, place1);
  LabOutcome out;
  const double cpu0 = thread_cpu_seconds();
  out.result = register_scan(*source, *target);
  out.cpu_seconds = thread_cpu_seconds() - cpu0;
  const Eigen::Isometry3d guess = place1 * d.second_scan.pre.transform;
  const Eigen::Isometry3d estimated = out.result.correction * guess;
  const Eigen::Isometry3d truth = world_to_survey * d.second_scan.sensor_to_world;
  out.odometry = pose_error(guess, truth);
  out.registered = pose_error(estimated, truth);
  return out;
}

class LabRegistration : public ::testing::TestWithParam<int> {};

TEST_P(LabRegistration, SecondScanIsCorrectedToTheTruePose) {
  if (sanitized()) GTEST_SKIP() << "too slow under the sanitizers";
  const LabData& d = lab_data();
  sim::Robot robot(d.scene.robot, std::uint64_t(GetParam()));
  robot.move_to(d.second);
  ASSERT_DOUBLE_EQ(robot.true_pose().x, d.second.x);
  const LabOutcome o = register_second(d, robot.reported_pose());
  std::printf(
      "seed %d: odometry error %.1f cm, %.3f° yaw; registered %.2f cm, %.4f° yaw (%.4f° "
      "total); fitness %.3g m², overlap %.3f, %zu/%zu points, %d iterations, %.3f s (%.3f s "
      "CPU)\n",
      GetParam(), o.odometry.translation_m * 100, o.odometry.yaw_deg,
      o.registered.translation_m * 100, o.registered.yaw_deg, o.registered.rotation_deg,
      o.result.fitness, o.result.overlap, o.result.source_points, o.result.target_points,
      o.result.iterations, o.result.seconds, o.cpu_seconds);
  // The odometry alone misses the bounds (else the test would prove nothing)...
  EXPECT_TRUE(o.odometry.translation_m > 0.02 || std::fabs(o.odometry.yaw_deg) > 0.3);
  // ... and registration brings the pose within them.
  EXPECT_LT(o.registered.translation_m, 0.02);
  EXPECT_LT(std::fabs(o.registered.yaw_deg), 0.3);
  EXPECT_LT(o.registered.rotation_deg, 0.3);
}

INSTANTIATE_TEST_SUITE_P(RobotSeeds, LabRegistration, ::testing::Values(1, 2, 3));

TEST(LabRegistrationDrift, LargestExpectedOdometryErrorIsCorrected) {
  // The worst drift the survey expects: 0.3 m and 5° of yaw.
  if (sanitized()) GTEST_SKIP() << "too slow under the sanitizers";
  const LabData& d = lab_data();
  for (const sim::Pose2& off : {sim::Pose2{0.3, 0.0, 5.0}, sim::Pose2{-0.2, 0.22, -5.0}}) {
    const sim::Pose2 reported{d.second.x + off.x, d.second.y + off.y,
                              d.second.yaw_deg + off.yaw_deg};
    const LabOutcome o = register_second(d, reported);
    std::printf("drift (%.2f, %.2f, %.1f°): registered %.2f cm, %.4f° yaw, %.3f s (%.3f s CPU)\n",
                off.x, off.y, off.yaw_deg, o.registered.translation_m * 100, o.registered.yaw_deg,
                o.result.seconds, o.cpu_seconds);
    EXPECT_LT(o.registered.translation_m, 0.02);
    EXPECT_LT(std::fabs(o.registered.yaw_deg), 0.3);
  }
}

#endif  // SEMIOCTREE_HAVE_SIM

}  // namespace
}  // namespace semioctree
