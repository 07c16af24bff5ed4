// Surfel radii that guarantee a hole-free surface (coverage, thesis 3.3).
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct RadiusEstimationConfig {
  int k = 8;              ///< neighbours considered
  double scale = 1.0;     ///< multiplies the covering radius (>= 1 keeps the coverage guarantee)
  double max_radius = 0;  ///< clamp (0: none)
};

/// Fills cloud.radii (requires normals). Each radius is chosen so that the discs, projected into each
/// surfel's tangent plane, cover the gaps between neighbours (3.3).
void estimateRadii(SurfelCloud& cloud, const RadiusEstimationConfig& config);

}  // namespace rc
