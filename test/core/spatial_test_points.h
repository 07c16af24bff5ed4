// Point sets shared by the spatial-query tests: uniform, clustered and surface-like (unit sphere) layouts.
#pragma once

#include <random>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {
namespace test {

enum class Layout { kUniform, kClustered, kSphere };

std::vector<Vec3> makePoints(Layout layout, size_t n, uint32_t seed, double scale = 1.0,
                             const Vec3& offset = Vec3::Zero()) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3> centers;
  for (int c = 0; c < 8; ++c) centers.emplace_back(uni(rng), uni(rng), uni(rng));
  std::vector<Vec3> pts(n);
  for (size_t i = 0; i < n; ++i) {
    Vec3 p = Vec3::Zero();
    switch (layout) {
      case Layout::kUniform:
        p = Vec3(uni(rng), uni(rng), uni(rng));
        break;
      case Layout::kClustered:
        p = centers[i % centers.size()] + 0.03 * Vec3(gauss(rng), gauss(rng), gauss(rng));
        break;
      case Layout::kSphere:
        p = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
        break;
    }
    pts[i] = offset + scale * p;
  }
  return pts;
}

}  // namespace test
}  // namespace rc
