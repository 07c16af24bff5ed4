// Globally implicit goal springs of one elastic solid (thesis 8.2.3, (8.29)-(8.31)): backward Euler on the
// goal forces linearised with the goal positions held fixed within the step, solved by preconditioned CG
// over all of the solid's particles.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sph/sph_particles.h"

namespace rc {

/// A goal spring of a neighbourhood: with the goal g held fixed, the force 0.5 K_e m_i V W_ij (g - r_ij) of
/// (8.31) on `other` (minus on the centre) has the stiffness `stiffness` = 0.5 K_e m_i V W_ij in x_j - x_i.
struct SphGoalSpring {
  uint32_t other;
  double stiffness;
};

struct SphImplicitGoalResult {
  int iterations = 0;
  double relative_residual = 0.0;  ///< |r|_{D^-1} / |b|_{D^-1} at the end (D the Jacobi preconditioner)
  bool converged = false;
};

/// A velocity constraint of one particle: the components of dv along `normals` (orthonormal, up to 3) are
/// prescribed (dv . n_k = values_k), the others are free. 3 normals fix the particle (anchors).
struct SphVelocityConstraint {
  uint32_t particle = 0;
  int count = 0;
  Vec3 normals[3];
  double values[3] = {0.0, 0.0, 0.0};
};

/// The linear system of one step, (M + dt^2 K) dv = dt (f0 - dt K v), with K = (I - P)^T L (I - P): L the
/// stiffness of the goal springs held fixed (a weighted graph Laplacian, the same for x, y and z), P the
/// mass-weighted projection onto the rigid motions of the whole solid (translation and rotation about the
/// centre of mass), so that K neither damps a rigid motion nor exerts a net force or torque. Local
/// rotations of parts (bending, pieces of a broken solid) are treated like deformation: damped as backward
/// Euler damps. Constrained velocity components (plane contacts, anchors) are prescribed and solved with
/// the filtered CG of Baraff & Witkin (1998).
class SphImplicitGoalSolver {
 public:
  /// Sets the system: positions and masses of the solid's particles and per particle s the springs of its
  /// neighbourhood (centre s). Clears the constraints.
  void setSystem(const std::vector<Vec3>& positions, const std::vector<double>& masses,
                 const std::vector<std::vector<SphGoalSpring>>& springs);
  /// Replaces the constraints (at most one per particle).
  void setConstraints(const std::vector<SphVelocityConstraint>& constraints);
  const std::vector<SphVelocityConstraint>& constraints() const { return constraints_; }

  size_t size() const { return masses_.size(); }
  /// y = K u.
  void applyStiffness(const std::vector<Vec3>& u, std::vector<Vec3>& y) const;
  /// f <- (I - P)^T f: removes the net force and the net torque of f (about any point) by subtracting the
  /// mass-weighted rigid distribution.
  void removeNetForceAndTorque(std::vector<Vec3>& f) const;
  /// Solves (M + dt^2 K) dv = dt (f0 - dt K v) for the free components by CG with the Jacobi preconditioner
  /// m_s + dt^2 L_ss, the constrained ones prescribed, starting from dv (warm start), until
  /// |r|_{D^-1} <= tolerance |b|_{D^-1} or max_iterations.
  SphImplicitGoalResult solve(const std::vector<Vec3>& f0, const std::vector<Vec3>& v, double dt,
                              double tolerance, int max_iterations, std::vector<Vec3>& dv) const;
  /// The impulses the constraints exert in the solution dv: (M + dt^2 K) dv - dt (f0 - dt K v) at the
  /// constrained particles (one per constraint, in order).
  void constraintImpulses(const std::vector<Vec3>& f0, const std::vector<Vec3>& v, double dt,
                          const std::vector<Vec3>& dv, std::vector<Vec3>& impulses) const;

 private:
  /// u <- (I - P) u: the rigid motion that fits u best (mass-weighted) removed.
  void removeRigidMotion(std::vector<Vec3>& u) const;
  /// y = L u (the fixed-goal springs without projection).
  void applyLaplacian(const std::vector<Vec3>& u, std::vector<Vec3>& y) const;
  /// Zeroes the constrained components of a.
  void filter(std::vector<Vec3>& a) const;
  /// b = dt (f0 - dt K v).
  void rightHandSide(const std::vector<Vec3>& f0, const std::vector<Vec3>& v, double dt,
                     std::vector<Vec3>& b) const;

  // Symmetric rows of L: y_s = diag_s u_s - sum_e coefs_e u_{cols_e}.
  std::vector<uint32_t> row_begin_, cols_;
  std::vector<double> coefs_, diag_;
  std::vector<uint32_t> marker_;  // scratch of setSystem
  std::vector<double> masses_;
  std::vector<Vec3> arms_;  // x_s - centre of mass
  std::vector<SphVelocityConstraint> constraints_;
  bool rigid_projection_ = false, rotation_ = false;
  double total_mass_ = 0.0;
  Eigen::Matrix3d inertia_inverse_ = Eigen::Matrix3d::Zero();
  mutable std::vector<Vec3> r_, z_, p_, q_, t_;  // CG scratch
};

}  // namespace rc
