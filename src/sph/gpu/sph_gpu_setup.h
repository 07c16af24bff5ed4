// Conversion between the CPU solver's description (SphFluidConfig, SphPlane, SphElasticConfig, SphParticles)
// and the packed SphGpuSystem of the GPU path, with the checks of what the GPU path supports.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/sph/gpu/sph_gpu_system.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// One elastic solid of the GPU path: the particles of `phase` (kind kFluid), goal-position model.
struct SphGpuSolidSpec {
  uint8_t phase = 1;
  SphElasticConfig config;
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();  ///< lattice frame the particles were sampled in
};

/// Grid placement: the grid covers the particles' bounding box widened by `margin_h` smoothing lengths on
/// every side (particles outside fall into the border cells: correct, only slower).
struct SphGpuGridOptions {
  double margin_h = 4.0;
};

/// Packs a system for the GPU path (scalar R). The GPU path supports: dimension 3, a fixed time step
/// (config.fixed_dt > 0), SphBoundaryPressure::kSummation, both pressure kernels, planes, and solids of the
/// explicit goal-position model (no implicit_goal, docking, plasticity or anchors), phases 1..255.
/// Throws std::invalid_argument naming the unsupported or invalid input.
template <class R>
SphGpuSystem<R> makeSphGpuSystem(const SphFluidConfig& config, const std::vector<SphPlane>& planes,
                                 const std::vector<SphGpuSolidSpec>& solids, const SphParticles& particles,
                                 const SphGpuGridOptions& grid = {});

/// Writes positions, velocities, densities, pressures and forces (mass * acceleration, as
/// SphParticles::forces) of downloaded arrays into `particles` (same particles, same order). Throws
/// std::invalid_argument for a size mismatch.
template <class R>
void copySphGpuState(const SphGpuParticleArrays<R>& arrays, SphParticles& particles);

}  // namespace rc
