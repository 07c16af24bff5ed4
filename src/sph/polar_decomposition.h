// Rotational part of a 3x3 deformation by the quaternion iteration of Mueller, Bender, Chentanez and
// Macklin 2016 ("A robust method to extract the rotational part of deformations", MIG '16), warm-started
// from a previous rotation: the rotation R (8.24) of the lattice fit without a full SVD.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rc {

/// Iterates the rotation q towards the rotation R that maximises tr(R^T a) (the rotation of the polar
/// decomposition a = R S for det a > 0; the reflection-safe U V^T of the SVD in general), starting from q:
/// q <- exp(omega) q. With M = a R(q)^T, t the axial vector of M - M^T (= sum_k r_k x a_k over the columns)
/// and H = tr(M) I - sym(M) (the Hessian of tr(R^T a) in omega), omega = H^-1 t (Newton; quadratic
/// convergence) where H is positive definite, else Mueller et al.'s omega = t / (|tr M| + 1e-9). Stops when
/// |omega| <= tolerance or after a Newton step with |omega| < 1e-7 (returns true; the error is then of the
/// order of |omega|^2), or after max_iterations (returns false). q is kept normalised.
bool extractRotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q, int max_iterations = 50,
                     double tolerance = 1e-13);

}  // namespace rc
