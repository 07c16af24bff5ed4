#include "relaxed_connectivity/sph/gpu/sph_gpu_setup.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("makeSphGpuSystem: " + what);
}

template <class R>
SphGpuMat3<R> toMat3(const Eigen::Matrix3d& a) {
  SphGpuMat3<R> m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.m[i][j] = R(a(i, j));
  return m;
}

bool isRotation(const Eigen::Matrix3d& q) {
  return q.allFinite() && (q.transpose() * q - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
         q.determinant() > 0.0;
}

}  // namespace

template <class R>
SphGpuSystem<R> makeSphGpuSystem(const SphFluidConfig& config, const std::vector<SphPlane>& planes,
                                 const std::vector<SphGpuSolidSpec>& solids, const SphParticles& particles,
                                 const SphGpuGridOptions& grid) {
  config.validate();
  require(config.dimension == 3,
          "SphFluidConfig.dimension must be 3 on the GPU path, got " + std::to_string(config.dimension));
  require(config.fixed_dt > 0.0, "SphFluidConfig.fixed_dt must be > 0 (the GPU path has no adaptive step)");
  require(config.boundary_pressure == SphBoundaryPressure::kSummation,
          "SphFluidConfig.boundary_pressure must be kSummation on the GPU path");
  require(config.tensile_correction == 0.0,
          "SphFluidConfig.tensile_correction is not supported on the GPU path (0 = off)");
  require(config.density == SphDensityMethod::kSummation,
          "SphFluidConfig.density must be kSummation on the GPU path (continuity densities are CPU only)");
  require(grid.margin_h >= 0.0 && std::isfinite(grid.margin_h), "SphGpuGridOptions.margin_h must be >= 0");
  const size_t n = particles.size();
  require(n > 0, "SphParticles are empty");
  require(n < (size_t(1) << 31), "more than 2^31 particles");
  require(particles.velocities.size() == n && particles.masses.size() == n && particles.kinds.size() == n &&
              particles.phases.size() == n,
          "SphParticles arrays must all have the size of positions (" + std::to_string(n) + ")");
  const SphKernels kernels(3, config.smoothing_length);
  SphGpuSystem<R> sys;
  SphGpuParams<R>& p = sys.params;
  p.h = R(kernels.h);
  p.h2 = R(kernels.h2);
  p.inv_h = R(kernels.inv_h);
  p.poly6_coeff = R(kernels.poly6_coeff);
  p.spiky_coeff = R(kernels.spiky_coeff);
  p.viscosity_coeff = R(kernels.viscosity_coeff);
  p.rest_density = R(config.rest_density);
  p.stiffness = R(config.stiffness);
  p.gamma = R(config.gamma);
  p.negative_pressure_scale = R(config.negative_pressure_scale);
  p.viscosity = R(config.viscosity);
  p.xsph = R(config.xsph);
  p.gravity = {R(config.gravity.x()), R(config.gravity.y()), R(config.gravity.z())};
  p.poly6_pressure = config.pressure_kernel == SphPressureKernel::kPoly6 ? 1 : 0;
  sys.dt = R(config.fixed_dt);

  for (const SphPlane& plane : planes) {
    require(plane.normal.allFinite() && plane.normal.norm() > 0.0,
            "SphPlane.normal must be finite and non-zero");
    require(std::isfinite(plane.offset), "SphPlane.offset must be finite");
    require(plane.restitution >= 0.0 && plane.restitution <= 1.0, "SphPlane.restitution must be in [0, 1]");
    require(plane.friction >= 0.0 && plane.friction <= 1.0, "SphPlane.friction must be in [0, 1]");
    const double len = plane.normal.norm();
    const Vec3 nrm = plane.normal / len;
    sys.planes.push_back({{R(nrm.x()), R(nrm.y()), R(nrm.z())},
                          R(plane.offset / len),
                          R(plane.restitution),
                          R(plane.friction)});
  }
  p.num_planes = int(sys.planes.size());

  // Solids by phase.
  int max_phase = 0;
  for (const SphGpuSolidSpec& s : solids) max_phase = std::max(max_phase, int(s.phase));
  p.max_phase = max_phase;
  sys.solids.assign(size_t(max_phase) + 1, SphGpuSolidParams<R>{});
  for (auto& s : sys.solids) s.active = 0;
  std::vector<Eigen::Matrix3d> orientation(size_t(max_phase) + 1, Eigen::Matrix3d::Identity());
  for (const SphGpuSolidSpec& s : solids) {
    const std::string name = "solid of phase " + std::to_string(int(s.phase));
    require(s.phase != 0, "SphGpuSolidSpec.phase 0 is the fluid phase");
    require(!sys.solids[s.phase].active, name + " is given twice");
    s.config.validate();
    const SphElasticConfig& e = s.config;
    require(e.model == SphElasticModel::kGoalPosition,
            name + ": only the goal-position model runs on the GPU");
    require(!e.implicit_goal, name + ": implicit_goal is not supported on the GPU path");
    require(!e.docking, name + ": docking is not supported on the GPU path");
    require(!e.plasticity(), name + ": plasticity is not supported on the GPU path");
    require(!e.anchor_boundary_particles,
            name + ": anchor_boundary_particles is not supported on the GPU path");
    require(isRotation(s.orientation), name + ": orientation must be a rotation");
    require(kernels.h > 1.01 * e.lattice_spacing,
            name + ": the smoothing length must exceed the lattice spacing");
    require(e.min_neighbors >= 3, name + ": min_neighbors must be >= 3");
    const SphLattice lattice(3, e.lattice_spacing);
    SphGpuSolidParams<R>& sp = sys.solids[s.phase];
    sp.active = 1;
    sp.basis = toMat3<R>(lattice.basis());
    sp.inverse_basis = toMat3<R>(lattice.inverseBasis());
    sp.gram = toMat3<R>(lattice.basis().transpose() * lattice.basis());
    sp.spacing2 = R(e.lattice_spacing * e.lattice_spacing);
    sp.cell_volume = R(lattice.cellVolume());
    sp.goal_stiffness = R(e.goal_stiffness);
    sp.deformation_allowance = R(e.deformation_allowance);
    sp.min_neighbors = e.min_neighbors;
    orientation[s.phase] = s.orientation;
  }

  // Particles.
  SphGpuParticleArrays<R>& a = sys.particles;
  a.pos_mass.resize(n);
  a.velocity.resize(n);
  a.material.resize(n);
  a.transform.resize(n);
  Vec3 lo = particles.positions[0], hi = lo;
  for (size_t i = 0; i < n; ++i) {
    const Vec3& x = particles.positions[i];
    const Vec3& v = particles.velocities[i];
    const bool ok = x.allFinite() && v.allFinite() && particles.masses[i] > 0.0 &&
                    std::isfinite(particles.masses[i]) && uint32_t(particles.kinds[i]) <= 2;
    if (!ok) {
      const std::string which = "particle " + std::to_string(i);
      require(x.allFinite(), which + ": position is not finite");
      require(v.allFinite(), which + ": velocity is not finite");
      require(uint32_t(particles.kinds[i]) <= 2, which + ": kind is unknown");
      require(false, which + ": mass must be finite and > 0");
    }
    const uint32_t kind = uint32_t(particles.kinds[i]);
    const uint32_t phase = particles.phases[i];
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
    a.pos_mass[i] = {R(x.x()), R(x.y()), R(x.z()), R(particles.masses[i])};
    a.velocity[i] = {R(v.x()), R(v.y()), R(v.z()), R(0)};
    a.material[i] = kind | (phase << 8);
    const bool solid = phase != 0 && int(phase) <= max_phase && sys.solids[phase].active;
    a.transform[i] = toMat3<R>(solid ? orientation[phase] : Eigen::Matrix3d::Identity());
  }
  a.resizeOutputs();

  // Grid: cells of at least h over the widened bounding box, coarsened to at most ~2 cells per particle
  // plus a million.
  const double margin = grid.margin_h * config.smoothing_length;
  lo -= Vec3::Constant(margin);
  hi += Vec3::Constant(margin);
  double cell = config.smoothing_length * (1.0 + 1e-6);
  const double max_cells = 2.0 * double(n) + 1e6;
  for (;;) {
    double cells = 1.0;
    for (int k = 0; k < 3; ++k) cells *= std::floor((hi[k] - lo[k]) / cell) + 1.0;
    if (cells <= max_cells) break;
    cell *= 1.25;
  }
  for (int k = 0; k < 3; ++k) {
    p.grid_lo[k] = R(lo[k]);
    p.dims[k] = int(std::floor((hi[k] - lo[k]) / cell)) + 1;
  }
  p.inv_cell = R(1.0 / cell);
  return sys;
}

template <class R>
void copySphGpuState(const SphGpuParticleArrays<R>& a, SphParticles& particles) {
  const size_t n = a.size();
  if (particles.size() != n || a.velocity.size() != n || a.density.size() != n || a.acceleration.size() != n)
    throw std::invalid_argument("copySphGpuState: " + std::to_string(n) + " arrays for " +
                                std::to_string(particles.size()) + " particles (or outputs not downloaded)");
  particles.densities.resize(n);
  particles.pressures.resize(n);
  particles.forces.resize(n);
  for (size_t i = 0; i < n; ++i) {
    particles.positions[i] = Vec3(a.pos_mass[i].x, a.pos_mass[i].y, a.pos_mass[i].z);
    particles.velocities[i] = Vec3(a.velocity[i].x, a.velocity[i].y, a.velocity[i].z);
    particles.densities[i] = a.density[i];
    particles.pressures[i] = a.pressure[i];
    particles.forces[i] =
        particles.masses[i] * Vec3(a.acceleration[i].x, a.acceleration[i].y, a.acceleration[i].z);
  }
}

template SphGpuSystem<float> makeSphGpuSystem<float>(const SphFluidConfig&, const std::vector<SphPlane>&,
                                                     const std::vector<SphGpuSolidSpec>&, const SphParticles&,
                                                     const SphGpuGridOptions&);
template SphGpuSystem<double> makeSphGpuSystem<double>(const SphFluidConfig&, const std::vector<SphPlane>&,
                                                       const std::vector<SphGpuSolidSpec>&,
                                                       const SphParticles&, const SphGpuGridOptions&);
template void copySphGpuState<float>(const SphGpuParticleArrays<float>&, SphParticles&);
template void copySphGpuState<double>(const SphGpuParticleArrays<double>&, SphParticles&);

}  // namespace rc
