#include "relaxed_connectivity/paint/force_shading.h"

#include <array>
#include <cmath>
#include <stdexcept>

namespace rc {

SurfaceContact forceShade(const SurfelCloud& originals, const Vec3& x, const Neighbor* neighbours,
                          size_t count) {
  SurfaceContact c;
  if (count == 0) return c;
  std::array<double, 64> dist;
  const size_t n = std::min<size_t>(count, dist.size());
  double d_max = 0;
  for (size_t i = 0; i < n; ++i) d_max = std::max(d_max, dist[i] = std::sqrt(neighbours[i].sq_dist));
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += d_max - dist[i];
  double depth = 0;
  Vec3 normal = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t j = neighbours[i].index;
    const double w = sum > 0 ? (d_max - dist[i]) / sum : 1.0 / n;       // (5.4)
    depth += w * originals.normals[j].dot(originals.positions[j] - x);  // (5.2)
    normal += w * originals.normals[j];                                 // (5.3)
  }
  c.closest = neighbours[0].index;
  c.depth = depth;
  c.normal_length = normal.norm();
  if (c.normal_length > 0) c.normal = normal / c.normal_length;
  const bool below_closest =
      (x - originals.positions[c.closest]).dot(originals.normals[c.closest]) < 0;  // (3.9)
  c.inside = below_closest && depth > 0;
  return c;
}

SurfaceContact forceShade(const PaintSurface& surface, const Vec3& x, int n) {
  if (n < 1 || n > 64) throw std::invalid_argument("forceShade: n must lie in 1..64");
  std::array<Neighbor, 64> found;
  const size_t count = surface.nearestOriginals(x, size_t(n), found.data());
  return forceShade(surface.originals(), x, found.data(), count);
}

}  // namespace rc
