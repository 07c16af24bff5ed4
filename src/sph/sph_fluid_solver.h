// Weakly compressible SPH fluid solver (thesis 8.1.4): density (8.4), pressure (8.15)-(8.16), symmetric
// pressure force (8.17), Laplacian viscosity (8.18), XSPH (8.19), velocity Verlet, adaptive time step.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/sph_force_term.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"
#include "relaxed_connectivity/sph/sph_sorted_grid.h"

namespace rc {

/// Kernel whose gradient drives the pressure force (8.17); measurements in docs/sph_choices.md.
///  kPoly6 (default): the density kernel (8.4), so the pressure force is the exact negative gradient of the
///         compression energy (kinetic + potential + compression energy conserved up to the integration).
///  kSpiky: the thesis' choice (appendix C); not the gradient of any energy, it pumps energy into the fluid.
enum class SphPressureKernel { kSpiky, kPoly6 };

/// Pressure of boundary particles, which enter the pair force (8.17) like fluid particles; measurements in
/// docs/sph_choices.md.
///  kSummation (default): density by summation (8.4), pressure by (8.15), clamped to >= 0 (walls never pull);
///                 the derivative of the walls' compression energy, so walls neither add nor remove energy.
///  kExtrapolated: Adami, Hu & Adams 2012 (J. Comput. Phys. 231, eq. 27): the Shepard average of the
///                 neighbouring fluid pressures plus the hydrostatic head, clamped to >= 0; more accurate at
///                 rest, but the walls do work on the fluid.
enum class SphBoundaryPressure { kSummation, kExtrapolated };

/// How fluid particles get their density. kSummation: rho_i = sum_j m_j W_ij (8.4), recomputed from the
/// positions every step (particles at a free surface miss neighbours and read low). kContinuity: integrated
/// from the continuity equation, drho_i/dt = sum_j m_j (v_i - v_j) . grad W_ij (Monaghan 1992, eq. 3.8) with
/// the pressure kernel's gradient, starting from the particle's density (rest_density where it is 0, e.g. new
/// particles): a free surface starts and stays at rho_0, and a rigid motion leaves every density unchanged.
/// Boundary particles keep summation densities.
enum class SphDensityMethod { kSummation, kContinuity };

struct SphFluidConfig {
  int dimension = 3;                      ///< 2 (x-y plane, z = 0) or 3
  double smoothing_length = 0.1;          ///< h, kernel support radius
  double rest_density = 1000.0;           ///< rho_0 (8.15)
  double stiffness = 2.0e5;               ///< K (8.15), pressure units
  double gamma = 1.0;                     ///< Gamma (8.15), >= 1
  double negative_pressure_scale = 0.01;  ///< zeta (8.16), in [0, 1]
  /// Tensile-instability correction (Monaghan 2000, J. Comput. Phys. 159, eq. 4.4): a pair of particles under
  /// negative pressure is pushed apart by (R_i + R_j) f^4 with R_i = epsilon |p_i| / rho_i^2 and
  /// f = W(r) / W(tensile_spacing) (poly6), a short-range repulsion that keeps particles under tension from
  /// pairing up (clumping) while the fluid pulls. epsilon: 0 = off (no cost), 0.2 is Monaghan's value.
  double tensile_correction = 0.0;
  double tensile_spacing = 0.0;  ///< the initial particle spacing Delta p, in (0, h); needed when on
  SphPressureKernel pressure_kernel = SphPressureKernel::kPoly6;            ///< poly6: conservative
  SphBoundaryPressure boundary_pressure = SphBoundaryPressure::kSummation;  ///< summation: conservative
  SphDensityMethod density = SphDensityMethod::kSummation;                  ///< of fluid particles
  /// kContinuity: every this many steps the fluid densities are re-initialised by a Shepard filter,
  /// rho_i = sum_j m_j W_ij / sum_j (m_j / rho_j) W_ij (Colagrossi & Landrini 2003): it removes the drift of
  /// the integrated densities (the rate's discretisation error where particles are not isotropically spread)
  /// and keeps free surfaces at their density. 0: never.
  int density_reinit_interval = 0;
  double viscosity = 0.0;                ///< mu (8.18), shear viscosity, >= 0
  double xsph = 0.1;                     ///< xi (8.19), in [0, 1]
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);  ///< z must be 0 in 2D
  double cfl = 0.4;                      ///< factor on the time step limits, in (0, 1]
  double fixed_dt = 0.0;                 ///< > 0: always this step; 0: adaptive
  double max_dt = 0.01;                  ///< upper bound of the adaptive step
  /// A step is unstable if the kinetic energy exceeds this factor times (kinetic + compression energy before
  /// the step + gravity work of the step + moving-boundary energy).
  double instability_energy_growth = 10.0;
  /// The same over a window of steps: unstable if the kinetic energy exceeds instability_window_growth times
  /// (the energy at the window's start + the gravity work and moving-boundary energy since), which catches
  /// growth too slow for the one-step check (a tensile or time-step instability building up over a few
  /// steps). The window restarts every instability_window steps and when the fluid's mass changes (sources).
  /// Fluids only: with force terms (elastic solids, which a caller may drive) only the one-step check runs.
  /// 0: off.
  int instability_window = 10;
  double instability_window_growth = 3.0;
  /// Unstable if a liquid particle (phase 0) is compressed by more than this fraction of rho_0
  /// ((rho - rho_0) / rho_0; weakly compressible SPH aims at about 0.01): particles clumping (tensile
  /// instability, too few neighbours) or a stiffness far too low. 0: off.
  double max_compression = 0.5;
  bool throw_on_instability = true;  ///< throw SphInstabilityError (else only StepStats::unstable)
  int num_threads = 0;               ///< OpenMP threads, 0 = all available

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
  /// Speed of sound at rest, sqrt(K Gamma / rho_0).
  double soundSpeed() const;
};

/// A half-space boundary: particles are kept where normal . x >= offset (normal is normalised).
struct SphPlane {
  Vec3 normal = Vec3(0.0, 1.0, 0.0);  ///< points into the allowed side
  double offset = 0.0;
  double restitution = 0.0;  ///< normal velocity after a hit = -restitution * before, in [0, 1]
  double friction = 0.0;     ///< tangential velocity scaled by (1 - friction) on a hit, in [0, 1]
};

enum class SphStepLimit { kFixed, kMaxDt, kSpeed, kSoundSpeed, kViscosity, kForce, kElastic };
const char* toString(SphStepLimit limit);

struct SphStepStats {
  uint64_t step = 0;  ///< 1-based number of this step
  double time = 0.0;  ///< simulated time after the step
  double dt = 0.0;
  SphStepLimit limit = SphStepLimit::kMaxDt;  ///< the criterion that chose dt (kFixed for fixed_dt)
  // The limits at the start of the step (all already scaled by cfl; infinity where not applicable).
  double dt_speed = 0.0;           ///< cfl h / max speed
  double dt_sound = 0.0;           ///< cfl h / c, c the sound speed at the largest fluid density
  double dt_viscosity = 0.0;       ///< cfl h^2 rho_0 / (mu (15 | 40/3)), 3D | 2D: 2 / max eigenvalue
  double dt_force = 0.0;           ///< cfl sqrt(h / max |a|)
  double dt_elastic = 0.0;         ///< min over the force terms (elastic wave speed, 8.2)
  double max_speed = 0.0;          ///< fluid particles, after the step
  double max_density_error = 0.0;  ///< max |rho - rho_0| / rho_0 over fluid particles
  double max_compression = 0.0;    ///< max (rho - rho_0) / rho_0 over liquid (phase 0) particles, >= 0
  double kinetic_energy = 0.0;     ///< fluid particles
  /// sum m e(rho) of the equation of state over the fluid particles, plus over the boundary particles with
  /// SphBoundaryPressure::kSummation (their e(rho) = 0 below rho_0, matching the clamped wall pressure).
  /// Kinetic + compression - sum_fluid m g . x is the energy the conservative defaults do not increase.
  double compression_energy = 0.0;
  double term_energy = 0.0;             ///< potential energy of the force terms (elastic, 8.2)
  double neighbors_per_particle = 0.0;  ///< mean, all particles, self excluded
  double seconds = 0.0;                 ///< wall time of the step
  bool unstable = false;
  std::string instability;  ///< message when unstable
};

/// Thrown by SphFluidSolver::step when the step is unstable (non-finite state or runaway kinetic energy).
class SphInstabilityError : public std::runtime_error {
 public:
  SphInstabilityError(uint64_t step, const std::string& message) : std::runtime_error(message), step_(step) {}
  uint64_t step() const { return step_; }

 private:
  uint64_t step_;
};

/// Explicit SPH solver. Pressure forces use the poly6 (or spiky) gradient, density and XSPH the poly6 kernel,
/// viscosity the viscosity Laplacian (see SphKernels). Boundary particles get densities and (non-negative)
/// pressures and push fluid particles with the same symmetric pair force, but are not integrated. All
/// particle sums run in a serial, stable cell order, so results are bitwise identical for any thread count.
///
/// Integration (velocity Verlet, kick-drift-kick): v' = v + dt/2 a(x); x += dt (v' + xsph); a' = a(x, v'');
/// v = v' + dt/2 a', where viscosity and XSPH use the predicted velocity v'' = v' + dt/2 a. Continuity
/// densities (SphDensityMethod::kContinuity) are staggered like the positions: rho += dt D(x, v') after the
/// drift, before a' (a symplectic-Euler update, stable up to the same step as summation; the trapezoidal rule
/// over D before and after the step was not: +21 % energy in 0.2 s of a free 2D blob at the adaptive step).
class SphFluidSolver {
 public:
  /// Validates config and particles (throws std::invalid_argument).
  SphFluidSolver(const SphFluidConfig& config, SphParticles particles);

  const SphFluidConfig& config() const { return config_; }
  const SphKernels& kernels() const { return kernels_; }
  /// Particle state. After editing it (adding particles, moving them), call particlesChanged().
  SphParticles& particles() { return particles_; }
  const SphParticles& particles() const { return particles_; }
  void particlesChanged() { forces_valid_ = false; }

  void addPlane(const SphPlane& plane);
  const std::vector<SphPlane>& planes() const { return planes_; }

  /// Adds a force term (e.g. an SphElasticSolid, 8.2) evaluated with every force computation (after
  /// SphForceTerm::beginStep with the step's dt); its stableTimeStep enters the adaptive step as
  /// SphStepLimit::kElastic. Throws for a null term.
  void addForceTerm(std::shared_ptr<SphForceTerm> term);
  const std::vector<std::shared_ptr<SphForceTerm>>& forceTerms() const { return force_terms_; }

  /// One time step. Throws SphInstabilityError if it is unstable and config().throw_on_instability.
  const SphStepStats& step();
  /// One step of advance(end_time - time()): shortened to end on end_time if it would pass it (the time is
  /// then set to end_time). Throws std::invalid_argument unless end_time > time().
  const SphStepStats& stepUntil(double end_time);
  /// Steps until `duration` more time has passed (the last step is shortened to end on it). `after_step`,
  /// if set, is called after every step (after the last one's time is set to the end), e.g. for
  /// SphThermalModel::step with lastStats().dt.
  const SphStepStats& advance(double duration,
                              const std::function<void(const SphStepStats&)>& after_step = {});

  double time() const { return time_; }
  uint64_t stepCount() const { return step_count_; }
  const SphStepStats& lastStats() const { return stats_; }

  /// Recomputes densities, pressures and forces at the current positions and velocities (done by step()
  /// when needed). The force terms are told the fixed step, else the last step (nothing before the first).
  void computeForces();

  /// SphDensityMethod::kContinuity: the density rate drho/dt of every particle at the last force computation
  /// (0 for boundary particles); empty with summation densities.
  const std::vector<double>& densityRates() const { return density_rates_; }

  /// Whether the neighbour rows of the last force computation are those of the current particles: forces
  /// are valid and every position is bit for bit the one they were found at (after step() they are).
  bool neighborsCurrent() const;
  /// The cell grid of the last force computation: grid().order()[s] is the particle at sorted position s.
  const SphSortedGrid& neighborGrid() const { return grid_; }
  /// Neighbours (d < h, self excluded) of the particle at sorted position s as sorted positions, in the
  /// grid's stable cell order (ascending); `count` receives their number. Valid while neighborsCurrent().
  const uint32_t* neighborRow(size_t s, uint32_t& count) const;

 private:
  void validateParticles() const;
  void computeForces(const std::vector<Vec3>& velocities);
  void densityPass(int t);
  /// The continuity equation's density rate of the particle at sorted position s over its neighbour row.
  double continuityRate(size_t s, const uint32_t* row, size_t count, bool poly6_gradient) const;
  void boundaryPressurePass(int t);
  void forcePass(int t);
  /// forcePass for one pressure kernel, with or without viscosity (without it no distance is needed) and the
  /// tensile correction.
  template <bool kPoly6Pressure, bool kViscosity, bool kTensile>
  void forcePassOf(int t);
  /// forcePassOf with flags[k] as its k-th template argument.
  template <bool... kFlags>
  void forcePassWith(int t, const bool* flags);
  void addTermForces(const std::vector<Vec3>& velocities);
  /// SphForceTerm::beginStep(dt) of every force term.
  void announceStep(double dt);
  double pressureOf(double density) const;
  double compressionEnergyOf(double density) const;
  void chooseTimeStep(double requested_dt);
  void collideWithPlanes(size_t i);
  const SphStepStats& advanceOneStep(double requested_dt);
  /// Energies, max speed and density error into stats_; false if the state is not finite.
  bool measureState();
  /// The Shepard re-initialisation of the fluid densities (SphFluidConfig::density_reinit_interval) on the
  /// neighbour rows of the last force computation (those of the current positions).
  void reinitializeDensities();
  std::string likelyCause() const;

  SphFluidConfig config_;
  SphKernels kernels_;
  SphParticles particles_;
  std::vector<SphPlane> planes_;
  std::vector<std::shared_ptr<SphForceTerm>> force_terms_;
  std::vector<Vec3> term_forces_;
  SphStepStats stats_;
  double time_ = 0.0;
  uint64_t step_count_ = 0;
  bool forces_valid_ = false;
  double forces_dt_ = 0.0;  // the dt announced to the force terms for the current forces
  int num_threads_ = 1;
  double fluid_mass_ = 0.0, max_boundary_speed2_ = 0.0;
  // The energy window (SphFluidConfig::instability_window): its first step, energy and fluid mass, and the
  // energy that may enter the fluid since (gravity work, moving boundaries).
  uint64_t window_start_ = 0;
  double window_energy_ = 0.0, window_mass_ = -1.0, window_inflow_ = 0.0;

  // Original order.
  std::vector<Vec3> accelerations_, xsph_, predicted_;
  // Sorted (cell) order.
  SphSortedGrid grid_;
  std::vector<Vec3> s_pos_, s_vel_, s_acc_, s_xsph_;
  std::vector<double> s_mass_, s_rho_, s_press_, s_press_term_;
  std::vector<double> s_tension_;  // R_i of the tensile correction (0 unless p_i < 0)
  // SphDensityMethod::kContinuity: the densities at the start of the step and the velocities of the rate (the
  // particles', in the step the half-step ones) of the density pass, its rates D (sorted), D in original
  // order, and the step the density pass advances the densities by (0 outside a step).
  std::vector<double> s_rho_given_, s_rho_rate_, density_rates_;
  std::vector<Vec3> s_vel_rate_;
  double continuity_dt_ = 0.0;
  std::vector<SphParticleKind> s_kind_;
  std::vector<uint32_t> row_begin_, row_count_;  // neighbour rows in the owning thread's buffer
  std::vector<std::vector<uint32_t>> thread_lists_;
  std::vector<std::vector<double>> thread_sq_dists_;  // per thread: squared distances of a row (scratch)
  /// Per thread: the candidates of the current cell's 27-cell block as structure of arrays (scratch).
  struct CellCandidates {
    std::vector<double> x, y, z;
    std::vector<uint32_t> index;
  };
  std::vector<CellCandidates> thread_candidates_;
  std::vector<size_t> thread_first_;
};

}  // namespace rc
