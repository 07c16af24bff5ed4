// A running SPH scene (thesis 8): the solver with its force terms (makeSphSolver) and the per-step physics
// beyond it, the thermal model (heat conduction, melting and freezing, 8.2.4) and the fluid sources, stepped
// after every solver step. The object that runSphScene (rc_sph), the sph_sim node and the tests step, so all
// advance a scene the same way.
#pragma once

#include <memory>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_fluid_source.h"
#include "relaxed_connectivity/sph/sph_scene.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace rc {

class SphSimulation {
 public:
  /// The scene's own solver (makeSphSolver) and thermal model (makeSphThermal); `scene` outlives the
  /// simulation. Call emit(solver().time()) before the first step for the sources' first layers (runSphScene
  /// does).
  explicit SphSimulation(const SphScene& scene);
  /// Steps `solver`, made by makeSphSolver(scene) (possibly with changed threads) and outliving the
  /// simulation; `thermal`: the scene's model (made by makeSphThermal when null and the scene enables
  /// temperature).
  SphSimulation(const SphScene& scene, SphFluidSolver& solver,
                std::shared_ptr<SphThermalModel> thermal = nullptr);
  SphSimulation(const SphSimulation&) = delete;
  SphSimulation& operator=(const SphSimulation&) = delete;

  const SphScene& scene() const { return scene_; }
  SphFluidSolver& solver() { return solver_; }
  const SphFluidSolver& solver() const { return solver_; }

  /// Whether anything runs after a solver step (temperature or sources); false: afterStep does nothing.
  bool active() const { return thermal_ != nullptr || !sources_.empty(); }
  /// Appends the source layers due at `time` (before the first step: the solver's start time); calls
  /// SphFluidSolver::particlesChanged() when particles were added, which grows every per-particle array.
  void emit(double time);
  /// After a solver step of `st.dt` ending at `st.time`: the thermal model (8.2.4, 8.34-8.36), then the
  /// sources (new particles get their source's temperature).
  void afterStep(const SphStepStats& st);
  /// One solver step followed by afterStep (an unstable step throws or is reported as the solver is set).
  const SphStepStats& step();

  const std::shared_ptr<SphThermalModel>& thermal() const { return thermal_; }
  const std::vector<SphFluidSource>& sources() const { return sources_; }
  uint64_t melted() const { return melted_; }  ///< solid particles melted (8.35) by afterStep so far
  uint64_t frozen() const { return frozen_; }  ///< fluid particles frozen (8.36) by afterStep so far
  /// Sum over emitted particles of m t (t: their emission time) and of m v at emission (the momentum the
  /// sources added).
  double emittedMassTime() const { return emitted_mass_time_; }
  const Vec3& emittedMomentum() const { return emitted_momentum_; }
  /// Sum over afterStep calls of the particle count before emission (the mean count per step with sources).
  double particleSteps() const { return particle_steps_; }

 private:
  /// own_solver (owned) or given_solver (borrowed): exactly one is set.
  SphSimulation(const SphScene& scene, std::unique_ptr<SphFluidSolver> own_solver,
                SphFluidSolver* given_solver, std::shared_ptr<SphThermalModel> thermal);

  const SphScene& scene_;                       // outlives the simulation
  std::unique_ptr<SphFluidSolver> own_solver_;  // null when stepping a given solver
  SphFluidSolver& solver_;
  std::shared_ptr<SphThermalModel> thermal_;
  std::vector<SphFluidSource> sources_;
  uint64_t melted_ = 0, frozen_ = 0;
  double emitted_mass_time_ = 0.0, particle_steps_ = 0.0;
  Vec3 emitted_momentum_ = Vec3::Zero();
};

}  // namespace rc
