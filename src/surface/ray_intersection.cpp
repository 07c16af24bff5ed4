#include "relaxed_connectivity/surface/ray_intersection.h"

#include <algorithm>
#include <cmath>

namespace rc {

MlsRayHit intersectRayMls(const MlsSurface& surface, const Vec3& origin, const Vec3& dir,
                          const RayIntersectionConfig& config) {
  MlsRayHit result;
  if (!origin.allFinite() || !dir.allFinite() || !(dir.squaredNorm() > 0)) return result;
  const double support = surface.supportRadius();
  const double eps = config.eps > 0 ? config.eps : 1e-10 * support;
  const double eps2 = config.eps2 > 0 ? config.eps2 : 0.5 * support;
  Vec3 q, n, previous = origin, current = origin;
  double t = 0;
  bool converged = false;
  for (int k = 1; k <= config.max_iterations; ++k) {
    if (!surface.fitPlane(previous, &q, &n)) return result;
    const double denom = n.dot(dir);
    if (std::abs(denom) < 1e-12 * dir.norm()) return result;  // ray parallel to the plane
    t = n.dot(q - origin) / denom;  // intersect plane and ray (Algorithm 3.1, line 4)
    current = origin + t * dir;
    result.iterations = k;
    if ((current - previous).norm() < eps) {
      converged = true;
      break;
    }
    previous = current;
  }
  if (!converged || !surface.fitPlane(current, &q, &n)) return result;
  if ((q - current).norm() >= eps2) return result;  // Algorithm 3.1, line 6
  if (t < config.t_min || t > config.t_max) return result;
  result.hit = true;
  result.point = current;
  result.normal = n;
  result.t = t;
  return result;
}

MlsRayHit intersectRayMlsRobust(const MlsSurface& surface, const Vec3& origin, const Vec3& dir,
                                const RayIntersectionConfig& config) {
  MlsRayHit none;
  const SurfelCloud& cloud = surface.cloud();
  if (cloud.empty() || !origin.allFinite() || !dir.allFinite() || !(dir.squaredNorm() > 0)) return none;
  const double support = surface.supportRadius(), len = dir.norm();
  // Clip the ray to the samples' bounding box grown by the support (slab test), in units of dir.
  Vec3 lo, hi;
  cloud.bounds(&lo, &hi);
  lo.array() -= support;
  hi.array() += support;
  double t0 = config.t_min, t1 = config.t_max;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0) {
      if (origin[a] < lo[a] || origin[a] > hi[a]) return none;
      continue;
    }
    double ta = (lo[a] - origin[a]) / dir[a], tb = (hi[a] - origin[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  if (!(t0 <= t1)) return none;
  Neighbor nearest;
  for (double t = t0; t <= t1;) {
    const Vec3 p = origin + t * dir;
    if (surface.tree().knn(p, 1, &nearest) == 0) return none;
    const double dist = std::sqrt(nearest.sq_dist);
    if (dist < support) {
      RayIntersectionConfig local = config;
      local.t_min = -std::numeric_limits<double>::infinity();
      local.t_max = std::numeric_limits<double>::infinity();
      MlsRayHit hit = intersectRayMls(surface, p, dir, local);
      if (hit.hit) {
        hit.t += t;
        if (hit.t >= config.t_min && hit.t <= config.t_max) return hit;
      }
    }
    t += std::max(0.5 * support, dist - support) / len;  // far from the samples: skip the empty space
  }
  return none;
}

}  // namespace rc
