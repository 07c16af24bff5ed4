// Temperature and phase transitions of the SPH solver (thesis 8.2.4): heat conduction in SPH form (the
// thesis cites [145]; Cleary & Monaghan 1999, J. Comput. Phys. 148), heat sources and sinks, and melting
// (8.35) and freezing (8.36) as Poisson processes (8.34).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"
#include "relaxed_connectivity/sph/sph_sorted_grid.h"

namespace rc {

class SphFluidSolver;

/// A heated (or cooled) floor: particles with signed distance normal . x - offset <= distance are driven
/// towards `temperature` (Newton's law, dT/dt = transfer_rate (temperature - T), integrated exactly) and
/// receive `heat_flux` (power per unit mass, W/kg, may be negative).
struct SphHeatedPlane {
  Vec3 normal = Vec3(0.0, 1.0, 0.0);  ///< normalised on use; points into the domain
  double offset = 0.0;
  double distance = 0.1;       ///< > 0
  double temperature = 0.0;    ///< target of the Newton transfer
  double transfer_rate = 0.0;  ///< 1/s, >= 0
  double heat_flux = 0.0;      ///< W/kg
};

struct SphThermalConfig {
  double conductivity = 1.0;           ///< k (W/(m K)), >= 0
  double heat_capacity = 1.0;          ///< c (J/(kg K)), > 0; heat of particle i is m_i c T_i
  double rest_density = 1000.0;        ///< used where a particle's density is not > 0 (or always, below)
  bool use_particle_densities = true;  ///< volumes m/rho from SphParticles::densities (the solver's)
  double initial_temperature = 0.0;    ///< temperature of particles the model has not seen yet
  double ambient_temperature = 0.0;
  double ambient_rate = 0.0;  ///< 1/s, Newton exchange of every particle with the ambient, >= 0
  /// Diffusion substeps are at most this fraction of the monotone limit 1 / max_i D_i, in (0, 1].
  double stability_factor = 1.0;
  int max_substeps = 100000;  ///< more than this in one step(): std::runtime_error
  int num_threads = 0;        ///< OpenMP threads, 0 = all available

  // Melting (8.35): lambda_m = max(0, lambda_m^0 (T - T_m)).
  bool melting = false;
  double melting_rate = 1.0;  ///< lambda_m^0 (1/(s K)), >= 0
  double melting_temperature = 0.0;
  uint8_t melting_phase = 0;  ///< solid id that can melt; 0: every solid

  // Freezing (8.36): lambda_f = lambda_f^0 max(0, T_f - T) max(0, n_s - n_min) min(1, c_v) min(1, c_F).
  bool freezing = false;
  double freezing_rate = 1.0;  ///< lambda_f^0 (1/(s K)), >= 0
  double freezing_temperature = 0.0;
  uint8_t freezing_phase = 1;  ///< solid id a freezing particle joins, >= 1
  /// n_min; n_s counts the neighbours (within h) of phase freezing_phase, of any kind. Negative values let
  /// isolated particles freeze spontaneously.
  double min_solid_neighbors = 0.0;
  /// v_max of c_v = v_max / |v_i - mean velocity of the solid neighbours| (infinity: c_v = 1).
  double max_relative_speed = std::numeric_limits<double>::infinity();
  /// F_max of c_F = F_max / |sum_j F_ij| (infinity: c_F = 1); needs setFreezingSolid.
  double max_lattice_force = std::numeric_limits<double>::infinity();

  uint64_t seed = 1;  ///< of the counter-based random numbers of (8.34)

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
};

/// Diagnostics of the last step().
struct SphThermalStats {
  uint64_t step = 0;
  double dt = 0.0;
  /// Monotone (and hence stable) explicit limit of the diffusion: 1 / max_i D_i with D_i = sum_j g_ij /
  /// (m_i c); the update is then a convex combination (maximum principle). About rho c h^2 / k times a
  /// kernel constant (0.074 on a full 2D square lattice with h = 2.5 d, test HeatDiffusion...). infinity if
  /// there are no pairs. step() substeps to stay below it.
  double stable_dt = 0.0;
  int substeps = 0;
  size_t participants = 0;  ///< particles that conduct heat
  size_t pairs = 0;         ///< directed neighbour pairs
  double total_heat = 0.0;  ///< sum m_i c T_i over the non-held participants, after the step
  double min_temperature = 0.0, max_temperature = 0.0;
  size_t melted = 0, frozen = 0;  ///< phase changes of this step
};

/// Temperature per particle (indexed like SphParticles), explicit SPH heat conduction and stochastic
/// melting and freezing. Heat conducts between kFluid-kind particles (fluid and solid phases) and held
/// particles; other boundary particles are insulating. Conduction (Cleary & Monaghan, their eq. 19):
///   m_i c dT_i/dt = sum_j g_ij (T_j - T_i),  g_ij = 2 k V_i V_j (-w'(r) / r),
/// V = m / rho, w the poly6 kernel (-w'(r)/r = 6 a/h^2 (1 - r^2/h^2)^2 is finite at r = 0, so the
/// regularisation r^2 + eta^2 of Cleary & Monaghan is not needed). This is the Brookshaw Laplacian, exact for
/// quadratic fields with full kernel support. Pair fluxes are exactly antisymmetric, so heat is conserved up
/// to rounding. All sums run in a serial, stable cell order and random numbers are a hash of (seed, step,
/// particle index), so results are bitwise identical for any thread count. Costs nothing unless step() is
/// called.
class SphThermalModel {
 public:
  /// Validates config (throws std::invalid_argument).
  explicit SphThermalModel(const SphThermalConfig& config);

  const SphThermalConfig& config() const { return config_; }

  /// Temperatures, one per particle; grown with initial_temperature when particles appear.
  std::vector<double>& temperatures() { return temperatures_; }
  const std::vector<double>& temperatures() const { return temperatures_; }
  /// Sets all temperatures of particles [first, first + count) (grows the vector if needed).
  void setTemperature(size_t first, size_t count, double temperature);

  /// Holds the particles at `temperature`: they exchange heat with their neighbours (a cooled rod, a
  /// heater) but their own temperature only changes when written through temperatures(). Held particles
  /// never change phase.
  void holdTemperature(const std::vector<size_t>& indices, double temperature);
  void release(const std::vector<size_t>& indices);
  bool isHeld(size_t i) const { return i < held_.size() && held_[i]; }

  /// Adds a heat source / sink plane. Throws std::invalid_argument for a bad plane.
  void addHeatedPlane(const SphHeatedPlane& plane);

  /// Optional: the elastic solid that freezing particles join (its phase must be freezing_phase). Freezing
  /// particles adopt the lattice transform A_j of their nearest solid neighbour, and c_F uses its lattice.
  void setFreezingSolid(std::shared_ptr<SphElasticSolid> solid);

  /// Advances temperatures by dt and applies melting and freezing. The solver's forces stay valid: the
  /// next step's first half-kick uses those of the last evaluation, its force evaluation the new phases. Call
  /// after each solver step with that step's dt: the neighbour rows of the step are then reused
  /// (SphFluidSolver::neighborsCurrent), else searched anew.
  const SphThermalStats& step(SphFluidSolver& solver, double dt);
  /// The same on bare particles (densities as set there); returns whether a phase changed.
  bool step(SphParticles& particles, const SphKernels& kernels, double dt);

  const SphThermalStats& lastStats() const { return stats_; }
  uint64_t stepCount() const { return step_count_; }
  /// Total heat sum m_i c T_i over the kFluid-kind particles that are not held.
  double totalHeat(const SphParticles& particles) const;

  /// Rates of (8.35) / the temperature factor of (8.36) for a temperature.
  double meltingRate(double temperature) const;
  /// (8.36) for given neighbourhood measures (c_v, c_F as defined above; infinity for "no limit").
  double freezingRate(double temperature, double solid_neighbors, double c_v, double c_f) const;
  /// The uniform number in [0, 1) that decides particle i's transition at model step `step` (8.34).
  static double uniformRandom(uint64_t seed, uint64_t step, uint64_t particle);

 private:
  bool advance(SphParticles& particles, const SphKernels& kernels, double dt, const SphFluidSolver* solver);
  /// Sorted slot s holds particle i: its index, position, heat capacity m c and volume m / rho.
  void setMember(size_t s, uint32_t i, const SphParticles& particles);
  void buildNeighbors(const SphParticles& particles, const SphKernels& kernels);
  /// The same rows from the solver's neighbour rows of the step (no grid or distance search of its own).
  void buildNeighborsFrom(const SphFluidSolver& solver);
  /// g_ij of the rows (row_start_ and nbr_ set); `threads` OpenMP threads.
  void fillCoefficients(const SphKernels& kernels, int threads);
  void diffuse(const SphParticles& particles, double dt);
  bool transitions(SphParticles& particles, const SphKernels& kernels, double dt);

  SphThermalConfig config_;
  int num_threads_ = 1;
  std::vector<double> temperatures_;
  std::vector<uint8_t> held_;
  std::vector<SphHeatedPlane> planes_;
  std::shared_ptr<SphElasticSolid> freezing_solid_;
  SphThermalStats stats_;
  uint64_t step_count_ = 0;

  // Participants in sorted (cell) order and their neighbour rows (CSR).
  SphSortedGrid grid_;
  std::vector<Vec3> points_;
  std::vector<uint32_t> members_, s_index_;
  std::vector<int32_t> thermal_of_;   // solver sorted position -> participant (or -1)
  std::vector<uint32_t> solver_pos_;  // participant -> solver sorted position
  std::vector<double> s_mc_, s_vol_, s_temp_, s_next_;
  std::vector<size_t> row_start_;
  std::vector<uint32_t> nbr_;
  std::vector<double> coeff_;
  std::vector<uint8_t> new_phase_;
};

}  // namespace rc
