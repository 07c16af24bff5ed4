// Test model shared by the conversion tests: the unit sphere sampled by a Fibonacci spiral.
#pragma once

#include <cmath>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// n Fibonacci points on the unit sphere, outward normals, all of the given radius.
inline SurfelCloud fibonacciSphereSurfels(size_t n, double radius) {
  SurfelCloud c;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(n), r = std::sqrt(1.0 - z * z);
    const Vec3 p(r * std::cos(golden * double(i)), r * std::sin(golden * double(i)), z);
    c.positions.push_back(p);
    c.normals.push_back(p);
  }
  c.radii.assign(n, radius);
  return c;
}

}  // namespace rc
