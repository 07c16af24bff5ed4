// Shared by the FEM tests: random points on an off-centre ellipsoid, whose convex hull is a random convex
// polyhedron with every point a node.
#pragma once

#include <random>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

inline std::vector<Vec3> randomPointsOnEllipsoid(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Vec3> points;
  while (static_cast<int>(points.size()) < n) {
    Vec3 p(normal(rng), normal(rng), normal(rng));
    if (p.norm() < 1e-3) continue;
    p.normalize();
    points.emplace_back(1.5 * p.x() + 0.2, 1.0 * p.y() - 0.1, 0.7 * p.z() + 0.3);
  }
  return points;
}

}  // namespace rc
