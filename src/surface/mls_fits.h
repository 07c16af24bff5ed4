// The local fits of the MLS projections (thesis 3.1) over one weighted neighbourhood: the simplified plane
// (3.5-3.6), Levin's bivariate polynomial (3.1-3.4) and algebraic spheres (APSS, Guennebaud & Gross 2007).
// Internal to rc_surface (used by MlsSurface); every fit works in scaled local coordinates.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/weight_function.h"

namespace rc {

/// The samples of positive weight around an evaluation point p, structure-of-arrays, in scaled local
/// coordinates y_i = (x_i - p) / r (r: the support radius, so |y_i| < 1) with weights w_i = w(|x_i - p|).
/// The arrays are padded with zero-weight entries to a multiple of kLanes so that the sums vectorise.
struct MlsLocalSamples {
  static constexpr size_t kLanes = 2;                   ///< doubles per SIMD packet of the sums
  std::vector<double> x, y, z, sq_norm, w, nx, ny, nz;  ///< sq_norm = |y_i|^2; normals only if present
  size_t count = 0;                                     ///< samples of positive weight
  size_t padded = 0;                                    ///< count rounded up to kLanes
  bool has_normals = false;

  /// Keeps the candidates ids[0..n) (and `extra` unless it is kNoExtra) with |x_i - p| < support. `normals`
  /// may be null. `orient_normals`: the normals are unoriented and are flipped to agree with the (nonzero)
  /// normal of the sample nearest p. Allocates only while the buffers grow. Returns count.
  static constexpr uint32_t kNoExtra = UINT32_MAX;
  size_t gather(const Vec3* positions, const Vec3* normals, const uint32_t* ids, size_t n, uint32_t extra,
                const Vec3& p, double support, const WeightFunction& weight, bool orient_normals = false);
};

/// Plane of (3.5)-(3.6) in local coordinates: centroid q (3.6) and unit normal n (smallest eigenvector of the
/// weighted covariance (3.5), oriented like the sum of the input normals when they are present). False for
/// no weight or collinear / coincident samples.
bool fitLocalPlane(const MlsLocalSamples& s, Vec3* q, Vec3* n);

/// Weighted sum of the input normals (3.8) (unnormalised; zero without normals).
Vec3 localNormalSum(const MlsLocalSamples& s);

/// Levin's second step (3.1)-(3.4): a bivariate polynomial of `degree` over the plane (q, n) fitted in local
/// coordinates, and the closest point of its graph to the local point y (written to foot, with the graph
/// normal). False for an ill-conditioned system.
bool projectLocalPolynomial(const MlsLocalSamples& s, const Vec3& q, const Vec3& n, int degree, const Vec3& y,
                            Vec3* foot, Vec3* normal);

/// Algebraic sphere s(y) = u0 + ul.y + uq |y|^2 in local coordinates.
struct LocalSphere {
  double u0 = 0, uq = 0;
  Vec3 ul = Vec3::Zero();
};
/// Oriented fit with normals (Guennebaud & Gross 2007): all sums in one pass, then the sphere in closed form
/// (gradient fitted to the normals, offset to the points). Needs normals.
bool fitLocalSphereWithNormals(const MlsLocalSamples& s, LocalSphere* sphere);
/// Point-only fit under Pratt's normalisation |ul|^2 - 4 u0 uq = 1 (generalised 5x5 eigenproblem).
bool fitLocalSpherePoints(const MlsLocalSamples& s, LocalSphere* sphere);
/// Closest point of the sphere (or plane, uq -> 0) to y along the gradient line, and the unit gradient there
/// (flipped to agree with the gradient at y unless `keep_orientation`).
bool projectLocalSphere(const LocalSphere& sphere, const Vec3& y, bool keep_orientation, Vec3* foot,
                        Vec3* normal);

}  // namespace rc
