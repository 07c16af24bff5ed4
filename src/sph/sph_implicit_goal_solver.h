// Globally implicit goal springs of elastic solids (thesis 8.2.3, (8.29)-(8.31)): backward Euler on the
// goal forces linearised with the goal positions held fixed within the step, solved by preconditioned CG
// over all of a solid's particles; solids in contact are solved together with their penalty springs (8.37).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/sph/sph_particles.h"

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
  /// Anchors (prescribed motion): never released. Others (plane contacts) let go where they would pull.
  bool fixed = false;
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

  /// OpenMP threads of setSystem and the stiffness products (>= 1; results are the same for any count).
  void setThreads(int threads) { threads_ = threads > 1 ? threads : 1; }
  size_t size() const { return masses_.size(); }
  const std::vector<double>& masses() const { return masses_; }
  /// L_ss: the diagonal of the spring Laplacian (the Jacobi preconditioner is m_s + dt^2 L_ss).
  const std::vector<double>& laplacianDiagonal() const { return diag_; }
  /// Zeroes the constrained components of a.
  void filter(std::vector<Vec3>& a) const;
  /// b = dt (f0 - dt K v).
  void rightHandSide(const std::vector<Vec3>& f0, const std::vector<Vec3>& v, double dt,
                     std::vector<Vec3>& b) const;
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

  // Symmetric rows of L: y_s = diag_s u_s - sum_e coefs_e u_{cols_e}.
  std::vector<uint32_t> row_begin_, cols_;
  std::vector<double> coefs_, diag_;
  int threads_ = 1;
  // Scratch of setSystem: per thread the row counts and write positions of its centres' springs and a marker
  // per column; the unmerged rows.
  std::vector<std::vector<uint32_t>> thread_counts_, thread_markers_;
  std::vector<uint32_t> raw_begin_, raw_cols_, merged_count_;
  std::vector<double> raw_coefs_;
  std::vector<double> masses_;
  std::vector<Vec3> arms_;  // x_s - centre of mass
  std::vector<SphVelocityConstraint> constraints_;
  bool rigid_projection_ = false, rotation_ = false;
  double total_mass_ = 0.0;
  Eigen::Matrix3d inertia_inverse_ = Eigen::Matrix3d::Zero();
  mutable std::vector<Vec3> r_, z_, p_, q_, t_;  // CG scratch
};

/// A penalty spring (8.37) between particles i and j of two solids, linearised at the current positions for
/// the implicit step: the force on j along n = (x_j - x_i) / r at the end of the step is
///   N = force - (dt stiffness + damping) n . (v_j - v_i)   (v: the end-of-step velocities),
/// on i minus that; only N > 0 (repulsion) is applied.
struct SphContactSpring {
  uint32_t first = 0, second = 0;  ///< original particle indices i and j
  Vec3 normal = Vec3::UnitX();     ///< n
  double force = 0.0;              ///< the normal force on j at the current positions
  double stiffness = 0.0;          ///< -dN/dr (N/m), >= 0
  double damping = 0.0;            ///< coefficient of the approach speed (N s/m), >= 0
};

/// One solid's part of an implicit step (SphElasticSolid with global implicit goal springs): its system
/// (springs, rigid projection, constraints) and the step's data per solver particle. The pointers stay
/// valid until the block is solved.
struct SphImplicitGoalBlock {
  SphImplicitGoalSolver* solver = nullptr;
  const std::vector<uint32_t>* particles = nullptr;  ///< original index per solver particle
  const std::vector<Vec3>* f0 = nullptr;             ///< explicit goal forces (8.31)
  const std::vector<Vec3>* velocity = nullptr;       ///< the velocity the springs resist
  std::vector<Vec3>* dv = nullptr;                   ///< warm start in, velocity change out
  std::vector<Vec3>* force = nullptr;                ///< out: the step's force (the solver's velocity change)
  double dt = 0.0;
  double tolerance = 1e-4;  ///< CG relative residual
  int max_iterations = 200;
  /// Called once the block is solved (dv, force written, forces added).
  std::function<void(const SphImplicitGoalResult&)> finish;
};

/// Statistics of SphImplicitGoalCoupling::solve.
struct SphImplicitCouplingStats {
  size_t groups = 0;           ///< systems solved: solids in contact form one
  size_t coupled_solids = 0;   ///< solids in a group of two or more
  size_t active_contacts = 0;  ///< contact springs that push at the end (released: pulled, (8.37))
  size_t released_contacts = 0;
  int iterations = 0;  ///< CG iterations, all groups and rounds
};

/// Backward Euler over several solids at once with the penalty springs between them (8.37): solids joined by
/// contact springs form a group, whose velocity changes solve one system
///   (M + dt^2 K + dt G) dv = dt (f0 + f_c - (dt K + G) v),
/// K block-diagonal of the solids' goal stiffness (SphImplicitGoalSolver, rigid motions projected out per
/// solid), G = sum_p (dt k_p + c_p) (e_j - e_i)(e_j - e_i)^T (x) n n^T the contact springs and f_c their
/// forces, by CG with a 3x3 block Jacobi preconditioner, the constraints of each solid filtered. Contact
/// springs that would pull and plane constraints that would pull are released, and the group solved
/// again (warm-started, up to 4 rounds). The force of a particle is its goal force and contact forces at the
/// end of the step, f0 - dt K (v + dv) + sum_p N_p n_p, plus along constrained normals the constraint's
/// impulse: the goal part has no net force or torque per solid and the contact parts are central and
/// antisymmetric, so without constraints the group's linear and angular momentum are exact to rounding
/// whatever the CG residual. A solid alone keeps its own solve (SphImplicitGoalSolver::solve, force
/// M dv / dt, without constraints its net force and torque removed).
///
/// Protocol per force evaluation: each solid submits its block, then solve() runs once (the contact term
/// after the solids) and clears the blocks.
class SphImplicitGoalCoupling {
 public:
  /// Adds a block. Throws std::logic_error when a block with the same particles is still pending (no
  /// solve() since its last submission), std::invalid_argument for inconsistent sizes.
  void submit(SphImplicitGoalBlock block);
  size_t pendingBlocks() const { return blocks_.size(); }
  /// The pending block holding original particle i (-1: none) and its index in the block's solver.
  int32_t blockOf(size_t i) const { return i < owner_.size() ? owner_[i] : -1; }
  uint32_t localIndexOf(size_t i) const { return local_[i]; }
  /// Solves the pending blocks with the contact springs (both ends in pending blocks), adds the forces to
  /// `forces` (original order), calls each block's finish and clears the blocks. Throws
  /// std::invalid_argument for a contact with an end outside the pending blocks or blocks of different dt.
  SphImplicitCouplingStats solve(const std::vector<SphContactSpring>& contacts, std::vector<Vec3>& forces);

 private:
  struct Contact {
    uint32_t a, sa, b, sb;  // block and local index of i and j
    Vec3 normal;
    double force, coefficient, rate;  // f_p, dt (dt k_p + c_p), dt k_p + c_p
    bool active;
  };
  struct Work {  // per block of a group: CG vectors, right-hand sides, preconditioner
    std::vector<Vec3> r, z, p, q, t, b, b0;
    // Inverse diagonal blocks: scalar without contacts, else 3x3 (index into contact_blocks).
    std::vector<double> scalar;
    std::vector<int32_t> contact_block;
    std::vector<Eigen::Matrix3d> contact_blocks;
  };
  using Field = std::vector<Vec3> Work::*;
  /// A solid without contacts: its own solve with released plane constraints.
  SphImplicitGoalResult solveAlone(SphImplicitGoalBlock& block);
  /// A group of blocks with its contacts (indices into contacts_): rounds of CG with released contacts and
  /// planes, then the forces.
  SphImplicitGoalResult solveGroup(const std::vector<uint32_t>& group, const std::vector<uint32_t>& contacts,
                                   SphImplicitCouplingStats& stats);
  /// Right-hand sides (b) and preconditioners at the current constraints and active contacts.
  void prepareGroup(const std::vector<uint32_t>& group, const std::vector<uint32_t>& contacts);
  /// Preconditioned CG on the group from the blocks' dv.
  SphImplicitGoalResult conjugateGradients(const std::vector<uint32_t>& group,
                                           const std::vector<uint32_t>& contacts, double tolerance,
                                           int max_iterations);
  /// out = A in over the group, filtered by the constraints when `filter`.
  void applyGroup(const std::vector<uint32_t>& group, const std::vector<uint32_t>& contacts, Field in,
                  Field out, bool filter);
  /// z = D^-1 r, filtered.
  void precondition(uint32_t block);
  /// The normal force on j of contact c at the end-of-step velocities v + dv.
  double contactForce(const Contact& c) const;

  std::vector<SphImplicitGoalBlock> blocks_;
  std::vector<int32_t> owner_;
  std::vector<uint32_t> local_;
  std::vector<Contact> contacts_;
  std::vector<Work> work_;
  std::vector<Vec3> impulses_;
  std::vector<uint32_t> parent_;  // union-find over the blocks
};

}  // namespace rc
