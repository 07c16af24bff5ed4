// The surfels of a CSG scene seen as elliptical discs (thesis 4.2.1: "the surface is considered to be the
// union of surfel disks"): centre, unit normal, semi-axis vectors, bounding radius, patch and role, plus the
// exact disc-disc intersection test that defines clipping partners.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct SurfelDiscs {
  std::vector<Vec3> centers;
  std::vector<Vec3> normals;  ///< unit
  std::vector<Vec3> axes1;    ///< semi-axis vectors spanning the disc: {c + a t1 + b t2 : a^2 + b^2 <= 1}
  std::vector<Vec3> axes2;
  std::vector<double> radii;  ///< bounding radius (largest semi-axis, 4.2.1)
  std::vector<int32_t> patches;
  std::vector<SurfelRole> roles;
  double max_radius = 0;

  size_t size() const { return centers.size(); }

  /// Reads positions, normals, radii (circular) or axes1/axes2 (elliptical; normals default to t1 x t2), the
  /// int column "patch_id" (required) and "surfel_role" (optional, 0..2). Throws std::invalid_argument naming
  /// the missing or bad channel and the first bad surfel.
  static SurfelDiscs fromCloud(const SurfelCloud& cloud);
  /// Re-reads positions/normals/axes after the cloud moved (same size and patches).
  void updateGeometry(const SurfelCloud& cloud);

  /// True if surfels i and j are clipping partners: different patches, ||c_i - c_j|| < r_i + r_j (the
  /// conservative test of Algorithm 4.1) and the discs intersect in 3D (discsIntersect).
  bool partners(uint32_t i, uint32_t j) const;
};

/// Exact intersection test of two elliptical discs {c + a t1 + b t2 : a^2 + b^2 <= 1} with unit normals n.
/// Each disc's plane cuts the other disc in a chord; the discs intersect iff both chords exist and overlap on
/// the common line. Computed from the chords (not from the plane-plane line), so it stays finite for
/// near-parallel discs; exactly parallel discs intersect iff coplanar (|offset| <= 1e-12 of the radii) and
/// their centres are closer than the sum of the largest semi-axes (conservative).
bool discsIntersect(const Vec3& c1, const Vec3& n1, const Vec3& t11, const Vec3& t12, const Vec3& c2,
                    const Vec3& n2, const Vec3& t21, const Vec3& t22);

}  // namespace rc
