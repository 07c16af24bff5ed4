// Test and benchmark scene of the SPH GPU path: a 3D dam break in a tank of boundary-particle walls and
// planes, with elastic blocks (explicit goal-position model, 8.2) dropped beside the fluid column.
#pragma once

#include <vector>

#include "relaxed_connectivity/sph/gpu/sph_gpu_setup.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

struct SphGpuTankScene {
  Vec3 tank = Vec3(1.0, 0.6, 0.5);    ///< inner size of the tank (floor at y = 0, corner at the origin)
  Vec3 column = Vec3(0.4, 0.5, 0.5);  ///< fluid column in the corner x = 0, z = 0
  double dx = 0.01;                   ///< fluid lattice spacing (cubic)
  double smoothing_ratio = 2.2;       ///< h / dx
  int wall_layers = 2;                ///< boundary particle layers (0: planes only)
  int num_blocks = 0;                 ///< elastic cubes beside the column, phases 1..num_blocks
  double block_size = 0.15;           ///< edge length of a cube
  double block_drop = 0.02;           ///< gap between a cube and the floor (or the cube below)
  double goal_stiffness = 1.0e4;      ///< K_e (8.31)
  double viscosity = 0.5;             ///< mu (8.18)
  double cfl = 0.4;                   ///< fixed_dt = cfl h / c, c = 10 sqrt(2 g column height)
};

/// The scene and everything the solvers take. Elastic cubes have the fluid's volume per particle (fcc
/// spacing dx 2^(1/6)) and the lattice mass of their solid (SphLattice::particleMass).
struct SphGpuScene {
  SphFluidConfig config;
  std::vector<SphPlane> planes;
  std::vector<SphGpuSolidSpec> solids;
  SphParticles particles;
  size_t fluid_particles = 0, solid_particles = 0, boundary_particles = 0;
};

/// Throws std::invalid_argument for a non-positive size or spacing, or cubes that do not fit beside the
/// column.
SphGpuScene makeSphGpuTankScene(const SphGpuTankScene& scene);

}  // namespace rc
