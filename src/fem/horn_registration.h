// Closed-form absolute orientation (Horn 1987, thesis [103]) used for the per-element rotations of stiffness
// warping (thesis 9.1.4): the proper rotation R minimising sum_i w_i |R (X_i - C) - (x_i - c)|^2 with C, c
// the weighted centroids. The unit quaternion of R is the eigenvector of the largest eigenvalue of Horn's
// symmetric 4x4 matrix N(S), S = sum_i w_i (X_i - C)(x_i - c)^T. Unlike polar decomposition of a deformation
// gradient it never returns a reflection and stays well defined for flat (planar) point sets.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct HornRegistration {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // maps rest offsets to current offsets
  Vec3 rest_centroid = Vec3::Zero();
  Vec3 current_centroid = Vec3::Zero();
  /// Gap between the two largest eigenvalues of N relative to the largest |eigenvalue|; ~0 means the
  /// rotation is not determined (collinear or collapsed points).
  double eigenvalue_gap = 0.0;
};

/// Horn's symmetric 4x4 matrix for the cross-covariance S (rest x current); quaternion order (w, x, y, z).
Eigen::Matrix4d hornMatrix(const Eigen::Matrix3d& cross_covariance);

/// Registration of rest points onto current points with non-negative weights (at least one positive).
/// Throws std::invalid_argument for mismatched sizes, negative/non-finite weights or non-finite points.
HornRegistration hornRegistration(const std::vector<Vec3>& rest, const std::vector<Vec3>& current,
                                  const Eigen::VectorXd& weights);

/// The same on the raw 3 n coordinate vectors (node a at 3 a) without validation; the hot path of
/// WarpedDynamics.
HornRegistration hornRegistration(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                  const Eigen::Ref<const Eigen::VectorXd>& current,
                                  const Eigen::Ref<const Eigen::VectorXd>& weights);

/// The same rotation by Newton iterations from `guess` (an element's previous rotation, a warm start in the
/// spirit of Mueller et al. 2016): R maximises tr(R^T A), A = S^T; with B = R^T A, gradient
/// g = (B21 - B12, B02 - B20, B10 - B01), Hessian -(tr(B) I - sym(B)), R <- R exp([H^-1 g]x) until
/// |step| <= 1e-9 (quadratic convergence, a few iterations; the result matches the eigen-solve to round-off).
/// Falls back to the 4x4 eigen-solve for flat, collapsed or mirrored point sets (det A <= 1e-6 (|A|_F /
/// sqrt 3)^3), an indefinite Newton matrix, or no convergence in 8 iterations; *used_eigen_solve tells which.
/// eigenvalue_gap is Horn's: 2 (tr(B) - lambda_max(B)) / tr(B) at the optimum.
HornRegistration warmStartedRegistration(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                         const Eigen::Ref<const Eigen::VectorXd>& current,
                                         const Eigen::Ref<const Eigen::VectorXd>& weights,
                                         const Eigen::Matrix3d& guess, bool* used_eigen_solve = nullptr);

}  // namespace rc
