// Penalty collision handling between distinct objects (thesis 8.2.6): forces between particles of different
// objects are restricted to their repulsive part (8.37).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "relaxed_connectivity/sph/sph_force_term.h"
#include "relaxed_connectivity/sph/sph_implicit_goal_solver.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"
#include "relaxed_connectivity/sph/sph_sorted_grid.h"

namespace rc {

class SphElasticSolid;

struct SphObjectPenaltyConfig {
  /// K_c (1/s^2, per unit mass like K_e of (8.31)): stiffness of the goal-position force that pushes a
  /// particle of another object back to `contact_distance`, finite and > 0.
  double stiffness = 1.0e4;
  /// d: particles of different objects closer than d interact (the lattice spacing of the solids: the
  /// rest distance of lattice neighbours), finite, > 0 and <= the kernel support h.
  double contact_distance = 0.05;
  /// c (1/s): relative-velocity part of the interaction force, finite and >= 0. With c > 0 the projection
  /// and clamp of (8.37) make contacts inelastic without ever pulling objects together.
  double damping = 0.0;
  /// Locally implicit contact springs (as SphElasticConfig::implicit_goal): with k_i = sum over i's contacts
  /// of V W(r) K_c m / m_i (the stiffness per unit mass of particle i) plus the stiffness of i's body
  /// (setObjectStiffness) and dt the announced step (beginStep), the stiffness part of each pair becomes
  /// m V W(r) K_c ((d - r) - dt n . (v_j - v_i)) / (1 + dt^2 max(k_i, k_j)) (backward Euler on the pair with
  /// the contact direction held fixed), still clamped by (8.37). Antisymmetric and central: momentum is
  /// exact. Unconditionally stable (between stiff bodies only with their stiffness in k_i: two dice at 30x
  /// their explicit step gain 17x kinetic energy without it, test_sph_implicit_goal), so the step limit
  /// becomes the contact CFL cfl d / (2 max speed) (no pair closes more than cfl d / 1 per step) and the
  /// explicit damping limit; the approach of colliding objects is dissipated (at most the stiffness part).
  /// Off (default): explicit (8.37), stable below the K_c limit of stableTimeStep().
  /// Between solids with global implicit goal springs coupled by SphObjectPenalty::coupleGlobalImplicit
  /// (makeSphSolver couples them when `couple_global_implicit`), the contact springs instead join the
  /// solids' backward Euler solve (SphImplicitGoalCoupling): solids in contact are solved as one system
  /// with the pair springs linearised at the current positions, stiffness -dN/dr, so a contact is as stiff
  /// as (8.37) at any step (the local springs above are softened by 1 + dt^2 K_e).
  bool implicit = false;
  /// With `implicit`: makeSphSolver couples the contacts between solids with global implicit goal springs
  /// into their solve (coupleGlobalImplicit). Off: the locally implicit springs above between them too.
  bool couple_global_implicit = true;

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
};

/// Diagnostics of the last force evaluation.
struct SphObjectPenaltyStats {
  size_t objects = 0;        ///< distinct object ids (phases 1..255) among the integrated particles
  size_t contact_pairs = 0;  ///< pairs of different objects closer than the contact distance
  /// contact pairs whose force passed the test of (8.37) (coupled solids: contact springs that pushed at the
  /// end of the step)
  size_t repulsive_pairs = 0;
  double min_distance = 0.0;      ///< smallest distance between particles of different objects (< d), else d
  double energy = 0.0;            ///< potential energy of the stiffness part
  Vec3 net_force = Vec3::Zero();  ///< of the forces added by this term itself (not the coupled contacts)
};

/// Object ids are the particle phases: every integrated (kFluid) particle with phase p != 0 belongs to
/// object p (an SphElasticSolid). Fluid particles (phase 0) and boundary particles never take part. For
/// particles i, j of different objects closer than d, with r = |x_j - x_i| and n = (x_j - x_i) / r, the
/// interaction force on j is the goal-position force (8.31) towards the goal d n (the lattice rest
/// distance) plus relative-velocity damping, with the pair's mean mass m = (m_i + m_j) / 2, the kernel
/// weight W(r) and the lattice cell volume V of spacing d:
///   F_ij = m V W(r) (K_c (d - r) n - c (v_j - v_i)),
/// and (8.37) keeps only its component along n where that pushes j away from i:
///   F'_ij = (n . F_ij) n if n . F_ij > 0, else 0;   j gets F'_ij, i gets -F'_ij.
/// The forces are central and exactly antisymmetric, so linear and angular momentum are conserved. Without
/// damping the force is the negative gradient of sum_pairs m V K_c int_r^d W(s) (d - s) ds (the reported
/// potential energy). Nothing is computed while fewer than two objects exist. Results are identical for any
/// thread count. Add it to a SphFluidSolver with addForceTerm().
///
/// The solver's own pair forces (pressure (8.17), viscosity (8.18)) still act between objects; the thesis
/// restricts those to (8.37) as well, which needs a phase test in the solver's force pass.
class SphObjectPenalty : public SphForceTerm {
 public:
  /// `kernels`: those of the solver (W = poly6). Throws std::invalid_argument for a bad config or a
  /// contact distance beyond the kernel support.
  SphObjectPenalty(const SphObjectPenaltyConfig& config, const SphKernels& kernels);

  const SphObjectPenaltyConfig& config() const { return config_; }
  /// V: the lattice cell volume (2D: area) of spacing d.
  double particleVolume() const { return volume_; }

  /// Pair potential m V K_c int_r^d W(s) (d - s) ds for unit mean mass (0 for r >= d).
  double pairPotential(double distance) const;

  // SphForceTerm
  void addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                 std::vector<Vec3>& forces) override;
  /// cfl * 2 / omega_max with omega_max = sqrt(2 z K_c V kappa q) + 2 z c V W(0) q: z contacts per particle
  /// (the kissing number, 6 in 2D, 12 in 3D), kappa = max over r < d of W(r) + |W'(r)| (d - r) (the pair
  /// stiffness), q = (1 + m_max / m_min) / 2 over the object particles. With `implicit` the K_c part drops
  /// out and the contact CFL cfl d / (2 max speed of the object particles) enters instead. Infinity with
  /// fewer than two objects.
  double stableTimeStep(const SphParticles& particles, double cfl) const override;
  double potentialEnergy() const override { return stats_.energy; }
  /// The dt of the implicit contact springs of the next evaluations (0 until the first call: explicit).
  /// Throws std::invalid_argument for dt not finite and >= 0.
  void beginStep(double dt) override;
  bool implicitInStep() const override { return config_.implicit; }

  /// Implicit contact springs: the stiffness per unit mass (1/s^2) that holds the particles of object
  /// `phase` to their body, e.g. K_e of its implicit goal springs (8.31) (0 by default). It enters k_i, so a
  /// contact moves a particle against its body only by its share K_c / (K_c + K_e) of the overlap rather
  /// than by all of it in one step (which strains a stiff body by the whole overlap and feeds energy in).
  /// Throws std::invalid_argument for a stiffness not finite and >= 0.
  void setObjectStiffness(uint8_t phase, double stiffness);

  /// Forces of this term alone at the current positions and velocities (zeroed first).
  void computeForces(const SphParticles& particles, std::vector<Vec3>& forces);

  const SphObjectPenaltyStats& stats() const { return stats_; }

  /// With `implicit`: the contacts between `solid` and the other coupled solids (all with global implicit
  /// goal springs) join their backward Euler solve (see SphImplicitGoalCoupling): the solid hands its system
  /// to this term instead of solving it, and this term solves all of them with the contact springs and adds
  /// the solids' forces, so it must be added to the solver after them. Pairs with an uncoupled object keep
  /// the locally implicit springs. Throws std::invalid_argument unless `implicit` and the solid has global
  /// implicit goal springs (goal-position model).
  void coupleGlobalImplicit(SphElasticSolid& solid);
  size_t coupledSolids() const { return coupled_solids_; }
  /// Of the last evaluation with coupled solids: groups solved, contact springs that pushed, CG iterations.
  const SphImplicitCouplingStats& couplingStats() const { return coupling_stats_; }

 private:
  /// Number of distinct object ids among the integrated particles.
  static size_t countObjects(const SphParticles& particles);
  /// Force on sorted particle s from all contacts (sum of -F'_sj), its pair energies (halved) and statistics.
  void gatherForces(size_t s);
  /// k_s of the implicit springs: sum over the contacts of sorted particle s of V W(r) K_c m / m_s.
  void gatherStiffness(size_t s);

  SphObjectPenaltyConfig config_;
  SphKernels kernels_;
  double volume_ = 0.0;
  double pair_stiffness_bound_ = 0.0;  // kappa
  SphObjectPenaltyStats stats_;

  // Per evaluation (sorted order of the object particles).
  SphSortedGrid grid_;
  std::vector<uint32_t> members_;  // original index of each sorted object particle
  std::vector<Vec3> s_pos_, s_vel_;
  std::vector<double> s_mass_;
  std::vector<uint8_t> s_phase_;
  std::vector<Vec3> s_force_;
  std::vector<double> s_energy_, s_min_dist_, s_stiffness_;
  double step_dt_ = 0.0;
  std::array<double, 256> object_stiffness_{};  // per phase, see setObjectStiffness
  std::vector<uint32_t> s_contacts_, s_repulsive_;
  // Coupled global implicit solve: per sorted particle whether it is in a pending block and the contact
  // springs to later sorted particles of other blocks; all of them in sorted order.
  std::shared_ptr<SphImplicitGoalCoupling> coupling_;
  size_t coupled_solids_ = 0;
  SphImplicitCouplingStats coupling_stats_;
  std::vector<uint8_t> s_coupled_;
  std::vector<std::vector<SphContactSpring>> s_springs_;
  std::vector<SphContactSpring> springs_;
};

}  // namespace rc
