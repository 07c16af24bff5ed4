// Contact of a point with the painted object (thesis 5.4.1): inside/outside by the closest original surfel
// (3.9), penetration depth and normal by force shading over the n nearest originals (5.2)-(5.4).
#pragma once

#include <cstdint>

#include "relaxed_connectivity/core/neighbor.h"
#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

struct SurfaceContact {
  bool inside = false;          ///< (3.9) with the closest surfel: (x - x_c) . N_c < 0, and d > 0
  double depth = 0;             ///< d (5.2) [m]; > 0 below the surface (only meaningful near it)
  Vec3 normal = Vec3::UnitZ();  ///< N (5.3) normalised; (0, 0, 1) when the weighted normals cancel
  double normal_length = 0;     ///< |N| before normalising (1 on a plane, < 1 where normals spread)
  uint32_t closest = 0;         ///< the closest original surfel
};

/// Force shading at x from the given neighbours (sorted by distance, squared distances as the kd-tree returns
/// them): weights w_i = (d_max - d_i) / sum_j (d_max - d_j) (5.4), uniform when all distances are equal.
SurfaceContact forceShade(const SurfelCloud& originals, const Vec3& x, const Neighbor* neighbours,
                          size_t count);
/// The same with the `n` nearest originals of `surface` (n <= 64); one kd-tree query.
SurfaceContact forceShade(const PaintSurface& surface, const Vec3& x, int n);

}  // namespace rc
