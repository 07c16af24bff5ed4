// Host driver of the SPH GPU path: steps an SphGpuSystem on the CPU with the same per-particle functions
// (sph_gpu_kernels.h) and the same order of passes as the CUDA solver (SphGpuSolver), in float or double.
// The reference the GPU is tested against, and itself tested against SphFluidSolver / SphElasticSolid.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/sph/gpu/sph_gpu_system.h"

namespace rc {

/// Seconds of wall time per pass, summed over the steps (neighbour sort, density, forces, elastic,
/// integration).
struct SphGpuPassTimes {
  double sort = 0.0, density = 0.0, force = 0.0, elastic = 0.0, integrate = 0.0;
  uint64_t steps = 0;
  double total() const { return sort + density + force + elastic + integrate; }
};

template <class R>
class SphGpuHostSolver {
 public:
  /// Sorts the particles and evaluates the forces at the initial state (as SphFluidSolver's first step).
  /// Throws std::invalid_argument for inconsistent arrays.
  explicit SphGpuHostSolver(const SphGpuSystem<R>& system);

  /// `steps` steps of velocity Verlet: kick, drift with XSPH and planes, predicted velocity; re-sort by cell;
  /// density, forces, elastic forces at the predicted velocity; final kick. Throws std::runtime_error when a
  /// solid neighbourhood overflowed or the state became non-finite.
  void step(int steps = 1);
  /// The state and the outputs of the last force evaluation in original order.
  void download(SphGpuParticleArrays<R>& out) const;
  /// Mean number of neighbours (d < h, self excluded) of the fluid-kind particles at the last evaluation.
  double neighborsPerParticle() const { return neighbors_per_particle_; }
  const SphGpuPassTimes& passTimes() const { return times_; }
  uint64_t stepCount() const { return steps_; }

 private:
  void sortByCell();
  void evaluate();
  void checkFlags() const;
  SphGpuState<R> state();

  SphGpuParams<R> params_;
  std::vector<SphGpuSolidParams<R>> solids_;
  std::vector<SphGpuPlane<R>> planes_;
  R dt_;
  size_t n_;
  // Sorted order.
  std::vector<SphGpuVec4<R>> pos_mass_, velocity_, eval_vel_, acceleration_, xsph_, elastic_force_;
  std::vector<R> pressure_, pressure_term_, strain_;
  std::vector<uint32_t> material_, id_;  // id_[s]: original index of sorted particle s
  std::vector<SphGpuMat3<R>> transform_;
  std::vector<uint32_t> cell_start_, cell_of_, order_, neighbor_count_;
  std::vector<uint64_t> neighbor_masks_;  // 9 per particle (SphGpuState::neighbor_masks)
  uint32_t error_flags_ = 0;
  double neighbors_per_particle_ = 0.0;
  SphGpuPassTimes times_;
  uint64_t steps_ = 0;
};

extern template class SphGpuHostSolver<float>;
extern template class SphGpuHostSolver<double>;

}  // namespace rc
