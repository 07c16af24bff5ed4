// Samplers that turn the analytic patch shapes of a CSG scene (thesis 4.3-4.4) into surfels with exact
// outward normals and covering radii: sphere, ellipsoid, square on a plane (one side of a half-space) and the
// six faces of a box. Normals always point out of the solid; a solid entering the CSG as a complement keeps
// them (the CSG tree handles the inversion, 4.3). Only positions, normals, radii (and for ellipsoids
// elliptical axes) are filled.
#pragma once

#include <Eigen/Geometry>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Radii are `radius_scale` times the covering radius of the sampling lattice (the largest distance from a
/// surface point to its nearest sample), so radius_scale >= 1 leaves no holes.
/// Either `samples` or `spacing` (> 0) sets the density; `spacing` wins when both are set.
struct PatchSampling {
  size_t samples = 0;         ///< number of surfels (per face for boxes; squares use the nearest m x m grid)
  double spacing = 0;         ///< mean sample spacing sqrt(area per surfel)
  double radius_scale = 1.5;  ///< multiple of the covering radius

  /// Surfel count for a surface of the given area.
  size_t countFor(double area) const;
};

/// Fibonacci lattice on a sphere; circular surfels.
SurfelCloud sampleSphere(const Vec3& center, double radius, const PatchSampling& sampling);

/// Ellipsoid {c + R diag(semi_axes) u : |u| = 1}: the sphere's Fibonacci lattice mapped through the
/// ellipsoid; elliptical surfels (axes1/axes2 are the exact image of the sphere's covering disk, radii their
/// larger semi-axis).
SurfelCloud sampleEllipsoid(const Vec3& center, const Vec3& semi_axes, const Eigen::Matrix3d& rotation,
                            const PatchSampling& sampling);

/// Square of side `size` centred at `center` on the plane with outward normal `normal`; one edge direction is
/// `up` projected into the plane. m x m grid with m = max(1, round(sqrt(samples))).
SurfelCloud samplePlaneSquare(const Vec3& center, const Vec3& normal, const Vec3& up, double size,
                              const PatchSampling& sampling);

/// One surfel of the given radius at `center` (a half-space represented by a single disk, Fig. 4.10).
SurfelCloud samplePlaneDisk(const Vec3& center, const Vec3& normal, double radius);

/// The six faces of the box c + R [-h, h]: each face an m x m grid with `sampling.samples` per face.
SurfelCloud sampleBoxFaces(const Vec3& center, const Vec3& half_extents, const Eigen::Matrix3d& rotation,
                           const PatchSampling& sampling);

/// Unit vector orthogonal to n (any).
Vec3 anyOrthogonal(const Vec3& n);

}  // namespace rc
