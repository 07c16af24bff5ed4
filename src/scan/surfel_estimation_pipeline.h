// Scan -> surfels for one view (ROS-free; the surfel_estimator node only translates messages): drop
// non-finite points, estimate normals oriented towards the sensor origin, optional MLS smoothing
// (thesis 3.1), surfel radii that cover the surface (3.3), and a rigid transform into the fixed frame.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/surface/mls_surface.h"
#include "relaxed_connectivity/surface/normal_estimation.h"
#include "relaxed_connectivity/surface/radius_estimation.h"

namespace rc {

struct SurfelEstimationConfig {
  NormalEstimationConfig normals;  ///< viewpoint is set per view (the sensor origin)
  RadiusEstimationConfig radii;
  bool mls_smoothing = false;
  MlsConfig mls;           ///< used when mls_smoothing (support radius = mls.weight.scale for Wendland)
  size_t min_points = 16;  ///< fewer finite points: the view is rejected

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

struct SurfelEstimationStats {
  size_t input_points = 0;
  size_t valid_points = 0;
  size_t output_surfels = 0;
  size_t mls_failures = 0;  ///< points MLS could not project (left unsmoothed)
};

/// Turns one view, given in the sensor frame (origin = sensor centre), into surfels in the fixed frame
/// `fixed_frame` using `sensor_to_fixed`. Throws std::invalid_argument with the reason for an empty cloud, a
/// cloud without (enough) finite points, or a non-finite transform.
SurfelCloud estimateSurfels(SurfelCloud view, const Eigen::Isometry3d& sensor_to_fixed,
                            const std::string& fixed_frame, const SurfelEstimationConfig& config,
                            SurfelEstimationStats* stats = nullptr);

}  // namespace rc
