// The packed input of the SPH GPU path (thesis 8.1, 8.2): parameters, planes, solids and particle arrays in
// original particle order, free of Eigen so that CUDA sources can include it. Built by makeSphGpuSystem
// (sph_gpu_setup.h) from the CPU solver's configuration.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/sph/gpu/sph_gpu_kernels.h"

namespace rc {

/// Particle arrays in original order: inputs (pos_mass, velocity, material, transform) and, after a
/// download, the outputs of the last force evaluation (density, pressure, acceleration, strain).
template <class R>
struct SphGpuParticleArrays {
  std::vector<SphGpuVec4<R>> pos_mass;  ///< x, y, z, mass
  std::vector<SphGpuVec4<R>> velocity;
  std::vector<uint32_t> material;           ///< kind | phase << 8
  std::vector<SphGpuMat3<R>> transform;     ///< A_i (8.23); the solid's orientation before the first fit
  std::vector<R> density, pressure;         ///< (8.4), (8.15)-(8.16)
  std::vector<SphGpuVec4<R>> acceleration;  ///< total: forces / mass + gravity (0 for boundaries)
  std::vector<R> strain;                    ///< max |sigma_k - 1| of the last fit (solids)

  size_t size() const { return pos_mass.size(); }
  /// Sizes the output arrays to the inputs.
  void resizeOutputs() {
    density.assign(size(), R(0));
    pressure.assign(size(), R(0));
    acceleration.assign(size(), SphGpuVec4<R>{R(0), R(0), R(0), R(0)});
    strain.assign(size(), R(0));
  }
  /// Fills these arrays (n particles, original order) from arrays in sorted order: id[s] is the original
  /// index of sorted particle s; eval_velocity.w holds the density.
  void assignFromSorted(size_t n, const uint32_t* id, const SphGpuVec4<R>* sorted_pos_mass,
                        const SphGpuVec4<R>* sorted_velocity, const uint32_t* sorted_material,
                        const SphGpuMat3<R>* sorted_transform, const SphGpuVec4<R>* eval_velocity,
                        const R* sorted_pressure, const SphGpuVec4<R>* sorted_acceleration,
                        const R* sorted_strain) {
    pos_mass.resize(n);
    velocity.resize(n);
    material.resize(n);
    transform.resize(n);
    resizeOutputs();
    for (size_t s = 0; s < n; ++s) {
      const uint32_t i = id[s];
      pos_mass[i] = sorted_pos_mass[s];
      velocity[i] = sorted_velocity[s];
      material[i] = sorted_material[s];
      transform[i] = sorted_transform[s];
      density[i] = eval_velocity[s].w;
      pressure[i] = sorted_pressure[s];
      acceleration[i] = sorted_acceleration[s];
      strain[i] = sorted_strain[s];
    }
  }
};

/// Everything a GPU (or host driver) solver needs: fixed time step dt, velocity Verlet as SphFluidSolver.
template <class R>
struct SphGpuSystem {
  SphGpuParams<R> params;
  std::vector<SphGpuSolidParams<R>> solids;  ///< indexed by phase (entry 0 unused), size max_phase + 1
  std::vector<SphGpuPlane<R>> planes;
  R dt = R(0);
  SphGpuParticleArrays<R> particles;
};

}  // namespace rc
