// CUDA solver of the SPH GPU path (built with RC_BUILD_CUDA into rc_sph_cuda): weakly compressible fluid
// (8.1.4) and elastic solids of the explicit goal-position model (8.2) in float, with the per-particle
// functions of sph_gpu_kernels.h (shared with SphGpuHostSolver). Every step: radix sort of the particles by
// grid cell with the kick-drift fused into the reorder (the keys come from the last force pass), and the list
// of solid particles; density (with the neighbour bit masks of the 9 cell runs); elastic forces (one thread
// per solid particle, vector atomics scatter); forces with the elastic acceleration, the final kick and the
// next cell keys. setPreviousPasses(true) runs the first version's sequence (separate passes) for comparison.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "relaxed_connectivity/sph/gpu/sph_gpu_host_solver.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_system.h"

namespace rc {

class SphGpuSolver {
 public:
  /// Whether a CUDA device can be used; `description` receives its name (or the error).
  static bool deviceAvailable(std::string* description = nullptr);

  /// Uploads the system, sorts it and evaluates the forces at the initial state. Throws std::runtime_error
  /// when no CUDA device is usable or memory runs out, std::invalid_argument for inconsistent arrays.
  explicit SphGpuSolver(const SphGpuSystem<float>& system);
  ~SphGpuSolver();
  SphGpuSolver(const SphGpuSolver&) = delete;
  SphGpuSolver& operator=(const SphGpuSolver&) = delete;

  /// `steps` velocity Verlet steps (as SphGpuHostSolver::step), asynchronous except for one check of the
  /// error flags at the end (throws std::runtime_error on a solid neighbourhood overflow or a non-finite
  /// state).
  void step(int steps = 1);
  /// step(steps) timed with CUDA events on the solver's stream: milliseconds on the device.
  double timedStep(int steps);
  /// The state and the outputs of the last force evaluation in original order (synchronises).
  void download(SphGpuParticleArrays<float>& out);
  /// Mean number of neighbours of the fluid-kind particles at the last evaluation (synchronises).
  double neighborsPerParticle();
  /// With profiling on, every pass is timed with CUDA events (milliseconds summed into passTimes(), in
  /// seconds); this synchronises after every step.
  void setProfiling(bool on);
  const SphGpuPassTimes& passTimes() const;
  /// On (default): the density pass records per particle which candidates of its 9 cell runs are neighbours
  /// (bit masks), so the force and elastic passes visit only neighbours; off: every pass scans the cells.
  void setNeighborMasks(bool on);
  /// On: the pass sequence of the first version (separate kick-drift pass, elastic forces after the forces,
  /// memset and finish passes), for comparison; off (default): kick-drift fused into the sort, elastic
  /// acceleration and final kick into the force pass. Both give the same results up to float rounding.
  void setPreviousPasses(bool on);
  void resetPassTimes();
  /// Waits for all queued work.
  void synchronize();
  size_t size() const;
  uint64_t stepCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rc
