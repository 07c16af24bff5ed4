// Dynamics of a linear elastic polyhedral mesh with stiffness warping (thesis 9.1.4): lumped masses (9.21),
// per-element rotations R_e by Horn's registration (warm-started Newton iterations, eigen-solve fallback),
// corotational forces and linearised implicit Euler on M U'' + D U' + K U = F (9.20), optional Rayleigh
// damping and ground contact by projection.
//
// With rest positions X, current positions x, element centroids C_e, c_e (registration weights) and
// u_e = R_e^T (x_e - c_e) - (X_e - C_e):
//   f_int(x) = -sum_e R_e K_e u_e,            K_w = sum_e R_e K_e R_e^T,          C = alpha M + beta K_w,
//   (M + dt C + dt^2 K_w) dv = dt (f_ext + f_int(x) - C v - dt K_w v),   v+ = v + dv,   x+ = x + dt v+
// (backward Euler with f_int(x+) ~ f_int(x) - K_w (x+ - x), rotations frozen over the step).
// R_e maps rest to current offsets, so the thesis K'_e = R^T K_e R (R current to rest) is R_e K_e R_e^T here.
// Ground contact inside the solve: nodes on or below the plane, or predicted to cross it during the step, are
// held at v+ . n = w_i = min(0, (offset - n . x_i) / dt) (a landing node stops on the plane) by the filter
// S_i = I - n n^T, i.e. (S A S + I - S) y = S (b - A z), dv = y + z with z_i = (w_i - n . v_i) n; held nodes
// whose reaction J_i = n . (A dv - b)_i pulls by more than the solver's error are released, free nodes that
// would still cross are added, and the step re-solved (at most 8 solves). Coulomb friction is the implicit
// tangential impulse -c_i (I - n n^T) v+_i, c_i = mu J_i / |v_t| from the previous step's J_i (capped), so it
// cannot add energy. Nodes left below the plane (solver error) are projected onto it.
// Held dofs (Dirichlet conditions, any subset of a node's components) are eliminated before the contact
// solve: with dv = y + z_h (z_h the prescribed increments that bring each held dof to its target at the end
// of the step), (S_h A S_h + I - S_h) y = S_h (b - A z_h), S_h removing the held dofs; the held dofs'
// reactions are (A dv - b) / dt. A node with a held component takes no ground contact.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {

struct GroundPlane {
  bool enabled = false;
  Vec3 normal = Vec3::UnitZ();  // normalised by WarpedDynamics
  double offset = 0.0;          // plane: normal . x = offset; admissible side normal . x >= offset
  double friction = 0.5;        // Coulomb coefficient, applied inside the implicit solve
};

struct WarpedDynamicsOptions {
  /// kCholmod: supernodal Cholesky (CholmodSolver), analysed once per pattern; needs a build with CHOLMOD.
  /// kCholmodPcg: CG preconditioned by the CHOLMOD factor of an earlier system matrix (the rotations and the
  /// contact set change slowly); when CG does not reach cg_tolerance within pcg_refactor_iterations, the
  /// current matrix is factorised and solved directly (and preconditions the following steps).
  enum class Solver { kConjugateGradient, kSimplicialLDLT, kCholmod, kCholmodPcg };
  enum class Preconditioner { kJacobi, kIncompleteCholesky };
  enum class RotationWeights { kLumpedMasses, kNodeVolumeFractions };

  double time_step = 0.01;
  bool stiffness_warping = true;   // false: R_e = I (plain linear elasticity)
  double mass_damping = 0.0;       // Rayleigh alpha (F.3 uses no damping)
  double stiffness_damping = 0.0;  // Rayleigh beta
  Vec3 gravity = Vec3::Zero();
  GroundPlane ground;
  RotationWeights rotation_weights = RotationWeights::kLumpedMasses;
  Solver solver = Solver::kConjugateGradient;
  Preconditioner preconditioner = Preconditioner::kJacobi;
  double cg_tolerance = 1e-8;  // relative residual |A dv - b| / |b|
  int cg_max_iterations = 2000;
  bool cg_warm_start = true;         // start from the previous step's dv
  int pcg_refactor_iterations = 10;  // kCholmodPcg: CG iterations before refactorising
  /// kCholmodPcg: after pcg_refactor_iterations, CG goes on when its mean residual reduction per iteration
  /// predicts convergence within this many more (0: refactorise at once, the old rule).
  int pcg_extension_iterations = 3;
  /// kCholmodPcg: the preconditioner follows the contact set exactly when at most this many nodes are in
  /// contact differently from the factorised matrix (Schur complements of the factor, one blocked solve per
  /// new contact set); more refactorise. 0: no correction (each changed node costs CG iterations).
  int pcg_contact_updates = 64;
  /// Keep the previous R_e when Horn's top eigenvalue gap is below this (collinear/collapsed element).
  double min_eigenvalue_gap = 1e-12;
};

struct StepStatistics {
  int solver_iterations = 0;  // CG iterations summed over the solves of the step (1 per direct solve)
  int factorizations = 0;     // numeric factorisations (direct solvers, kCholmodPcg refactorisations)
  double solver_error = 0.0;  // CG relative residual estimate (0 for the direct solver)
  bool converged = true;
  int contact_nodes = 0;         // nodes held on the ground inside the solve (v+ . n = 0)
  int projected_nodes = 0;       // nodes that crossed the ground during the step and were projected back
  int contact_rounds = 0;        // linear solves (1 + re-solves after contact releases or additions)
  int contact_updates = 0;       // kCholmodPcg: changed contact nodes absorbed by the preconditioner
  int degenerate_rotations = 0;  // elements that kept their previous rotation
  // Wall time of the step's phases, milliseconds: R_e, element forces and R_e K_e R_e^T (warping); scatter
  // into K_w, system matrix, right-hand side and contact-filtered matrices (assembly); linear solves (solve).
  double warping_ms = 0.0, assembly_ms = 0.0, solve_ms = 0.0;
};

class WarpedDynamics {
 public:
  /// Starts at rest (x = X, v = 0). Throws std::invalid_argument for a non-positive or non-finite time step,
  /// negative damping, a zero ground normal or non-positive CG settings, std::runtime_error for kCholmod in a
  /// build without CHOLMOD.
  WarpedDynamics(LinearElasticModel model, const WarpedDynamicsOptions& options = WarpedDynamicsOptions());

  const LinearElasticModel& model() const { return model_; }
  const WarpedDynamicsOptions& options() const { return options_; }
  int numNodes() const { return model_.mesh().numNodes(); }
  int numDofs() const { return model_.numDofs(); }

  /// 3 N vectors, node i at 3 i. Setters throw std::invalid_argument for a wrong size or non-finite values.
  const Eigen::VectorXd& restPositions() const { return rest_; }
  const Eigen::VectorXd& positions() const { return positions_; }
  const Eigen::VectorXd& velocities() const { return velocities_; }
  /// The lumped masses (9.21) per degree of freedom (node i's mass at 3 i, 3 i + 1 and 3 i + 2).
  const Eigen::VectorXd& lumpedMasses() const { return masses3_; }
  void setPositions(const Eigen::VectorXd& positions);
  void setVelocities(const Eigen::VectorXd& velocities);
  /// Nodal forces applied in addition to gravity (m_i g).
  void setExternalForces(const Eigen::VectorXd& forces);

  /// Held degrees of freedom: dof_mask has 3 N entries (non-zero: held; empty: none held). Held dofs reach
  /// their targets at the end of every following step (v+ = (target - x) / dt); the targets start as the
  /// current positions (the dofs hold still). Throws std::invalid_argument for a wrong size.
  void setHeld(std::vector<char> dof_mask);
  /// Positions the held dofs reach at the end of the next step (3 N; free dofs' entries are ignored).
  /// Throws std::invalid_argument for a wrong size or non-finite values.
  void setHeldTargets(const Eigen::VectorXd& targets);
  const std::vector<char>& heldDofs() const { return held_dofs_; }
  int numHeldDofs() const { return num_held_dofs_; }
  /// The force the holder exerted on each held dof during the last step ((A dv - b) / dt), zero elsewhere.
  const Eigen::VectorXd& heldReactions() const { return held_reactions_; }

  /// One linearised backward Euler step (header equations) followed by ground contact.
  StepStatistics step();

  /// Recomputes R_e, f_int and K_w from the current positions (step() does this first).
  void updateWarping();
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotations_; }
  /// Starting rotations (e.g. carried over from the body this one was cut from): the warm start of the next
  /// registrations and the rotation kept by degenerate elements. Throws std::invalid_argument for a wrong
  /// count or a non-finite matrix.
  void setRotations(const std::vector<Eigen::Matrix3d>& rotations);
  /// The previous step's dv, the CG warm start (cg_warm_start). Throws std::invalid_argument for a wrong size
  /// or non-finite values.
  const Eigen::VectorXd& previousVelocityIncrement() const { return previous_dv_; }
  void setPreviousVelocityIncrement(const Eigen::VectorXd& dv);

  /// kCholmod / kCholmodPcg: the CHOLMOD solver (null for the other solvers).
  const CholmodSolver* cholmodSolver() const { return cholmod_.get(); }
  const Eigen::VectorXd& elasticForces() const { return elastic_forces_; }
  const Eigen::SparseMatrix<double>& warpedStiffness() const { return warped_stiffness_; }

  /// Energies and momenta of the current state; the elastic energy 1/2 sum_e u_e^T K_e u_e uses rotations
  /// registered to the current positions. Gravity potential -sum_i m_i g . x_i.
  double kineticEnergy() const;
  double elasticEnergy() const;
  double gravityPotentialEnergy() const;
  double totalEnergy() const { return kineticEnergy() + elasticEnergy() + gravityPotentialEnergy(); }
  Vec3 linearMomentum() const;
  Vec3 angularMomentum(const Vec3& origin = Vec3::Zero()) const;
  Vec3 centerOfMass() const;
  /// Volume enclosed by the deformed boundary triangles.
  double currentVolume() const;

 private:
  struct ElementFrame {
    Eigen::Matrix3d rotation;
    Vec3 rest_centroid, current_centroid;
    bool degenerate;
  };
  ElementFrame elementFrame(int e, const Eigen::VectorXd& positions, const Eigen::Matrix3d& previous) const;
  void gatherElement(int e, const Eigen::VectorXd& global, Eigen::VectorXd& local) const;
  Eigen::VectorXd elementDisplacement(int e, const ElementFrame& frame) const;  // u_e
  void applyGroundContact(StepStatistics& stats);
  // Eliminates the held dofs from system_matrix_ and rhs (header); returns z_h, zero at free dofs.
  Eigen::VectorXd eliminateHeldDofs(Eigen::VectorXd& rhs, Eigen::VectorXd& guess);
  // held_reactions_ from the full step's dv and the unfiltered right-hand side.
  void computeHeldReactions(const Eigen::VectorXd& dv, const Eigen::VectorXd& rhs);
  // Friction coefficient c of the node's tangential impulse -c (I - n n^T) v+ this step, for the normal
  // ground impulse J (Coulomb bound mu J).
  double groundFrictionCoefficient(int node, double normal_impulse) const;
  // Adds c (I - n n^T) to the node's diagonal block of system_matrix_ and -c (I - n n^T) v_i to rhs.
  void addGroundFriction(int node, double coefficient, Eigen::VectorXd& rhs);
  Eigen::VectorXd contact_impulses_;  // per node: normal ground impulse of the last step (0: not held)
  Eigen::VectorXd solveSystem(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b,
                              const Eigen::VectorXd& guess, const std::vector<char>& active,
                              StepStatistics& stats);
  void buildConstrainedMatrix(const std::vector<char>& active);
  void factorizeCholmod(const Eigen::SparseMatrix<double>& a, StepStatistics& stats);
  // kCholmodPcg: remembers the matrix and contact set of the factorisation just made.
  void recordFactoredContact(const std::vector<char>& active);
  // Prepares the preconditioner for the contact set `active`: false when more nodes changed than
  // pcg_contact_updates or the correction is not positive definite (then refactorise).
  bool prepareContactCorrection(const std::vector<char>& active, StepStatistics& stats);
  // x = B^-1 b, B: the factorised matrix with the released nodes' normal dofs coupled again.
  void applyReleasedInverse(const Eigen::MatrixXd& b, Eigen::MatrixXd& x);
  // z = M^-1 r, M: the factorised matrix filtered to the current contact set.
  void applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z);
  // CG on a x = b from x, preconditioned by cholmod_'s factor; false when not converged in max_iterations
  // (plus up to max_extension when the residual's mean reduction rate predicts convergence within them).
  bool factorPreconditionedCg(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b,
                              Eigen::VectorXd& x, int max_iterations, int max_extension,
                              StepStatistics& stats);

  LinearElasticModel model_;
  WarpedDynamicsOptions options_;
  Eigen::VectorXd rest_, positions_, velocities_, user_forces_, gravity_forces_, masses3_;
  std::vector<Eigen::VectorXd> rotation_weights_;  // per element, per local node
  std::vector<Eigen::Matrix3d> rotations_;
  int degenerate_rotations_ = 0;
  Eigen::VectorXd elastic_forces_;
  Eigen::VectorXd element_forces_;  // f_e of every element, element e at element_force_offset_[e]
  std::vector<int> element_force_offset_;
  Eigen::VectorXd rotated_blocks_;  // R_e K_e R_e^T of every element as 3 x 3 blocks, scratch
  std::vector<int> rotated_block_offset_;
  int max_element_nodes_ = 0;
  std::vector<int> diagonal_index_;  // dof -> value index of the diagonal entry
  Eigen::SparseMatrix<double> warped_stiffness_, system_matrix_, constrained_matrix_;
  Eigen::VectorXd previous_dv_;
  std::vector<char> held_dofs_, held_nodes_;  // per dof / per node (any component held); empty: none
  int num_held_dofs_ = 0;
  Eigen::VectorXd held_targets_, held_reactions_;
  bool held_changed_ = false;  // the factorised system (kCholmod*) filtered a different held set
  // Lower: the symmetric product is serial; Eigen's OpenMP SpMV (Lower | Upper) spin-waits badly on small
  // systems when cores are shared.
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::DiagonalPreconditioner<double>>
      jacobi_cg_;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>
      ichol_cg_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool ldlt_analyzed_ = false;
  double last_warping_ms_ = 0.0, last_scatter_ms_ = 0.0;  // of the latest updateWarping()
  std::unique_ptr<CholmodSolver> cholmod_;  // kCholmod only; re-analyses when the pattern changes
  // kCholmodPcg: the factor is of F = filter(A_f, C_f), A_f the unfiltered system matrix then (kept for the
  // couplings), C_f its contact set. For the current set C: released nodes (C_f \ C, normals p_i = e_i (x) n,
  // columns of Q) and added nodes (C \ C_f, columns of E). With Z = P A_f Q (P removes the normals of C_f),
  // W = F^-1 Z, S = Q^T A_f Q - Z^T W: B^-1 (filter(A_f, C_f \ C)) by block elimination; with V = B^-1 E,
  // H = E^T V and t = B^-1 (I - E E^T) r the preconditioner M^-1 r = t - V H^-1 E^T t + E E^T r is the exact
  // inverse of filter(A_f, C): only A_f -> A (rotations) is left to CG.
  Eigen::SparseMatrix<double> factored_system_;
  std::vector<char> factored_active_;
  std::vector<int> released_nodes_, added_nodes_;
  Eigen::SparseMatrix<double> released_coupling_;             // Z
  Eigen::MatrixXd released_solves_, added_solves_;            // W, V
  Eigen::LLT<Eigen::MatrixXd> released_schur_, added_schur_;  // S, H
};

}  // namespace rc
