// Exact CSG ray casting of analytic solids (sphere, ellipsoid, half-space, box): the reference the CSG
// splatting renderer (thesis 4.2) is tested against. Each solid gives the interval list of a ray inside it;
// the CSG tree combines interval lists with union/intersection/difference/complement; the first boundary in
// front of the camera is the visible surface.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// An analytic solid; its outward normals are the normals of the patch sampled from it.
struct AnalyticSolid {
  enum class Kind { kSphere, kEllipsoid, kHalfSpace, kBox };
  Kind kind = Kind::kSphere;
  Vec3 center = Vec3::Zero();     ///< sphere/ellipsoid/box centre; a point on a half-space's plane
  double radius = 1;              ///< sphere
  Vec3 semi_axes = Vec3::Ones();  ///< ellipsoid semi-axes; box half extents (in the rotated frame)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< ellipsoid/box orientation
  Vec3 normal =
      Vec3::UnitZ();  ///< half-space outward unit normal: the solid is {x : (x - center) . normal <= 0}

  static AnalyticSolid sphere(const Vec3& center, double radius);
  static AnalyticSolid ellipsoid(const Vec3& center, const Vec3& semi_axes,
                                 const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity());
  static AnalyticSolid halfSpace(const Vec3& point_on_plane, const Vec3& outward_normal);
  static AnalyticSolid box(const Vec3& center, const Vec3& half_extents,
                           const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity());

  /// The solid moved rigidly by `motion`.
  AnalyticSolid transformed(const Eigen::Isometry3d& motion) const;
  /// Signed distance-like value: negative inside, positive outside, zero on the boundary.
  double implicit(const Vec3& x) const;
  bool contains(const Vec3& x) const { return implicit(x) < 0; }
};

/// A boundary crossing along a ray: parameter t, the patch whose surface it is and the outward normal there
/// (of the interval it bounds).
struct RayBoundary {
  double t = 0;
  int patch = -1;
  Vec3 normal = Vec3::Zero();
};

/// A maximal segment [enter.t, leave.t] of the ray inside a solid; t may be -inf/+inf.
struct RayInterval {
  RayBoundary enter, leave;
};
using IntervalList = std::vector<RayInterval>;  ///< sorted, disjoint

/// Intervals of the ray origin + t dir (unit dir) inside `solid`, boundaries tagged with `patch`.
IntervalList solidIntervals(const AnalyticSolid& solid, int patch, const Vec3& origin, const Vec3& dir);

/// Boolean combinations of interval lists; boundaries keep the patch and outward normal of the result.
IntervalList intervalUnion(const IntervalList& a, const IntervalList& b);
IntervalList intervalIntersection(const IntervalList& a, const IntervalList& b);
IntervalList intervalDifference(const IntervalList& a, const IntervalList& b);
IntervalList intervalComplement(const IntervalList& a);  ///< normals flip (they point out of the complement)

/// First visible surface along a ray.
struct AnalyticHit {
  bool hit = false;
  double t = 0;                ///< ray parameter
  int patch = -1;              ///< patch whose boundary is seen
  Vec3 normal = Vec3::Zero();  ///< outward normal of the CSG result there (flipped on complemented patches)
};

/// Casts rays against `solids[patch]` combined by `tree` (any CsgTree: leaves name patch ids, which index
/// `solids`). Throws std::invalid_argument if a leaf has no solid.
class AnalyticCsgCaster {
 public:
  AnalyticCsgCaster(std::vector<AnalyticSolid> solids, CsgTree tree);
  /// Interval list of the whole tree along a ray.
  IntervalList intervals(const Vec3& origin, const Vec3& dir) const;
  /// First boundary with t > t_min.
  AnalyticHit cast(const Vec3& origin, const Vec3& dir, double t_min = 0) const;
  /// Point classification of the CSG object.
  bool contains(const Vec3& x) const;

 private:
  IntervalList evaluate(int node, const Vec3& origin, const Vec3& dir) const;
  bool containsNode(int node, const Vec3& x) const;
  std::vector<AnalyticSolid> solids_;
  CsgTree tree_;
};

/// Per-pixel reference images (row-major; misses: depth +inf, patch -1, normal zero).
struct AnalyticImages {
  uint32_t width = 0, height = 0;
  std::vector<float> depth;  ///< camera-frame z of the first surface
  std::vector<int32_t> patch_id;
  std::vector<Eigen::Vector3f> normal;  ///< world frame
};

/// Ray casts every pixel centre (Camera::pixelRay at integer (u, v)); surfaces nearer than near_clip are
/// skipped.
AnalyticImages castImage(const AnalyticCsgCaster& caster, const Camera& camera);

}  // namespace rc
