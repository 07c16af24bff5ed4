// 3D mean value coordinates (Floater, Kos & Reimers 2005; Ju, Schaefer & Warren 2005) on the triangulated
// surface of a convex polyhedral element: shape functions (9.8)-(9.10) and their analytic gradients (appendix
// D).
#pragma once

#include <Eigen/Core>

#include "relaxed_connectivity/fem/convex_polyhedron.h"

namespace rc {

/// Where an evaluation point lies. On the boundary the coordinates are the limits from inside: barycentric
/// coordinates of the boundary triangle containing the point (linear along an edge, Kronecker delta at a
/// node).
enum class BoundaryContact { kInterior, kFace, kEdge, kVertex };

/// Shape functions phi_i = w_i / sum_k w_k of one element. The weights are computed per boundary triangle T
/// (vertices i of T, d_i = x_i - x, c_i = d_{i+1} x d_{i+2}, D_T = det[d_0 d_1 d_2] = 6 V_T):
///   m_T = sum_k beta_k c_k / |c_k|,  beta_k = angle(d_{k+1}, d_{k+2}) = atan2(|c_k|, d_{k+1} . d_{k+2}),
///   w_i += (m_T . c_i) / D_T,
/// which regroups the one-ring sums of (9.8)/(9.9) triangle by triangle (m_T is twice the integral of the
/// unit normal over the spherical triangle, so sum_T m_T = 0 gives linear precision (9.11)). Gradients are
/// exact derivatives of these expressions (appendix D, (D.1)), evaluated with beta/|c| = alpha/(|d_a||d_b|
/// sin alpha) as in (D.4). Zero-area triangles contribute nothing and are skipped. On tetrahedra the
/// coordinates are the linear (barycentric) shape functions, computed directly unless
/// Options::tetrahedron_shortcut is false.
///
/// evaluate() is const, thread-safe and allocation-free for interior points.
class MeanValueCoordinates {
 public:
  struct Options {
    bool tetrahedron_shortcut = true;
    /// Points within this distance (relative to the element scale) of a face plane are on the boundary.
    double boundary_relative_tolerance = 1e-14;
    /// On the boundary, gradients are the limits along the ray towards the centroid, extrapolated
    /// (Richardson) from the interior gradients at distances h and 2h; h = this * element scale.
    double boundary_gradient_offset = 1e-5;
  };

  explicit MeanValueCoordinates(const ConvexPolyhedron& element) : MeanValueCoordinates(element, Options()) {}
  MeanValueCoordinates(const ConvexPolyhedron& element, Options options);

  const ConvexPolyhedron& element() const { return element_; }
  int numNodes() const { return element_.numNodes(); }

  /// lambda[i] = phi_i(x) (numNodes() values); gradients (may be null): gradients[i] = grad phi_i(x).
  /// Throws std::domain_error if x is outside the element by more than the element tolerance.
  BoundaryContact evaluate(const Vec3& x, double* lambda, Vec3* gradients = nullptr) const;
  /// Convenience: resizes lambda (n) and gradients (n x 3, row i = grad phi_i^T).
  BoundaryContact evaluate(const Vec3& x, Eigen::VectorXd& lambda,
                           Eigen::Matrix<double, Eigen::Dynamic, 3>& gradients) const;

  /// Unnormalised mean value weights w_i (9.8) and gradients grad w_i (D.2) at an interior point (x must not
  /// be on a face plane). Always the general formula (no tetrahedron shortcut).
  void weights(const Vec3& x, double* w, Vec3* grad_w) const;

 private:
  BoundaryContact evaluateBoundary(const Vec3& x, int face, double* lambda, Vec3* gradients) const;
  void evaluateInterior(const Vec3& x, double* lambda, Vec3* gradients) const;

  ConvexPolyhedron element_;
  Options options_;
  std::vector<ConvexPolyhedron::Triangle> active_triangles_;  // non-zero area
  bool use_barycentric_ = false;
  Eigen::Matrix3d tet_inverse_;  // rows: grad phi_1..3 of the tetrahedron
};

}  // namespace rc
