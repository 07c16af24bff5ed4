// Extra force terms of the SPH solver, e.g. the elastic forces of solid particles (thesis 8.2).
#pragma once

#include <omp.h>

#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

class SphFluidSolver;

/// A force term that SphFluidSolver adds to its integrated (kFluid kind) particles at every force
/// evaluation, after density, pressure and viscosity. Forces on boundary particles are ignored.
class SphForceTerm {
 public:
  virtual ~SphForceTerm() = default;
  /// Called by SphFluidSolver before each force evaluation with the time step it belongs to: the step just
  /// taken (the evaluation at its end), or for the evaluation before the first step (or after
  /// particlesChanged()) the fixed step, else the previous step (0 before any). For terms with rates per
  /// simulated time (Poisson processes, flow); the default ignores it.
  virtual void beginStep(double /*dt*/) {}
  /// True when the forces are integrated implicitly over the announced step (they depend on dt, e.g. the
  /// locally implicit springs of SphElasticConfig::implicit_goal): the solver then evaluates the forces the
  /// first step starts from again once the adaptive step is chosen, rather than with dt = 0 (explicit).
  virtual bool implicitInStep() const { return false; }
  /// The solver whose force evaluation runs, set around each addForces call and cleared (nullptr) after:
  /// terms that need neighbourhoods may read its rows (SphFluidSolver::neighborRow) instead of searching.
  virtual void setNeighborSource(const SphFluidSolver* /*solver*/) {}
  /// Adds the term's forces (mass * acceleration) at the particles' current positions and the given
  /// velocities to `forces` (original particle order, size particles.size()). May update internal state
  /// that persists between evaluations.
  virtual void addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                         std::vector<Vec3>& forces) = 0;
  /// Largest stable time step of the term, already scaled by `cfl` (infinity when the term does not limit).
  virtual double stableTimeStep(const SphParticles& particles, double cfl) const = 0;
  /// Potential energy stored by the term at the last evaluation (enters the solver's instability check).
  virtual double potentialEnergy() const = 0;

  /// Threads the term may use; SphFluidSolver::addForceTerm passes the solver's own count (0: all cores).
  void setThreadLimit(int threads) { thread_limit_ = threads; }
  int threadLimit() const { return thread_limit_ > 0 ? thread_limit_ : omp_get_max_threads(); }

 private:
  int thread_limit_ = 0;
};

}  // namespace rc
