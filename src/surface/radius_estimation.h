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

/// Mean sample spacing h of a surface sample of unknown area: from the mean 6th-neighbour distance r6 of a
/// uniform density rho, pi r6^2 rho = 6 and h = 1 / sqrt(rho) (= sqrt(area / n) on a uniform sample). The
/// unit MLS support radii are given in (3 h is PCL's usual search radius). Throws for fewer than 7 points.
double sampleSpacing(const std::vector<Vec3>& positions);

}  // namespace rc
