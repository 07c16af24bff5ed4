#include "relaxed_connectivity/sph/sph_simulation.h"

#include "relaxed_connectivity/sph/sph_scene_setup.h"

namespace rc {

SphSimulation::SphSimulation(const SphScene& scene)
    : SphSimulation(scene, std::make_unique<SphFluidSolver>(makeSphSolver(scene)), nullptr, nullptr) {}

SphSimulation::SphSimulation(const SphScene& scene, SphFluidSolver& solver,
                             std::shared_ptr<SphThermalModel> thermal)
    : SphSimulation(scene, nullptr, &solver, std::move(thermal)) {}

SphSimulation::SphSimulation(const SphScene& scene, std::unique_ptr<SphFluidSolver> own_solver,
                             SphFluidSolver* given_solver, std::shared_ptr<SphThermalModel> thermal)
    : scene_(scene),
      own_solver_(std::move(own_solver)),
      solver_(given_solver ? *given_solver : *own_solver_),
      thermal_(thermal ? std::move(thermal) : makeSphThermal(scene, solver_)) {
  for (const SphFluidSourceConfig& config : scene.sources)
    sources_.emplace_back(config, solver_.kernels(), solver_.config().rest_density);
}

void SphSimulation::emit(double time) {
  bool added = false;
  SphParticles& p = solver_.particles();
  for (SphFluidSource& source : sources_) {
    const size_t first = p.size();
    const size_t count = source.emit(p, time);
    if (count == 0) continue;
    added = true;
    if (thermal_) thermal_->setTemperature(first, count, source.config().temperature);
    for (size_t i = first; i < p.size(); ++i) {
      emitted_mass_time_ += p.masses[i] * time;
      emitted_momentum_ += p.masses[i] * p.velocities[i];
    }
  }
  if (added) solver_.particlesChanged();
}

void SphSimulation::afterStep(const SphStepStats& st) {
  if (thermal_) {
    const SphThermalStats& ts = thermal_->step(solver_, st.dt);
    melted_ += ts.melted;
    frozen_ += ts.frozen;
  }
  if (!sources_.empty()) {
    particle_steps_ += double(solver_.particles().size());
    emit(st.time);
  }
}

const SphStepStats& SphSimulation::step() {
  const SphStepStats& st = solver_.step();
  if (!st.unstable) afterStep(st);
  return st;
}

}  // namespace rc
