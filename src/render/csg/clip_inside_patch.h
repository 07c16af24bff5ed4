// Inside/outside classification of a point against a patch from nearby surfels (thesis 4.1.1): the half-space
// test (4.3), the concave/convex rule of the two closest surfels (4.4, Fig. 4.2) and Algorithm 4.4.
#pragma once

#include <cstdint>
#include <limits>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/csg_tri_logic.h"

namespace rc {

/// s clips x iff x is not inside by (4.3): (x - c_s) . N_s >= 0.
inline bool surfelClips(const Vec3& c, const Vec3& n, const Vec3& x) {
  return (x - c).dot(n) >= 0.0;
}

/// Two surfels are concave iff s1 clips c2 and s2 clips c1 (Fig. 4.2a); otherwise convex (Fig. 4.2b).
inline bool surfelsConcave(const Vec3& c1, const Vec3& n1, const Vec3& c2, const Vec3& n2) {
  return surfelClips(c1, n1, c2) && surfelClips(c2, n2, c1);
}

/// (4.4): inside iff not clipped by s1 OR not clipped by s2 for a concave pair (the solid is the union of the
/// two half-spaces, an inner corner), AND for a convex pair (the intersection, an outer edge, Fig. 4.2b).
inline bool insideTwoClosest(const Vec3& x, const Vec3& c1, const Vec3& n1, const Vec3& c2, const Vec3& n2) {
  const bool in1 = !surfelClips(c1, n1, x), in2 = !surfelClips(c2, n2, x);
  return surfelsConcave(c1, n1, c2, n2) ? (in1 || in2) : (in1 && in2);
}

/// Algorithm 4.4 over the candidate surfels `ids[0..count)` (the clipping partners of one patch):
/// unknown if none, (4.3) with the only one, else (4.4) with the two closest to x. Allocation-free.
template <class Index>
Tri insidePatchFromSurfels(const Vec3& x, const Index* ids, size_t count, const Vec3* centers,
                           const Vec3* normals) {
  if (count == 0) return Tri::kUnknown;
  if (count == 1) return toTri(!surfelClips(centers[ids[0]], normals[ids[0]], x));
  double d0 = std::numeric_limits<double>::infinity(), d1 = d0;
  size_t i0 = 0, i1 = 0;
  for (size_t k = 0; k < count; ++k) {  // sortForDistance, keeping the two closest (ties: lower position)
    const double d = (centers[ids[k]] - x).squaredNorm();
    if (d < d0) {
      d1 = d0;
      i1 = i0;
      d0 = d;
      i0 = k;
    } else if (d < d1) {
      d1 = d;
      i1 = k;
    }
  }
  if (i0 == i1) i1 = (i0 == 0) ? 1 : 0;  // all distances infinite/NaN: any two
  return toTri(insideTwoClosest(x, centers[ids[i0]], normals[ids[i0]], centers[ids[i1]], normals[ids[i1]]));
}

}  // namespace rc
