// Ray intersection with the MLS surface by iterated plane fits (thesis Algorithm 3.1, Adamson & Alexa), and a
// robust wrapper that first marches along the ray until it is near the samples.
#pragma once

#include <limits>

#include "relaxed_connectivity/surface/mls_surface.h"

namespace rc {

struct RayIntersectionConfig {
  double eps = 0;   ///< convergence: |x_k - x_(k-1)| < eps (0: 1e-10 * support radius)
  double eps2 = 0;  ///< hit test: |q(x_k) - x_k| < eps2 (0: 0.5 * support radius)
  int max_iterations = 50;
  double t_min = 0;  ///< hits with ray parameter t < t_min (behind the origin) are rejected
  double t_max = std::numeric_limits<double>::infinity();
};

struct MlsRayHit {
  bool hit = false;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  ///< plane normal N(x_k) (oriented like the input normals when present)
  double t = 0;                ///< point = origin + t * dir (dir as passed, not normalised)
  int iterations = 0;
};

/// Algorithm 3.1 from `origin`, which must lie near the surface (the caller culls with a bounding volume).
/// Uses the simplified MLS planes (q(x), N(x)) of `surface` (its weight function and support).
MlsRayHit intersectRayMls(const MlsSurface& surface, const Vec3& origin, const Vec3& dir,
                          const RayIntersectionConfig& config = {});

/// Robust variant for arbitrary origins: marches along the ray in steps of half the support radius (larger
/// far from the samples) until the nearest sample is closer than the support radius, then runs Algorithm 3.1
/// from there; continues marching past starts that yield no hit. Returns the first hit with t in [t_min,
/// t_max] (t_max must be finite or the ray must leave the samples' bounding box).
MlsRayHit intersectRayMlsRobust(const MlsSurface& surface, const Vec3& origin, const Vec3& dir,
                                const RayIntersectionConfig& config = {});

}  // namespace rc
