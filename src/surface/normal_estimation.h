// Normal estimation for raw scans: weighted covariance (PCA) of the k nearest neighbours, with consistent
// orientation (towards a known sensor viewpoint, or propagated over a Riemannian minimum spanning tree when
// no viewpoint is known, Hoppe et al. 1992).
#pragma once

#include <optional>

#include "core/surfel_cloud.h"

namespace rc {

struct NormalEstimationConfig {
  int k = 16;  ///< neighbours per covariance fit (speed/accuracy knob)
  /// Orient normals towards this point (e.g. the scanner origin in the cloud's frame). Without it,
  /// orientation is propagated over the kNN graph and the result points away from the cloud's centroid on its
  /// extreme point.
  std::optional<Vec3> viewpoint;
  bool write_curvature =
      true;  ///< store surface variation lambda0 / (lambda0+lambda1+lambda2) in `curvature`
};

/// Fills cloud.normals (and curvature). Throws std::invalid_argument for fewer than 3 points or k < 3.
void estimateNormals(SurfelCloud& cloud, const NormalEstimationConfig& config);

/// Flips normals so that neighbouring normals agree (MST propagation); returns the number flipped.
size_t orientNormalsConsistently(SurfelCloud& cloud, int k = 16);

}  // namespace rc
