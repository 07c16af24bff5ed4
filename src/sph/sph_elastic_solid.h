// Elastic solids without stored connectivity (thesis 8.2): every solid particle fits the lattice of its
// closest sphere packing to its current neighbours (shape matching, 8.21-8.25) and derives elastic forces
// from the implicit rest state, either through a strain estimate and linear elasticity (8.26-8.28) or
// through goal positions (8.29-8.31), with the linear and angular momentum correction (8.32-8.33).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_force_term.h"
#include "relaxed_connectivity/sph/sph_implicit_goal_solver.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_lattice_keys.h"
#include "relaxed_connectivity/sph/sph_particles.h"
#include "relaxed_connectivity/sph/sph_sorted_grid.h"

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
  /// Locally implicit goal springs: every neighbourhood's goal forces (8.31) are integrated as springs that
  /// are implicit in the relative motion of the neighbourhood, with the goal held fixed within the step
  /// (backward Euler on the particle's own stiffness, v += dt k (g - x - dt u) / (1 + dt^2 k)): with k =
  /// K_e sum_j V W_ij the neighbourhood's stiffness per unit mass, dt the announced step (beginStep) and u
  /// the velocity relative to the neighbourhood's weighted mean velocity, the forces are scaled by
  /// 1 / (1 + dt^2 k) and get the damping -dt k u / (1 + dt^2 k). Both are applied per neighbourhood before
  /// the momentum correction (8.32)-(8.33), so linear and angular momentum stay exact and rigid motions are
  /// not damped. Unconditionally stable: stableTimeStep() no longer limits the step (the CFL, sound speed
  /// and collision limits do). It dissipates the stiff oscillations at large dt^2 k (like backward Euler);
  /// Off (default): the explicit force of (8.31), stable for dt < 2 / sqrt(2 K_e). Not the default because
  /// even at the explicit limit the scaling and damping change the dynamics (softer, damped bounces: the
  /// Fig. 8.7 tests' bounce and recovery tolerances fail with it); the stiff dice of Fig. 8.8 select it.
  /// Needs an announced step (SphForceTerm::beginStep, as inside SphFluidSolver) or time_step > 0; with
  /// dt = 0 the force is explicit.
  bool implicit_goal = false;
  /// With implicit_goal: > 0 caps the step at this multiple of the explicit limit (an accuracy bound: the
  /// effective stiffness is about K_e / (1 + dt^2 k), k ~ K_e sum_j V W_ij); 0 (default): no elastic limit.
  double implicit_step_factor = 0.0;
  /// With implicit_goal (scene files: `implicit_goal: global`): instead of the local springs, backward Euler
  /// on the goal forces (8.31) of the whole solid, linearised with the goals held fixed in the step (the
  /// stiffness of the springs 0.5 K_e m_i V W_ij between each centre and its assigned neighbours, with the
  /// rigid motions of the whole solid projected out, see SphImplicitGoalSolver), solved by Jacobi-
  /// preconditioned CG over all of the solid's particles, warm-started from the previous velocity change.
  /// The force is M dv / dt; without plane contacts or anchors its net force and torque are removed, so
  /// (8.32)-(8.33) hold exactly; a rigid motion of the whole solid is not damped. Unlike the local springs
  /// the solid stays as stiff as K_e at any step (stiff oscillations are damped as by backward Euler). The
  /// velocity the springs resist is the coming step's without this term: the given (predicted) velocity
  /// less half a kick of this term's previous force, plus half a kick of gravity (setEnvironment). Planes
  /// given by setEnvironment enter as velocity constraints. Implicit contact penalties (8.37) between solids
  /// coupled through an SphImplicitGoalCoupling (makeSphSolver couples them) join one system with the
  /// solids they connect; other forces (pressure, uncoupled penalties) stay explicit: a static offset of
  /// about dt^2 / 2 times their acceleration. The neighbourhoods are those of the shape matching.
  bool global_implicit_goal = false;
  double implicit_tolerance = 1e-4;   ///< CG: relative residual (Jacobi norm), in (0, 1)
  int implicit_max_iterations = 200;  ///< CG iterations per evaluation, >= 1
  /// Minimum assigned neighbours of a neighbourhood for shape matching (fewer: no forces from it).
  int min_neighbors = 4;

  /// Boundary-kind particles (static or moving) of the solid's phase take part in the shape matching like
  /// the others (they receive no forces): the solid is anchored to them, e.g. fixed to a wall (Fig. 8.7 c).
  bool anchor_boundary_particles = false;

  // Fracture and healing (8.2.5), off unless `docking`. Every particle keeps, per lattice point q of its
  // neighbourhood, whether q is docked (the particle assigned to q (8.21) enters the shape matching and
  // the forces) and a docking rate lambda_d^q. A docked q stays docked while a particle is assigned to it,
  // unless the pair is stretched beyond fracture_strain: then it detaches with the Poisson rate
  // fracture_rate (8.34) and its docking rate drops to 0 (a crack). A free q is occupied when its assigned
  // particle lies within docking_distance of it, the pair is not stretched beyond fracture_strain (it would
  // tear at once), q is not at the rim of the kernel (rest weight >= 1e-3 W(0)) and q is a nearest
  // neighbour of the centre or of a docked point nearer to the centre (docking proceeds from the contact
  // outwards: without this, pieces that approach dock at outer lattice points first, across a gap of a
  // lattice spacing, and bounce off the weak outer bonds). An occupied q docks within a step with
  // probability 1 - exp(-integral of lambda_d^q over the step) (8.34). The rates are per unit time:
  // lambda_d^q grows at docking_rate_increase (1/s^2) while q is docked or occupied, up to
  // max_docking_rate, and shrinks at docking_rate_decrease (1/s^2) otherwise (never below 0), so the
  // docking process does not depend on the step: a free point occupied from rate 0 on docks within time t
  // with probability 1 - exp(-increase t^2 / 2) (mean sqrt(pi / (2 increase)) below the cap). At a
  // particle's first evaluation its occupied points start docked at max_docking_rate, the others free at 0.
  // dt is the evaluation's step (SphForceTerm::beginStep; fixed or adaptive), else time_step.
  bool docking = false;
  /// Pair stretch |r_ij| / |P_i l_ij| - 1 above which a docked pair may detach (>= 0; infinity: only
  /// particles that leave the neighbourhood detach, the inherent fracture of 8.2.5).
  double fracture_strain = std::numeric_limits<double>::infinity();
  double fracture_rate = std::numeric_limits<double>::infinity();  ///< 1/s, >= 0; infinity: at once
  double max_docking_rate = 1000.0;                                ///< 1/s, >= 0
  double docking_rate_increase = 1.0e5;                            ///< Delta lambda_d^+ (1/s^2), >= 0
  double docking_rate_decrease = 1.0e5;                            ///< Delta lambda_d^- (1/s^2), >= 0
  /// A free lattice point is occupied by its assigned particle within this distance (in units of d, in
  /// lattice coordinates A_i^-1 r_ij), in (0, 1].
  double docking_distance = 0.3;

  // Plasticity (8.2.5: "stored plastic strain"), off unless yield_strain is finite. Each particle stores a
  // plastic transform P_i of its rest lattice (rest points P_i l); the elastic part A_i P_i^-1 = U S V^T of
  // the fit (8.23) has the elastic strain e = |S - I|. Beyond yield_strain, P_i absorbs the excess at
  // plastic_flow_rate: S' = I + (1 - a)(S - I) with a = (1 - exp(-rate dt)) (e - yield) / e,
  // P_i <- V (S / S') V^T P_i normalised to det 1 (volume preserving), its singular values kept in
  // [1 / (1 + max_plastic_strain), 1 + max_plastic_strain].
  double yield_strain = std::numeric_limits<double>::infinity();  ///< >= 0
  double plastic_flow_rate = 10.0;                                ///< 1/s, >= 0 and finite
  double max_plastic_strain = 1.0;                                ///< > 0

  /// Simulated time of a force evaluation for which no step was announced (SphForceTerm::beginStep), e.g.
  /// computeForces() outside a solver: dt of (8.34) and of the plastic flow. Inside an SphFluidSolver every
  /// evaluation is announced with its step's dt (fixed or adaptive), which replaces this value. Must be > 0
  /// when docking or plasticity is on.
  double time_step = 0.0;
  uint64_t seed = 1;  ///< of the counter-based random numbers of the docking process

  bool plasticity() const { return std::isfinite(yield_strain); }

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
  // Docking (config.docking): lattice points docked after this evaluation, and the changes of this one.
  size_t docked_points = 0;
  size_t detached = 0;   ///< docked points whose pair was stretched beyond fracture_strain and let go
  size_t separated = 0;  ///< docked points whose particle left (no particle assigned any more)
  size_t redocked = 0;   ///< free points that docked (healing)
  /// Plasticity: max over particles of |log sigma_k(P_i)| (0 without plasticity).
  double max_plastic_strain = 0.0;
  /// Global implicit goal springs: CG iterations and final relative residual of the last evaluation.
  int implicit_iterations = 0;
  double implicit_residual = 0.0;
  double energy = 0.0;             ///< elastic energy estimate
  Vec3 net_force = Vec3::Zero();   ///< sum of the elastic forces
  Vec3 net_torque = Vec3::Zero();  ///< sum of x cross elastic force
  /// The neighbourhoods came from the solver's neighbour rows (setNeighborSource), not a search of their own.
  bool solver_neighbor_rows = false;
};

/// Result of the lattice assignment of one neighbourhood (8.21).
struct SphLatticeAssignment {
  std::vector<Eigen::Vector3i> indices;  ///< lattice index per neighbour
  std::vector<uint8_t> assigned;         ///< 0: lost its lattice point to a closer neighbour (or the centre)
  // Scratch of assignLatticePoints, kept between calls.
  static constexpr int kTableHalfWidth = kLatticeTableHalfWidth;  ///< lattice indices [-8, 8)^3
  std::vector<double> sq_dists;        ///< squared distance to the lattice point per neighbour
  std::vector<int32_t> keepers;        ///< hash table of the keepers (indices outside the table)
  std::vector<int32_t> table_keepers;  ///< keeper per lattice point of the table
  std::vector<uint32_t> table_stamps;  ///< call stamp per table entry (older: empty)
  uint32_t stamp = 0;
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

/// One elastic object: all particles with phases[i] == phase (and kind kFluid; boundary kinds too with
/// anchor_boundary_particles) in one solver. It stores the per-particle lattice transform A_i of the
/// previous evaluation (the lattice itself is implicit, (8.20)); neighbours are found anew at every
/// evaluation. Only when switched on, it also stores per particle the docking state of its lattice points
/// (fracture and healing, 8.2.5) and a plastic transform P_i. Add it to a SphFluidSolver with
/// addForceTerm(). Results are identical for any thread count (random draws are a hash of (seed,
/// evaluation, particle, lattice point)).
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
  /// 2 K_e sum_j V W_ij < 2 K_e; with implicit_goal (unconditionally stable) infinity, or
  /// implicit_step_factor times the explicit limit. kStrain: omega_max^2 <= 4 V ((lambda + 2 mu) (sum_j
  /// a_j)^2 + gamma Y sum_j W_j / tr D) / m on a full lattice neighbourhood, a_j = W_j |D^-1 l_j| (of the
  /// order of the P-wave speed over the spacing).
  double stableTimeStep(const SphParticles& particles, double cfl) const override;
  double potentialEnergy() const override { return stats_.energy; }
  /// The dt of the next evaluations' docking draws (8.34) and plastic flow (config().time_step until the
  /// first call). Throws std::invalid_argument for dt not finite and >= 0.
  void beginStep(double dt) override;
  /// True with implicit_goal for the goal-position model.
  bool implicitInStep() const override {
    return config_.implicit_goal && config_.model == SphElasticModel::kGoalPosition;
  }
  /// Global implicit goal springs: the solver's planes (SphFluidSolver::planes()) and gravity. The planes
  /// enter the implicit solve as velocity constraints of the particles they would stop in the step, and
  /// gravity the velocity the springs resist (without them a solid resting on a plane sinks in by about
  /// dt^2 times the plane's reaction acceleration). Without constraints neither changes the result.
  void setEnvironment(const std::vector<SphPlane>& planes, const Vec3& gravity) {
    planes_ = planes;
    gravity_ = gravity;
  }
  /// The neighbour rows of the solver whose force evaluation runs (SphFluidSolver sets it around its
  /// addForces calls and clears it after): with the same smoothing length as this term's kernels, the
  /// neighbourhoods are read from its rows (SphFluidSolver::neighborRow) instead of a search of their own.
  void setNeighborSource(const SphFluidSolver* solver) override { neighbor_source_ = solver; }
  /// The dt the next evaluation uses for docking and plasticity.
  double stepTime() const { return step_dt_; }

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

  /// Docking (config.docking; empty otherwise): per particle, its docked lattice points after the last
  /// evaluation. Particles with fewer than a full neighbourhood lie on a surface or a crack (Fig. 8.7 c).
  const std::vector<uint32_t>& dockedCounts() const { return docked_count_; }
  /// Sums of SphElasticStats::detached / redocked over all evaluations.
  uint64_t totalDetached() const { return total_detached_; }
  uint64_t totalRedocked() const { return total_redocked_; }
  /// Plasticity (config.plasticity(); empty otherwise): per particle the plastic transform P_i of its rest
  /// lattice (identity for particles that never yielded).
  const std::vector<Eigen::Matrix3d>& plasticTransforms() const { return plastic_; }
  /// Number of force evaluations so far (the step counter of the docking draws).
  uint64_t evaluations() const { return evaluations_; }
  /// The uniform number in [0, 1) that decides lattice point `key` of particle `particle` at evaluation
  /// `evaluation` (8.34).
  static double uniformRandom(uint64_t seed, uint64_t evaluation, uint64_t particle, uint64_t key);

 private:
  /// Per particle and lattice point: docking state and rate (8.2.5).
  struct DockPoint {
    uint32_t key;  // packed lattice index
    int16_t slot;  // in the keeper table of SphLatticeAssignment (-1: outside)
    uint8_t docked;
    double rate;  // lambda_d^q
  };
  static constexpr int kDockTableSize = 8 * SphLatticeAssignment::kTableHalfWidth *
                                        SphLatticeAssignment::kTableHalfWidth *
                                        SphLatticeAssignment::kTableHalfWidth;
  /// A particle's docking state by lattice table slot (stamped per neighbourhood, never cleared).
  struct DockTable {
    std::vector<uint32_t> stamps;
    std::vector<int32_t> entries;  // index into the particle's DockPoint list
    uint32_t stamp = 0;
    /// The entry of lattice point (slot, key) in `state`, -1 if it has none.
    int32_t find(const std::vector<DockPoint>& state, int32_t slot, uint32_t key) const {
      if (slot >= 0) return stamps[size_t(slot)] == stamp ? entries[size_t(slot)] : -1;
      return findOutside(state, key);
    }
    /// find() for a point outside the table (rare): the first entry of that key.
    static int32_t findOutside(const std::vector<DockPoint>& state, uint32_t key);
  };
  struct Scratch {
    std::vector<Vec3> offsets;
    std::vector<uint32_t> neighbors;
    std::vector<double> weights;
    std::vector<Vec3> rest;  // P_i l_ij (l_ij without plasticity), filled with docking only
    SphLatticeAssignment assignment;
    DockTable dock_table;
    std::vector<uint8_t> taken;  // per old DockPoint: occupied by a neighbour
    std::vector<DockPoint> next;
    // The assigned neighbours only, in neighbour order: offset r_ij, rest point, weight W_ij, sorted solid
    // index, velocity, and the force on them.
    std::vector<Vec3> a_offset, a_rest, a_velocity, a_force;
    std::vector<double> a_weight;
    std::vector<uint32_t> a_neighbor;
    // The thread's contributions that wait for the scatter, per owner thread (see scatter_).
    struct Contribution {
      uint32_t target;  // sorted solid index
      Vec3 force;
    };
    std::vector<std::vector<Contribution>> deferred;
    uint32_t thread = 0;
  };
  /// Weighted sums over the assigned neighbours of a neighbourhood (one pass).
  struct FitSums {
    Eigen::Matrix3d rl, ll;  // sum_j W_ij r_ij l_ij^T, sum_j W_ij l_ij l_ij^T (8.23)
    double w_sum = 0.0;      // W_ii + sum_j W_ij
    double w_neighbors = 0.0;
    Vec3 weighted_r, weighted_v;  // sum_j W_ij r_ij, sum_j W_ij v_j
    size_t count = 0;
  };
  /// The lattice fit of a neighbourhood: A_i (8.23), its rotation R_i (8.24), the goal transform of (8.29)-
  /// (8.30) (goal model) and (sum_j W_ij l_ij l_ij^T)^-1.
  struct ShapeFit {
    Eigen::Matrix3d a, rot, goal, ll_inverse;
  };
  void prepare(const SphParticles& particles, const std::vector<Vec3>& velocities);
  /// Shape matching and forces of the neighbourhood of solid particle s (sorted order).
  void processNeighborhood(size_t s, Scratch& scratch);
  /// The neighbours of solid particle s (offsets, sorted solid indices, weights W_ij) into the scratch.
  size_t gatherNeighbors(size_t s, Scratch& scratch) const;
  /// (8.23)-(8.24) and the strain (8.26) of particle i from the fit sums; updates A_i, R_i, the warm start
  /// and the strain; false for a degenerate fit (no forces).
  bool fitShape(size_t s, const FitSums& sums, ShapeFit& fit);
  /// Forces of the goal model (8.31) (explicit or locally implicit) on the assigned neighbours into
  /// scratch.a_force; returns the centre's force.
  Vec3 goalForces(size_t s, const FitSums& sums, const ShapeFit& fit, Scratch& scratch);
  /// Forces of the strain model (8.26)-(8.28) with hourglass control; returns the centre's force.
  Vec3 strainForces(size_t s, const FitSums& sums, const ShapeFit& fit, Scratch& scratch);
  /// Momentum correction (8.32)-(8.33) of the neighbourhood's forces, then their scatter (see addForces).
  void correctAndScatter(size_t s, const FitSums& sums, Vec3 centre_force, Scratch& scratch);
  /// Docking decisions of the neighbourhood of solid particle s (8.2.5): clears assignment.assigned of
  /// the neighbours whose lattice point is not docked.
  void updateDocking(size_t s, Scratch& scratch);
  /// A docking rate after a step dt of growth (1/s^2) capped at `cap`, and its integral over the step.
  struct RateStep {
    double rate, integral;
  };
  static RateStep growDockingRate(double rate, double growth, double cap, double dt);
  /// Whether lattice point `index` is a nearest neighbour of the centre or of a lattice point nearer to the
  /// centre that is docked in `state` (indexed by `table`): docking proceeds from the centre outwards.
  bool dockedInnerNeighbor(const std::vector<DockPoint>& state, const DockTable& table,
                           const Eigen::Vector3i& index) const;
  /// Free lattice points whose rest weight is below this fraction of W(0) do not dock.
  static constexpr double kMinDockingWeight = 1e-3;
  /// Plastic flow of particle i from the elastic fit A_i P_i^-1 = U diag(sigma) V^T.
  void updatePlasticity(uint32_t i, const Eigen::Matrix3d& v, const Vec3& sigma);
  bool globalImplicit() const {
    return config_.model == SphElasticModel::kGoalPosition && config_.implicit_goal &&
           config_.global_implicit_goal && step_dt_ > 0.0;
  }
  /// Global implicit goal springs: replaces the explicit forces f0 (gathered in s_force_) by M dv / dt of
  /// the backward Euler step and adds them to `forces`.
  void solveGlobalImplicit(const SphParticles& particles, const std::vector<Vec3>& velocities,
                           std::vector<Vec3>& forces, SphElasticStats& stats);
  /// Global implicit goal springs, after the solve: keeps the step's force and velocity change per particle
  /// (the next step's warm start and resisted velocity) and the solve's statistics in `stats`.
  void finishGlobalImplicit(const SphImplicitGoalResult& result, SphElasticStats& stats);

 public:
  /// Global implicit goal springs: hands the solid's system to `coupling` at every evaluation instead of
  /// solving it; the term that runs the coupling after the solids (SphObjectPenalty::coupleGlobalImplicit)
  /// solves them together with their contact springs and adds their forces. nullptr (default): solved alone.
  void setImplicitCoupling(std::shared_ptr<SphImplicitGoalCoupling> coupling) {
    implicit_coupling_ = std::move(coupling);
  }
  const std::shared_ptr<SphImplicitGoalCoupling>& implicitCoupling() const { return implicit_coupling_; }

 private:
  std::shared_ptr<SphImplicitGoalCoupling> implicit_coupling_;
  SphImplicitGoalCoupling own_coupling_;  // the solve of the solid alone
  std::vector<Vec3> implicit_force_;      // sorted order: the step's force of the global springs

  SphElasticConfig config_;
  SphKernels kernels_;
  SphLattice lattice_;
  uint8_t phase_;
  Eigen::Matrix3d orientation_;
  double lame_lambda_ = 0.0, lame_mu_ = 0.0;
  double strain_omega2_mass_ = 0.0;  // m omega_max^2 bound of the strain model
  SphElasticStats stats_;

  std::vector<Eigen::Matrix3d> transform_, rotation_, strain_;
  std::vector<Eigen::Quaterniond> quaternion_;  // rotation_ as a quaternion: warm start of (8.24)
  std::vector<uint8_t> has_transform_;
  std::vector<uint32_t> unassigned_count_;
  // Per evaluation (sorted solid order).
  std::vector<uint32_t> solid_;      // original index of each solid particle
  std::vector<uint32_t> members_;    // solid particles in original order (scratch of prepare)
  std::vector<Vec3> member_points_;  // their positions
  std::vector<Vec3> s_pos_, s_vel_;
  std::vector<double> s_mass_;
  SphSortedGrid grid_;
  std::vector<Scratch> scratch_;  // per thread, kept between evaluations
  // Scatter: thread t evaluates the neighbourhoods [m t / T, m (t + 1) / T) in order and owns the particles
  // of that range. A particle receives its forces in neighbourhood order: directly from its owner while it
  // evaluates, when no lower thread's neighbourhood contributes to it (its neighbours all lie at or above
  // the owner's range); the other contributions wait in the evaluating thread's Scratch::deferred (per owner,
  // in neighbourhood order) and the owner adds them after the evaluation, lower threads' first.
  std::vector<uint32_t> scatter_;  // per sorted solid particle: owner thread << 1 | direct
  Vec3* force_target_ = nullptr;   // forces (original order) of this evaluation
  // Neighbour rows of the solver (setNeighborSource): per sorted solid particle its row in the solver's
  // order, per solver row the sorted solid index (kNoSolid: not of this solid). Empty: own grid search.
  static constexpr uint32_t kNoSolid = 0xFFFFFFFFu;
  const SphFluidSolver* neighbor_source_ = nullptr;
  std::vector<uint32_t> solid_row_, row_to_solid_;
  std::vector<uint8_t> reset_done_;          // per particle: reset as a non-member and untouched since
  std::vector<std::vector<uint32_t>> lost_;  // neighbours left without a lattice point
  // Global implicit goal springs: per sorted solid particle its neighbourhood's springs; per particle
  // (original order) the last force of this term (from an evaluation with dt > 0) and velocity change.
  std::vector<std::vector<SphGoalSpring>> springs_;
  SphImplicitGoalSolver implicit_solver_;
  /// Per particle: the last global implicit evaluation's position, the velocity the springs resisted,
  /// this term's force and velocity change; known: whether there was one.
  struct ImplicitHistory {
    Vec3 x = Vec3::Zero(), velocity = Vec3::Zero(), force = Vec3::Zero(), dv = Vec3::Zero();
    bool known = false;
  };
  std::vector<SphPlane> planes_;
  Vec3 gravity_ = Vec3::Zero();
  std::vector<SphVelocityConstraint> constraints_;
  std::vector<Vec3> impulses_;
  std::vector<ImplicitHistory> history_;
  std::vector<Vec3> f0_, v_mid_, dv_, s_force_;  // sorted order
  std::vector<double> energy_, max_strain_;
  std::vector<Vec3> net_force_, net_torque_;  // per neighbourhood
  std::vector<uint32_t> assigned_, unassigned_;
  std::vector<uint8_t> matched_;
  // Docking and plasticity state (per particle, sized only when on).
  std::vector<std::vector<DockPoint>> dock_;
  std::vector<Eigen::Vector3i> nearest_steps_;  // lattice steps of length d (the nearest neighbours)
  std::vector<uint8_t> dock_initialized_;
  std::vector<uint32_t> docked_count_;
  std::vector<uint32_t> detached_, separated_, redocked_;
  std::vector<Eigen::Matrix3d> plastic_;
  std::vector<double> plastic_strain_;  // max |log sigma_k(P_i)|
  uint64_t evaluations_ = 0, total_detached_ = 0, total_redocked_ = 0;
  double step_dt_ = 0.0;  // dt of (8.34) and the plastic flow for the next evaluation
};

}  // namespace rc
