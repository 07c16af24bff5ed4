// Skinning of a surface (mesh vertices or surfels) with the particles of an elastic solid (thesis 8.2.7):
// every surface point s^0 is bound once, in the rest state, to the solid particles i within the kernel
// support h of it, with the rest offsets s^0 - X_i. Per frame each bound particle predicts the point as
// s_i = x_i + F_i (s^0 - X_i) from its transform F_i, and the predictions are averaged with the SPH
// smoothing operator (8.38): s = sum_i w_i s_i, w_i = V_i W_h(|s^0 - X_i|) / sum_k V_k W_h(|s^0 - X_k|).
//
// Reading of (8.38): the weights are the poly6 kernel of the rest distance times the particle volume, and
// they are normalised (Shepard). Unnormalised, sum_i V_i W_h is about 0.5 at a solid's surface (see
// restWeightSums()), which would pull the skin towards the origin; normalised, the skin has linear
// precision: when every F_i is the gradient F of an affine motion x = F X + t, s = F s^0 + t exactly.
//
// Transforms F_i come either from the solid (SphElasticSolid::latticeTransforms(): A_i maps lattice
// coordinates to the world, so bind with the rest transforms A_i^0 and the skin uses A_i (A_i^0)^-1), or
// from fitTransforms(): a weighted least-squares affine fit of every bound particle's rest neighbourhood
// to its current positions (exact for affine motions; directions without rest neighbours, e.g. z in 2D,
// keep the identity). Normals follow the blended Jacobian J = sum_i w_i F_i as cof(J) n^0 = det(J)
// J^-T n^0, renormalised; tangent axes as J t; circular radii by the equal-area factor
// sqrt(|cof(J) n^0|) (Nanson's formula).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// What to do with a surface point that has no solid particle within the support radius.
enum class SphSkinOrphanPolicy {
  kThrow,            ///< std::invalid_argument naming the point and its distance to the nearest particle
  kNearestParticle,  ///< bind it to its nearest particle alone (weight 1)
};

struct SphSkinConfig {
  /// h of W_h in (8.38): particles closer than h to a rest surface point are bound to it. Finite, > 0;
  /// typically the solver's smoothing length.
  double support_radius = 0.0;
  /// Radius of the rest neighbourhoods of fitTransforms(); 0: support_radius. Finite, >= 0.
  double fit_radius = 0.0;
  SphSkinOrphanPolicy orphans = SphSkinOrphanPolicy::kThrow;
  /// 2 or 3: normalisation of the poly6 kernel in restWeightSums() (the skin itself does not depend on it).
  int dimension = 3;
  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
};

/// The rest configuration of the particle solid a surface is bound to. Arrays are indexed by particle
/// index of the whole particle system (as SphParticles, whose indices are stable).
struct SphSkinRest {
  std::vector<Vec3> positions;  ///< X, all particles of the system (rest state)
  /// The particles of the solid; empty: all particles.
  std::vector<uint32_t> solid;
  /// V_i (empty: all equal; the weights are normalised, so only ratios matter). > 0 where used.
  std::vector<double> volumes;
  /// Rest transforms A_i^0 of the transforms passed to deform() (empty: uniform_transform for all). For
  /// SphElasticSolid::latticeTransforms() this is the lattice orientation the solid was sampled with.
  std::vector<Eigen::Matrix3d> transforms;
  Eigen::Matrix3d uniform_transform = Eigen::Matrix3d::Identity();
};

/// Particles of `particles` with phase `phase` (kind kFluid), for SphSkinRest::solid.
std::vector<uint32_t> solidParticleIndices(const SphParticles& particles, uint8_t phase);

/// A surface bound to the rest state of a particle solid (8.38). Binding is O(points log particles);
/// deform() is O(bound pairs + fit pairs of the bound particles), OpenMP parallel, and allocation-free
/// after the first call.
class SphSkin {
 public:
  SphSkin() = default;
  /// Binds `rest_points` (the rest surface) to `rest`. Throws std::invalid_argument for a bad config,
  /// non-finite points or particle positions, a solid index out of range, a volume not > 0, a singular
  /// rest transform, points but no solid particles, and (kThrow) a point with no particle within
  /// support_radius.
  SphSkin(const SphSkinRest& rest, const std::vector<Vec3>& rest_points, const SphSkinConfig& config);

  const SphSkinConfig& config() const { return config_; }
  size_t pointCount() const { return rest_points_.size(); }
  /// (point, particle) pairs of (8.38).
  size_t pairCount() const { return pair_particle_.size(); }
  /// Distinct solid particles bound to at least one point (their global indices).
  const std::vector<uint32_t>& boundParticles() const { return bound_; }
  /// Points bound to their nearest particle because none was within support_radius (kNearestParticle).
  size_t orphanCount() const { return orphans_; }
  /// Per point: sum_i V_i W_h(|s^0 - X_i|) with the poly6 kernel (C.1) before normalisation (1 inside a
  /// full neighbourhood, about 0.5 on a flat surface of the solid; 0 for orphans).
  const std::vector<double>& restWeightSums() const { return weight_sum_; }

  /// Per particle of the system, the least-squares affine transform of its rest neighbourhood (radius
  /// fit_radius, poly6 weights) to `positions`, composed with its rest transform (so it is what deform()
  /// expects); written for the bound particles only (`out` is resized to the system size, other entries
  /// are left as they were or identity when new). Throws std::invalid_argument for a wrong size.
  void fitTransforms(const std::vector<Vec3>& positions, std::vector<Eigen::Matrix3d>& out) const;

  /// Deforms the surface (8.38) with the current particle `positions` and transforms (system size; only
  /// bound particles are read). Throws std::invalid_argument for wrong sizes.
  void deform(const std::vector<Vec3>& positions, const std::vector<Eigen::Matrix3d>& transforms);
  /// Deforms with the transforms of fitTransforms() (no transforms from the solid needed).
  void deform(const std::vector<Vec3>& positions);

  /// Results of the last deform(): deformed points and the blended Jacobians J = sum_i w_i F_i.
  const std::vector<Vec3>& points() const { return points_; }
  const std::vector<Eigen::Matrix3d>& jacobians() const { return jacobians_; }

  /// Normals after the last deform(): cof(J) n^0 renormalised (unit; n^0 kept where that vanishes).
  /// Throws std::invalid_argument unless rest_normals has pointCount() entries.
  void transformNormals(const std::vector<Vec3>& rest_normals, std::vector<Vec3>& out) const;
  /// `rest` (the bound surface: positions == rest points) deformed by the last deform(): positions,
  /// normals, tangent axes (J t) and radii (times sqrt of the area factor |cof(J) n^0|, or |det J|^(1/3)
  /// without normals). Other
  /// channels are copied. Throws std::invalid_argument if rest.size() != pointCount().
  void deformSurfels(const SurfelCloud& rest, SurfelCloud& out) const;
  /// The same for the vertices of a mesh; triangles are copied.
  void deformMesh(const TriangleMesh& rest, TriangleMesh& out) const;

 private:
  /// Affine fits F_l of the bound particles (compact order).
  void fitCompact(const std::vector<Vec3>& positions, std::vector<Eigen::Matrix3d>& compact) const;
  void blend(const std::vector<Vec3>& positions);
  void checkPositions(const std::vector<Vec3>& positions) const;

  SphSkinConfig config_;
  size_t system_size_ = 0;
  std::vector<Vec3> rest_points_;
  // Bound particles (compact index l): global index, inverse rest transform, current F_l.
  std::vector<uint32_t> bound_;
  std::vector<Eigen::Matrix3d> rest_transform_, rest_inverse_, current_;
  // (8.38) pairs of point p: [pair_begin_[p], pair_begin_[p + 1]).
  std::vector<size_t> pair_begin_;
  std::vector<uint32_t> pair_particle_;  // compact
  std::vector<double> pair_weight_;      // normalised w_i
  std::vector<Vec3> pair_offset_;        // s^0 - X_i
  std::vector<double> weight_sum_;
  size_t orphans_ = 0;
  // Affine fit of bound particle l: neighbours [fit_begin_[l], fit_begin_[l + 1]), F = B M^+ + (I - M M^+).
  std::vector<size_t> fit_begin_;
  std::vector<uint32_t> fit_neighbor_;  // global
  std::vector<double> fit_weight_;
  std::vector<Vec3> fit_rest_;  // X_j - X_i
  std::vector<Eigen::Matrix3d> fit_moment_pinv_, fit_null_;
  // Last deform().
  std::vector<Vec3> points_;
  std::vector<Eigen::Matrix3d> jacobians_;
};

/// Skin meshes of the solid shapes of scene files (`skin: {resolution: n}`), closed, outward oriented and
/// centred at the origin (rotate and move them with the solid). Throws std::invalid_argument for a
/// resolution outside [1, 1000] or a non-positive size.
/// Box [-half_extent, half_extent]: each face an n x n grid of quads split into two triangles; vertices are
/// shared between faces: 6 n^2 + 2 vertices, 12 n^2 triangles.
TriangleMesh sphBoxSkinMesh(const Vec3& half_extent, int resolution);
/// Sphere of `radius`: the icosahedron with every face split into n x n triangles, projected onto the
/// sphere (geodesic frequency n): 10 n^2 + 2 vertices, 20 n^2 triangles, unit outward vertex normals.
TriangleMesh sphSphereSkinMesh(double radius, int resolution);

}  // namespace rc
