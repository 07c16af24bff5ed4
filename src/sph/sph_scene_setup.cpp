#include "relaxed_connectivity/sph/sph_scene_setup.h"

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_object_penalty.h"

namespace rc {

bool sphDockedPoints(const SphFluidSolver& solver, std::vector<uint32_t>& docked) {
  const SphParticles& p = solver.particles();
  bool any = false;
  docked.assign(p.size(), 0);
  for (const auto& term : solver.forceTerms()) {
    const auto* solid = dynamic_cast<const SphElasticSolid*>(term.get());
    if (!solid || !solid->config().docking) continue;
    any = true;
    const std::vector<uint32_t>& counts = solid->dockedCounts();
    for (size_t i = 0; i < p.size() && i < counts.size(); ++i)
      if (p.phases[i] == solid->phase()) docked[i] = counts[i];
  }
  return any;
}

SphFluidSolver makeSphSolver(const SphScene& scene) {
  SphFluidSolver solver(scene.config, scene.particles);
  for (const SphPlane& plane : scene.planes) solver.addPlane(plane);
  const SphKernels kernels(scene.config.dimension, scene.config.smoothing_length);
  std::vector<std::shared_ptr<SphElasticSolid>> terms;
  for (const SphSceneSolid& solid : scene.solids) {
    auto term = std::make_shared<SphElasticSolid>(solid.elastic, kernels, solid.phase, solid.orientation);
    term->setEnvironment(solver.planes(), solver.config().gravity);  // constraints of the global springs
    solver.addForceTerm(term);
    terms.push_back(term);
  }
  if (scene.collisions.enabled) {
    const SphObjectPenaltyConfig& contact = scene.collisions.config;
    auto penalty = std::make_shared<SphObjectPenalty>(contact, kernels);
    for (size_t k = 0; k < scene.solids.size(); ++k) {
      const SphElasticConfig& elastic = scene.solids[k].elastic;
      if (!elastic.implicit_goal || elastic.model != SphElasticModel::kGoalPosition) continue;
      // Bodies held by implicit goal springs: the local contact springs see their stiffness; those with
      // global springs solve their contacts with them (the penalty evaluates after the solids).
      penalty->setObjectStiffness(scene.solids[k].phase, elastic.goal_stiffness);
      if (contact.implicit && contact.couple_global_implicit && elastic.global_implicit_goal)
        penalty->coupleGlobalImplicit(*terms[k]);
    }
    solver.addForceTerm(penalty);
  }
  return solver;
}

std::shared_ptr<SphThermalModel> makeSphThermal(const SphScene& scene, SphFluidSolver& solver) {
  if (!scene.thermal.enabled) return nullptr;
  SphThermalConfig config = scene.thermal.config;
  config.num_threads = solver.config().num_threads;
  auto model = std::make_shared<SphThermalModel>(config);
  const size_t n = solver.particles().size();
  model->setTemperature(0, n, config.initial_temperature);
  for (const SphSceneTemperature& range : scene.thermal.initial)
    model->setTemperature(range.first, range.count, range.temperature);
  for (const SphHeatedPlane& plane : scene.thermal.planes) model->addHeatedPlane(plane);
  for (const SphSceneHeld& held : scene.thermal.held) {
    for (size_t i : held.indices) model->temperatures()[i] = held.temperature;
    model->holdTemperature(held.indices, held.temperature);
  }
  if (config.freezing)
    for (const auto& term : solver.forceTerms()) {
      auto solid = std::dynamic_pointer_cast<SphElasticSolid>(term);
      if (solid && solid->phase() == config.freezing_phase) model->setFreezingSolid(solid);
    }
  return model;
}

}  // namespace rc
