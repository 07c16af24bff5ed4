#include "relaxed_connectivity/scan/surfel_estimation_pipeline.h"

#include <cmath>
#include <stdexcept>

namespace rc {

void SurfelEstimationConfig::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("surfel estimation: " + what); };
  if (normals.k < 3) fail("normal_k must be >= 3 (got " + std::to_string(normals.k) + ")");
  if (radii.k < 1) fail("radius_k must be >= 1 (got " + std::to_string(radii.k) + ")");
  if (!(radii.scale > 0) || !std::isfinite(radii.scale))
    fail("radius_scale must be a positive number (got " + std::to_string(radii.scale) + ")");
  if (!(radii.max_radius >= 0) || !std::isfinite(radii.max_radius))
    fail("max_radius must be >= 0 (got " + std::to_string(radii.max_radius) + ")");
  if (mls_smoothing) {
    if (!(mls.weight.scale > 0) || !std::isfinite(mls.weight.scale))
      fail("mls_support_radius must be a positive number (got " + std::to_string(mls.weight.scale) + ")");
    if (mls.max_iterations < 1) fail("mls_max_iterations must be >= 1");
  }
  if (min_points < 3) fail("min_points must be >= 3 (got " + std::to_string(min_points) + ")");
}

SurfelCloud estimateSurfels(SurfelCloud view, const Eigen::Isometry3d& sensor_to_fixed,
                            const std::string& fixed_frame, const SurfelEstimationConfig& config,
                            SurfelEstimationStats* stats) {
  SurfelEstimationStats local;
  SurfelEstimationStats& s = stats ? *stats : local;
  s = SurfelEstimationStats();
  s.input_points = view.size();
  if (view.empty()) throw std::invalid_argument("empty cloud (0 points)");
  if (!sensor_to_fixed.matrix().allFinite())
    throw std::invalid_argument("the transform to '" + fixed_frame + "' is not finite");

  // Only positions are measured; channels a previous stage may have left are recomputed.
  view.normals.clear();
  view.radii.clear();
  view.axes1.clear();
  view.axes2.clear();
  view.curvature.clear();
  view.removeNonFinite();
  s.valid_points = view.size();
  if (view.empty())
    throw std::invalid_argument("no finite points (all " + std::to_string(s.input_points) + " are NaN/Inf)");
  if (view.size() < config.min_points)
    throw std::invalid_argument("only " + std::to_string(view.size()) + " finite points (at least " +
                                std::to_string(config.min_points) + " needed)");

  NormalEstimationConfig normals = config.normals;
  normals.viewpoint = Vec3::Zero();  // the sensor origin in its own frame
  estimateNormals(view, normals);
  if (config.mls_smoothing) s.mls_failures = smoothCloud(view, config.mls);
  estimateRadii(view, config.radii);

  view.transform(sensor_to_fixed);
  view.frame_id = fixed_frame;
  view.width = view.height = 0;
  s.output_surfels = view.size();
  return view;
}

}  // namespace rc
