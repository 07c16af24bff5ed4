// Elastic solids without stored connectivity (thesis 8.2): every solid particle fits the lattice of its
// closest sphere packing to its current neighbours (shape matching, 8.21-8.25) and derives elastic forces
// from the implicit rest state, either through a strain estimate and linear elasticity (8.26-8.28) or
// through goal positions (8.29-8.31), with the linear and angular momentum correction (8.32-8.33).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sph/sph_force_term.h"
#include "sph/sph_kernels.h"
#include "sph/sph_lattice.h"
#include "sph/sph_particles.h"
#include "sph/sph_sorted_grid.h"

namespace rc {

enum class SphElasticModel {
  /// strain (8.26)-(8.28) -> corotated linear elastic stress; forces are the gradient of the neighbourhood
  /// energy through the strain fit, plus hourglass control of the modes the fit cannot see
  kStrain,
  kGoalPosition,  ///< direct forces towards volume-preserving goal positions (8.29)-(8.31)
};

struct SphElasticConfig {
  SphElasticModel model = SphElasticModel::kGoalPosition;
  double lattice_spacing = 0.05;  ///< d of (8.20); the solid's particles are sampled on this lattice
  // kStrain
  double youngs_modulus = 1.0e5;  ///< Y (Pa), > 0
  double poisson_ratio = 0.3;     ///< nu, in [0, 0.5)
  /// gamma: stiffness of the hourglass control of the strain model relative to Y (non-affine modes that
  /// the strain fit (8.28) cannot see), >= 0. Without it a 10% stretched block gains energy and blows up.
  double hourglass_control = 0.5;
  // kGoalPosition
  /// K_e of (8.31), per unit mass (1/s^2): F_ij = K_e m_i V W_ij (g'_ij - r_ij) with V W_ij the
  /// SPH-normalised weight (sum_j V W_ij < 1). The oscillation frequency is about sqrt(K_e); with this
  /// reading the K_e and time steps of thesis appendix F.2 sit at the stability limit of Verlet.
  double goal_stiffness = 1.0e4;
  double deformation_allowance = 0.5;  ///< s of (8.30), in [0, 1]
  /// Minimum assigned neighbours of a neighbourhood for shape matching (fewer: no forces from it).
  int min_neighbors = 4;

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
};

/// Diagnostics of the last force evaluation.
struct SphElasticStats {
  size_t solid_particles = 0;
  size_t matched_neighborhoods = 0;  ///< neighbourhoods that produced a lattice fit and forces
  size_t skipped_neighborhoods = 0;  ///< too few assigned neighbours or a degenerate fit
  size_t assigned_pairs = 0;         ///< (i, j) pairs with a lattice point
  size_t unassigned_pairs = 0;       ///< neighbours that lost their lattice point to a closer particle (8.21)
  double max_strain = 0.0;           ///< max over particles of the largest |eigenvalue| of the strain
  double energy = 0.0;               ///< elastic energy estimate
  Vec3 net_force = Vec3::Zero();     ///< sum of the elastic forces
  Vec3 net_torque = Vec3::Zero();    ///< sum of x cross elastic force
};

/// Result of the lattice assignment of one neighbourhood (8.21).
struct SphLatticeAssignment {
  std::vector<Eigen::Vector3i> indices;  ///< lattice index per neighbour
  std::vector<uint8_t> assigned;         ///< 0: lost its lattice point to a closer neighbour (or the centre)
};

/// (8.21) for the neighbours at `offsets` (x_j - x_i) of a particle with lattice transform `transform`
/// (A_i^(t-1)): each neighbour takes the lattice point nearest to A^-1 r_ij; a lattice point keeps only its
/// closest neighbour (distance to A^-1 r_ij; ties go to the lower offset index), the others stay
/// unassigned and receive no forces from this neighbourhood. The origin belongs to the centre particle.
void assignLatticePoints(const SphLattice& lattice, const Eigen::Matrix3d& transform,
                         const std::vector<Vec3>& offsets, SphLatticeAssignment& out);

/// Polar/singular decomposition A = U diag(sigma) V^T with det(U V^T) = +1 (reflection-safe: a negative
/// determinant flips the smallest singular value, so R = U V^T is a rotation (8.24)). In 2D only the x-y
/// block is decomposed (U, V rotations about z, sigma.z = 1).
void rotationSvd(const Eigen::Matrix3d& a, int dimension, Eigen::Matrix3d& u, Vec3& sigma,
                 Eigen::Matrix3d& v);

/// One elastic object: all particles with phases[i] == phase (and kind kFluid) in one solver. It stores
/// only the per-particle lattice transform A_i of the previous evaluation (the lattice itself is implicit,
/// (8.20)); neighbours are found anew at every evaluation. Add it to a SphFluidSolver with addForceTerm().
/// Results are identical for any thread count.
class SphElasticSolid : public SphForceTerm {
 public:
  /// `kernels`: those of the solver (h = neighbourhood radius, poly6 weights W_ij, spiky gradient for
  /// stresses). `lattice_orientation`: the rotation the particles were sampled with (frame of
  /// sampleLattice); it initialises A_i. Throws std::invalid_argument for a bad config, phase 0 (fluid),
  /// or an orientation that is not a rotation.
  SphElasticSolid(const SphElasticConfig& config, const SphKernels& kernels, uint8_t phase,
                  const Eigen::Matrix3d& lattice_orientation = Eigen::Matrix3d::Identity());

  const SphElasticConfig& config() const { return config_; }
  const SphLattice& lattice() const { return lattice_; }
  uint8_t phase() const { return phase_; }
  /// Volume per particle (lattice cell volume), V in the force models.
  double particleVolume() const { return lattice_.cellVolume(); }

  /// Appends solid particles at `positions` (kind kFluid, phase phase()) with `mass` and `velocity`;
  /// returns the index of the first. Throws std::invalid_argument for a mass not finite and > 0.
  size_t addParticles(SphParticles& particles, const std::vector<Vec3>& positions, double mass,
                      const Vec3& velocity = Vec3::Zero()) const;

  // SphForceTerm
  void addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                 std::vector<Vec3>& forces) override;
  /// Elastic limit cfl * 2 / omega_max (Verlet needs omega dt < 2). kGoalPosition: omega_max^2 <=
  /// 2 K_e sum_j V W_ij < 2 K_e. kStrain: omega_max^2 <= 4 V ((lambda + 2 mu) (sum_j a_j)^2 +
  /// gamma Y sum_j W_j / tr D) / m on a full lattice neighbourhood, a_j = W_j |D^-1 l_j| (of the order of
  /// the P-wave speed over the spacing).
  double stableTimeStep(const SphParticles& particles, double cfl) const override;
  double potentialEnergy() const override { return stats_.energy; }

  /// Forces of this term alone at the current state (zeroed first); updates A_i like addForces.
  void computeForces(const SphParticles& particles, std::vector<Vec3>& forces);

  const SphElasticStats& stats() const { return stats_; }
  /// Per particle (all particles of the system; identity / zero for others), from the last evaluation:
  /// the lattice transform A_i (8.23), its rotation R_i (8.24) and the strain (8.26).
  const std::vector<Eigen::Matrix3d>& latticeTransforms() const { return transform_; }
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotation_; }
  const std::vector<Eigen::Matrix3d>& strains() const { return strain_; }
  /// Per particle: number of neighbourhoods in which it lost its lattice point at the last evaluation.
  const std::vector<uint32_t>& unassignedCounts() const { return unassigned_count_; }
  /// Sets the lattice transform A_i that particle i's next lattice assignment (8.21) starts from, e.g. that
  /// of a neighbour when a fluid particle freezes into this solid (8.2.4). Throws std::out_of_range unless
  /// i < latticeTransforms().size(), std::invalid_argument for a non-finite or singular transform.
  void setLatticeTransform(size_t i, const Eigen::Matrix3d& transform);

 private:
  struct Contribution {
    uint32_t particle;
    Vec3 force;
  };
  struct Scratch {
    std::vector<Vec3> offsets;
    std::vector<uint32_t> neighbors;
    std::vector<double> weights;
    SphLatticeAssignment assignment;
  };
  void prepare(const SphParticles& particles);
  /// Shape matching and forces of the neighbourhood of solid particle s (sorted order).
  void processNeighborhood(size_t s, Scratch& scratch);

  SphElasticConfig config_;
  SphKernels kernels_;
  SphLattice lattice_;
  uint8_t phase_;
  Eigen::Matrix3d orientation_;
  double lame_lambda_ = 0.0, lame_mu_ = 0.0;
  double strain_omega2_mass_ = 0.0;  // m omega_max^2 bound of the strain model
  SphElasticStats stats_;

  std::vector<Eigen::Matrix3d> transform_, rotation_, strain_;
  std::vector<uint8_t> has_transform_;
  std::vector<uint32_t> unassigned_count_;
  // Per evaluation (sorted solid order).
  std::vector<uint32_t> solid_;  // original index of each solid particle
  std::vector<Vec3> s_pos_;
  std::vector<double> s_mass_;
  SphSortedGrid grid_;
  std::vector<std::vector<Contribution>> contributions_;  // per sorted solid particle
  std::vector<std::vector<uint32_t>> lost_;               // neighbours left without a lattice point
  std::vector<double> energy_, max_strain_;
  std::vector<uint32_t> assigned_, unassigned_;
  std::vector<uint8_t> matched_;
};

}  // namespace rc
