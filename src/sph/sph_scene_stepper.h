// The per-step physics of a scene beyond the SPH solver: the thermal model (heat conduction, melting and
// freezing, thesis 8.2.4) and the fluid sources, stepped after every solver step. Shared by runSphScene (the
// rc_sph tool) and the sph_sim node, so both advance a scene the same way.
#pragma once

#include <memory>
#include <vector>

#include "sph/sph_fluid_solver.h"
#include "sph/sph_fluid_source.h"
#include "sph/sph_scene.h"
#include "sph/sph_thermal.h"

namespace rc {

class SphSceneStepper {
 public:
  /// `solver` made by makeSphSolver(scene) and outliving the stepper; `thermal`: the scene's model (made by
  /// makeSphThermal when null and the scene enables temperature).
  SphSceneStepper(const SphScene& scene, SphFluidSolver& solver,
                  std::shared_ptr<SphThermalModel> thermal = nullptr);

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
  SphFluidSolver& solver_;
  std::shared_ptr<SphThermalModel> thermal_;
  std::vector<SphFluidSource> sources_;
  uint64_t melted_ = 0, frozen_ = 0;
  double emitted_mass_time_ = 0.0, particle_steps_ = 0.0;
  Vec3 emitted_momentum_ = Vec3::Zero();
};

}  // namespace rc
