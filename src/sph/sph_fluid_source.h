// A fluid source (emitter) of the SPH solver: a disc (3D; a segment in 2D) that pours fluid particles in
// layers of lattice points, e.g. the slime poured onto the cooled rod of thesis Fig. 8.5.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

struct SphFluidSourceConfig {
  int dimension = 3;                ///< 2 (x-y plane) or 3
  Vec3 center = Vec3::Zero();       ///< c, the centre of the disc
  Vec3 direction = Vec3(0, -1, 0);  ///< n, normalised on use; non-zero (z = 0 in 2D)
  double radius = 0.1;              ///< r, >= spacing / 2 (else a layer is one particle too heavy)
  double speed = 1.0;               ///< v (m/s), > 0
  double spacing = 0.05;            ///< lattice spacing d of the layers, > 0
  double start_time = 0.0;          ///< >= 0
  double stop_time = std::numeric_limits<double>::infinity();  ///< > start_time (infinity: never stops)
  double temperature = 0.0;  ///< of the emitted particles (scenes with temperature)
  size_t max_particles = 0;  ///< cap on the emitted particles, 0: none

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
  /// Area of the opening: pi r^2 (3D), 2 r (2D).
  double area() const;
};

/// What a source has done so far.
struct SphFluidSourceStats {
  size_t emitted = 0;  ///< particles appended
  size_t layers = 0;   ///< layers emitted (a capped last layer counts)
  size_t skipped = 0;  ///< lattice points left out: a particle lay within spacing / 2 of them
  double emitted_mass = 0.0;
  bool capped = false;  ///< reached max_particles
};

/// Emits layers of fluid particles (kind kFluid, phase 0, velocity v n, the lattice mass of `spacing`,
/// latticeParticleMass) on the points latticeDisc(n, r, d) of the disc. Layer k leaves the disc at
/// t_k = start + k p / v, where the layer pitch p = N m / (rho_0 A) (N points per layer, A the area) makes
/// the mass rate exactly rho_0 A v on average (p is within the Gauss-circle error of d: 1.06 d for r = 2.5 d
/// in 3D), independent of the time step: emit(particles, t) appends every layer with t_k <= t (and t_k <=
/// stop) not emitted yet, each at its exact offset v (t - t_k) along n. A lattice point with any particle
/// (integrated or boundary) within d / 2 is skipped (SphFluidSourceStats::skipped). Deterministic.
class SphFluidSource {
 public:
  /// Validates config (throws std::invalid_argument); the particle mass is latticeParticleMass(kernels,
  /// rest_density, spacing). kernels.dimension must be config.dimension.
  SphFluidSource(const SphFluidSourceConfig& config, const SphKernels& kernels, double rest_density);

  const SphFluidSourceConfig& config() const { return config_; }
  double particleMass() const { return mass_; }
  /// Lattice points per layer (N).
  size_t layerSize() const { return disc_.size(); }
  /// Distance along n between consecutive layers, N m / (rho_0 A).
  double layerPitch() const { return pitch_; }
  /// rho_0 A v, the mean mass rate while the source runs.
  double massRate() const { return rest_density_ * config_.area() * config_.speed; }
  /// Mass emitted in [start, t] by the schedule (skipped points and the cap aside): the due layers times N m.
  double scheduledMass(double time) const;

  /// Appends the layers due by simulated time `time` to `particles`; returns the number of particles
  /// appended (they are the last ones). Throws std::invalid_argument for a non-finite time.
  size_t emit(SphParticles& particles, double time);

  const SphFluidSourceStats& stats() const { return stats_; }

 private:
  /// Layers with t_k <= min(time, stop), i.e. k p <= v (min(time, stop) - start), so k < this.
  size_t dueLayers(double time) const;

  SphFluidSourceConfig config_;
  Vec3 normal_ = Vec3::Zero();
  std::vector<Vec3> disc_;  // offsets in the disc's plane
  double mass_ = 0.0, rest_density_ = 0.0, pitch_ = 0.0;
  size_t next_layer_ = 0;
  SphFluidSourceStats stats_;
  std::vector<Vec3> nearby_;  // scratch: particles near the layer
};

}  // namespace rc
