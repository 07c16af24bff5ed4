#include "relaxed_connectivity/sph/gpu/sph_gpu_scene.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"

namespace rc {

SphGpuScene makeSphGpuTankScene(const SphGpuTankScene& s) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("makeSphGpuTankScene: " + what);
  };
  if (!(s.dx > 0.0) || !(s.smoothing_ratio > 1.0)) fail("dx must be > 0 and smoothing_ratio > 1");
  if (!(s.tank.minCoeff() > 0.0) || !(s.column.minCoeff() > 0.0)) fail("tank and column sizes must be > 0");
  if (s.num_blocks < 0 || s.num_blocks > 255) fail("num_blocks must be in [0, 255]");
  SphGpuScene out;
  SphFluidConfig& c = out.config;
  c.dimension = 3;
  c.smoothing_length = s.smoothing_ratio * s.dx;
  c.rest_density = 1000.0;
  const double sound = 10.0 * std::sqrt(2.0 * 9.81 * s.column.y());
  c.stiffness = sound * sound * c.rest_density;
  c.viscosity = s.viscosity;
  c.xsph = 0.1;
  c.negative_pressure_scale = 0.0;
  c.gravity = Vec3(0, -9.81, 0);
  c.fixed_dt = s.cfl * c.smoothing_length / sound;
  const SphKernels kernels(3, c.smoothing_length);
  const double mass = latticeParticleMass(kernels, c.rest_density, s.dx);
  SphParticles& p = out.particles;
  out.fluid_particles = addLatticeBox(p, Vec3::Zero(), s.column, s.dx, mass, 3);
  // Elastic cubes in slots beside the column: x then z then upwards.
  const double d = s.dx * std::pow(2.0, 1.0 / 6.0);
  const SphLattice lattice(3, d);
  const double block_mass = lattice.particleMass(kernels, c.rest_density);
  const double gap = std::max(s.block_drop, 2.0 * d);
  const double x0 = s.column.x() + gap;
  const int nx = int((s.tank.x() - x0) / (s.block_size + gap));
  const int nz = int(s.tank.z() / (s.block_size + gap));
  if (s.num_blocks > 0 && (nx < 1 || nz < 1)) fail("no room for a cube beside the column");
  for (int b = 0; b < s.num_blocks; ++b) {
    const int ix = b % std::max(nx, 1), iz = (b / std::max(nx, 1)) % std::max(nz, 1);
    const int iy = b / std::max(nx * nz, 1);
    const Vec3 lo(x0 + ix * (s.block_size + gap), s.block_drop + iy * (s.block_size + gap),
                  0.5 * gap + iz * (s.block_size + gap));
    const Vec3 hi = lo + Vec3::Constant(s.block_size);
    if (hi.y() > s.tank.y()) fail("cube " + std::to_string(b) + " does not fit into the tank");
    SphGpuSolidSpec spec;
    spec.phase = uint8_t(b + 1);
    spec.config.model = SphElasticModel::kGoalPosition;
    spec.config.lattice_spacing = d;
    spec.config.goal_stiffness = s.goal_stiffness;
    out.solids.push_back(spec);
    const std::vector<Vec3> points = sampleLatticeBox(lattice, lo, hi);
    for (const Vec3& x : points) {
      p.add(x, Vec3::Zero(), block_mass, SphParticleKind::kFluid);
      p.phases.back() = spec.phase;
    }
    out.solid_particles += points.size();
  }
  if (s.wall_layers > 0)
    out.boundary_particles = addBoundaryWalls(p, Vec3::Zero(), s.tank, s.dx, s.wall_layers, mass, 3);
  out.planes = boxPlanes(Vec3::Zero(), s.tank, 3);
  return out;
}

}  // namespace rc
