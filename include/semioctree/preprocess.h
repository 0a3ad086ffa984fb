// Stage 1 (paper 2.1): level the cloud and cut floor and ceiling out of it.
// RANSAC finds the largest horizontal plane (normal within max_tilt_deg of z),
// the other horizontal planes are the peaks of the heights along its normal
// (floor and ceiling are parallel); the rotation of Eq 1-2 levels them, a translation puts
// the floor at z = 0; a Gaussian fitted to the floor and the ceiling peaks of
// the z histogram gives σ, and points within 2σ of either are removed (they
// carry no information for the NBV). Finally the cloud is decimated to a
// minimum point spacing or a target count.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <stdexcept>

#include "semioctree/scan_io.h"

namespace semioctree {

struct PreprocessParams {
  double max_tilt_deg = 15.0;     // a floor/ceiling normal is within this angle of z
  double ransac_distance = 0.03;  // RANSAC inlier distance, m
  int ransac_iterations = 500;
  std::size_t ransac_sample = 60000;  // planes are searched in a random subset this large
  double min_plane_fraction = 0.01;   // a floor/ceiling holds at least this share of points
  double min_room_height = 1.8;       // floor and ceiling at least this far apart, m
  double histogram_bin = 0.01;        // z histogram bin, m
  double peak_window = 0.15;          // search for the peaks this far from the planes, m
  double sigma_factor = 2.0;          // remove points within this many σ of floor/ceiling
  double min_sigma = 0.002;           // σ is at least this (noise-free data), m
  double min_spacing = 0.0;           // decimation: minimum point spacing, m (0: off)
  std::size_t target_points = 0;      // decimation: aim for this many points (0: off)
  std::size_t min_points = 1000;      // fewer input points than this is an error
};

struct HeightPeak {
  double center = 0;  // z of the Gaussian's mean (levelled frame)
  double sigma = 0;   // its standard deviation
  std::size_t removed = 0;
  std::size_t plane_inliers = 0;
};

struct PreprocessResult {
  Cloud::Ptr cloud;                    // levelled, floor at z = 0, floor/ceiling removed, decimated
  Eigen::Isometry3d transform;         // input frame → levelled frame
  double alpha_deg = 0, beta_deg = 0;  // Eq 1 angles of the floor/ceiling normal
  Eigen::Vector3d normal_input;        // that normal in the input frame (z > 0)
  double ceiling_height = 0;           // levelled; the floor is at 0
  HeightPeak floor, ceiling;
  std::size_t input_points = 0;
  std::size_t after_cut = 0;      // after removing floor and ceiling points
  std::size_t output_points = 0;  // after decimation
  double decimation_spacing = 0;  // spacing actually used (0: none)
};

class PreprocessError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws PreprocessError (with the reason) when the cloud has fewer than
// params.min_points points, no plane within max_tilt_deg of horizontal, or no
// floor and ceiling planes at least min_room_height apart.
PreprocessResult preprocess(const Cloud& input, const PreprocessParams& params = {});

// Decimates to a minimum spacing (PCL UniformSampling: one original point per
// cell of that size); exposed for reuse and tests.
Cloud::Ptr decimate(const Cloud& cloud, double spacing);

}  // namespace semioctree
