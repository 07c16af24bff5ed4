#include "relaxed_connectivity/fem/fem_static.h"

#include <chrono>
#include <stdexcept>
#include <utility>

#include "relaxed_connectivity/fem/fem_corotational_static.h"
#include "relaxed_connectivity/fem/fem_scene_regions.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {

FemStaticResult solveFemStatic(const FemScene& scene) {
  if (scene.analysis != FemAnalysis::kStatic)
    throw std::invalid_argument("solveFemStatic: the scene's analysis is not static");
  const auto start = std::chrono::steady_clock::now();
  const LinearElasticModel model(*scene.mesh, scene.youngs_modulus, scene.poisson_ratio, scene.density,
                                 scene.quadrature);
  const int n = model.mesh().numNodes();
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(model.numDofs());
  for (int i = 0; i < n; ++i) forces.segment<3>(3 * i) += model.lumpedMasses()[i] * scene.body_acceleration;
  const double tolerance = femBoxTolerance(model.mesh());
  for (const FemLoad& load : scene.loads)
    if (load.is_traction)
      forces += femTractionForces(model.mesh(), load, tolerance);
    else
      for (int i : load.nodes) forces.segment<3>(3 * i) += load.force / double(load.nodes.size());
  // One constraint per node: the union of the components its regions hold (the reader refuses a component
  // held twice).
  std::vector<int> slot(size_t(n), -1);
  std::vector<DisplacementConstraint> constraints;
  for (const FemHeldRegion& region : scene.held)
    for (int i : region.nodes) {
      if (slot[size_t(i)] < 0) {
        slot[size_t(i)] = int(constraints.size());
        constraints.push_back({i, Vec3::Zero(), {false, false, false}});
      }
      DisplacementConstraint& c = constraints[size_t(slot[size_t(i)])];
      for (int k = 0; k < 3; ++k)
        if (region.components[size_t(k)])
          c.held[size_t(k)] = true, c.displacement[k] = region.displacement[k];
    }
  FemStaticResult result;
  Eigen::VectorXd reactions;
  if (scene.static_options.corotational) {
    CorotationalStaticResult corotational =
        solveCorotationalStatic(model, forces, constraints, scene.static_options);
    result.displacements = std::move(corotational.displacements);
    reactions = std::move(corotational.reactions);
    result.iterations = corotational.iterations;
    result.residual = corotational.residual;
  } else {
    result.displacements = model.solveStatic(forces, constraints);
    reactions = model.reactions(result.displacements, forces);
  }
  for (int i = 0; i < n; ++i)
    result.max_displacement =
        std::max(result.max_displacement, result.displacements.segment<3>(3 * i).norm());
  for (const FemHeldRegion& region : scene.held) {
    Vec3 sum = Vec3::Zero();
    for (int i : region.nodes)
      for (int k = 0; k < 3; ++k)
        if (region.components[size_t(k)]) sum[k] += reactions[3 * i + k];
    result.held_reactions.push_back(sum);
  }
  for (const FemLoad& load : scene.loads) {
    Vec3 mean = Vec3::Zero();
    for (int i : load.nodes) mean += result.displacements.segment<3>(3 * i);
    result.load_displacements.push_back(mean / double(load.nodes.size()));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rc
