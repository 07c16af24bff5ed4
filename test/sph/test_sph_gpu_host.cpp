// The host driver of the GPU path's shared per-particle functions against the CPU solver (SphFluidSolver with
// SphElasticSolid, explicit goal-position model): one force evaluation and short trajectories, in double
// (agreement to rounding) and float (the GPU's precision).
#include "relaxed_connectivity/sph/gpu/sph_gpu_host_solver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "relaxed_connectivity/sph/gpu/sph_gpu_scene.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_setup.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

std::unique_ptr<SphFluidSolver> cpuSolver(const SphGpuScene& scene) {
  auto solver = std::make_unique<SphFluidSolver>(scene.config, scene.particles);
  for (const SphPlane& plane : scene.planes) solver->addPlane(plane);
  const SphKernels kernels(3, scene.config.smoothing_length);
  for (const SphGpuSolidSpec& s : scene.solids)
    solver->addForceTerm(std::make_shared<SphElasticSolid>(s.config, kernels, s.phase, s.orientation));
  return solver;
}

/// Differences of a host-driver state from the CPU solver's particles.
struct Deviation {
  double density = 0.0;   ///< max |rho - rho_cpu| / rho_0
  double force = 0.0;     ///< max |F - F_cpu| / max |F_cpu| (fluid kind)
  double position = 0.0;  ///< max |x - x_cpu| / dx
  double velocity = 0.0;  ///< max |v - v_cpu| / max |v_cpu|
};

template <class R>
Deviation deviation(const SphGpuHostSolver<R>& host, const SphParticles& cpu, double rest_density,
                    double dx) {
  SphGpuParticleArrays<R> a;
  host.download(a);
  SphParticles mine = cpu;
  copySphGpuState(a, mine);
  Deviation d;
  double fmax = 0.0, vmax = 0.0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    if (cpu.kinds[i] != SphParticleKind::kFluid) continue;
    fmax = std::max(fmax, cpu.forces[i].norm());
    vmax = std::max(vmax, cpu.velocities[i].norm());
  }
  for (size_t i = 0; i < cpu.size(); ++i) {
    d.density = std::max(d.density, std::abs(mine.densities[i] - cpu.densities[i]) / rest_density);
    d.position = std::max(d.position, (mine.positions[i] - cpu.positions[i]).norm() / dx);
    if (cpu.kinds[i] != SphParticleKind::kFluid) continue;
    d.force = std::max(d.force, (mine.forces[i] - cpu.forces[i]).norm() / fmax);
    if (vmax > 0.0) d.velocity = std::max(d.velocity, (mine.velocities[i] - cpu.velocities[i]).norm() / vmax);
  }
  return d;
}

SphGpuTankScene smallDamBreak(int blocks) {
  SphGpuTankScene s;
  s.tank = Vec3(0.6, 0.45, 0.3);
  s.column = Vec3(0.24, 0.36, 0.3);
  s.dx = 0.03;
  s.num_blocks = blocks;
  s.block_size = 0.15;
  return s;
}

TEST(SphGpuHostSolver, DamBreakWithBlockMatchesCpuSolver) {
  const SphGpuScene scene = makeSphGpuTankScene(smallDamBreak(1));
  ASSERT_GT(scene.solid_particles, 100u);
  ASSERT_GT(scene.fluid_particles, 500u);
  const double dx = 0.03, rho0 = scene.config.rest_density;
  auto cpu = cpuSolver(scene);
  cpu->computeForces();
  SphGpuHostSolver<double> host_d(
      makeSphGpuSystem<double>(scene.config, scene.planes, scene.solids, scene.particles));
  SphGpuHostSolver<float> host_f(
      makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
  const Deviation d0 = deviation(host_d, cpu->particles(), rho0, dx);
  const Deviation f0 = deviation(host_f, cpu->particles(), rho0, dx);
  std::printf("evaluation: density %.2e / %.2e, force %.2e / %.2e (double / float), %zu particles\n",
              d0.density, f0.density, d0.force, f0.force, scene.particles.size());
  EXPECT_LT(d0.density, 1e-12);
  EXPECT_LT(d0.force, 1e-10);
  EXPECT_LT(f0.density, 1e-6);
  // Float densities near rho_0 = 1000 resolve 6e-5, so pressures resolve K 6e-8 = 0.04 Pa (K = 7e5 Pa): the
  // pressure forces of mirror-symmetric neighbours, which cancel exactly in double, leave ~5e-4 max |F|.
  EXPECT_LT(f0.force, 2e-3);
  const int steps = 40;
  for (int k = 0; k < steps; ++k) cpu->step();
  host_d.step(steps);
  host_f.step(steps);
  const Deviation d1 = deviation(host_d, cpu->particles(), rho0, dx);
  const Deviation f1 = deviation(host_f, cpu->particles(), rho0, dx);
  std::printf(
      "after %d steps (t = %.4f s): position %.2e / %.2e dx, velocity %.2e / %.2e, density %.2e / %.2e\n",
      steps, cpu->time(), d1.position, f1.position, d1.velocity, f1.velocity, d1.density, f1.density);
  EXPECT_LT(d1.position, 1e-9);
  EXPECT_LT(d1.velocity, 1e-8);
  EXPECT_LT(f1.position, 1e-4);
  EXPECT_LT(f1.velocity, 1e-3);
  EXPECT_LT(f1.density, 1e-4);
  EXPECT_GT(cpu->lastStats().max_speed, 0.1);  // the column is collapsing
}

/// A rotated fcc block stretched by 10% along a tilted axis, spinning, no gravity, walls or viscosity.
SphGpuScene stretchedBlock() {
  SphGpuScene scene;
  const double d = 0.05;
  SphFluidConfig& c = scene.config;
  c.dimension = 3;
  c.smoothing_length = 2.0 * d;
  c.stiffness = 100.0;  // weak pressure: elastic forces dominate
  c.viscosity = 0.0;
  c.xsph = 0.0;
  c.gravity = Vec3::Zero();
  c.fixed_dt = 2e-3;
  SphGpuSolidSpec spec;
  spec.phase = 3;
  spec.config.lattice_spacing = d;
  spec.config.goal_stiffness = 1e4;
  spec.orientation = Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  scene.solids.push_back(spec);
  const SphLattice lattice(3, d);
  SphLatticeFrame frame;
  frame.orientation = spec.orientation;
  const std::vector<Vec3> rest = sampleLatticeBox(lattice, Vec3::Zero(), Vec3(0.4, 0.3, 0.3), frame);
  const SphKernels kernels(3, c.smoothing_length);
  const double mass = lattice.particleMass(kernels, c.rest_density);
  const Vec3 axis = Vec3(1, 0.3, -0.2).normalized(), spin(0.5, -1.0, 2.0);
  for (const Vec3& x : rest) {
    const Vec3 y = x + 0.1 * axis.dot(x - Vec3(0.2, 0.15, 0.15)) * axis;
    scene.particles.add(y, spin.cross(y), mass, SphParticleKind::kFluid);
    scene.particles.phases.back() = spec.phase;
  }
  scene.solid_particles = rest.size();
  return scene;
}

template <class R>
void momentaOf(const SphGpuHostSolver<R>& host, Vec3& linear, Vec3& angular, double& scale) {
  SphGpuParticleArrays<R> a;
  host.download(a);
  linear.setZero();
  angular.setZero();
  scale = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const Vec3 x(a.pos_mass[i].x, a.pos_mass[i].y, a.pos_mass[i].z);
    const Vec3 mv = double(a.pos_mass[i].w) * Vec3(a.velocity[i].x, a.velocity[i].y, a.velocity[i].z);
    linear += mv;
    angular += x.cross(mv);
    scale += mv.norm() * (1.0 + x.norm());
  }
}

TEST(SphGpuHostSolver, StretchedSpinningBlockMatchesCpuAndKeepsMomentum) {
  const SphGpuScene scene = stretchedBlock();
  ASSERT_GT(scene.solid_particles, 200u);
  auto cpu = cpuSolver(scene);
  cpu->computeForces();
  SphGpuHostSolver<double> host_d(
      makeSphGpuSystem<double>(scene.config, scene.planes, scene.solids, scene.particles));
  SphGpuHostSolver<float> host_f(
      makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
  const double d = 0.05, rho0 = scene.config.rest_density;
  const Deviation d0 = deviation(host_d, cpu->particles(), rho0, d);
  const Deviation f0 = deviation(host_f, cpu->particles(), rho0, d);
  std::printf("stretched block: force %.2e / %.2e (double / float)\n", d0.force, f0.force);
  EXPECT_LT(d0.force, 1e-9);
  EXPECT_LT(f0.force, 1e-4);
  Vec3 p0d, l0d, p0f, l0f;
  double sd, sf;
  momentaOf(host_d, p0d, l0d, sd);
  momentaOf(host_f, p0f, l0f, sf);
  const int steps = 50;
  for (int k = 0; k < steps; ++k) cpu->step();
  host_d.step(steps);
  host_f.step(steps);
  const Deviation d1 = deviation(host_d, cpu->particles(), rho0, d);
  const Deviation f1 = deviation(host_f, cpu->particles(), rho0, d);
  Vec3 p1d, l1d, p1f, l1f;
  momentaOf(host_d, p1d, l1d, sd);
  momentaOf(host_f, p1f, l1f, sf);
  std::printf(
      "after %d steps: position %.2e / %.2e d; momentum drift linear %.2e / %.2e, angular %.2e / %.2e\n",
      steps, d1.position, f1.position, (p1d - p0d).norm() / sd, (p1f - p0f).norm() / sf,
      (l1d - l0d).norm() / sd, (l1f - l0f).norm() / sf);
  EXPECT_LT(d1.position, 1e-9);
  EXPECT_LT(f1.position, 1e-3);
  EXPECT_LT((p1d - p0d).norm() / sd, 1e-12);
  EXPECT_LT((l1d - l0d).norm() / sd, 1e-12);
  EXPECT_LT((p1f - p0f).norm() / sf, 1e-5);
  EXPECT_LT((l1f - l0f).norm() / sf, 1e-5);
}

TEST(SphGpuHostSolver, RigidlyRotatedBlockHasZeroStrain) {
  SphGpuScene scene = stretchedBlock();
  // Undo the stretch: the sampled rest points, rotated about the centre.
  const SphLattice lattice(3, 0.05);
  SphLatticeFrame frame;
  frame.orientation = scene.solids[0].orientation;
  const std::vector<Vec3> rest = sampleLatticeBox(lattice, Vec3::Zero(), Vec3(0.4, 0.3, 0.3), frame);
  const Eigen::Matrix3d q = Eigen::AngleAxisd(1.1, Vec3(0.2, 1, 0.4).normalized()).toRotationMatrix();
  for (size_t i = 0; i < rest.size(); ++i) scene.particles.positions[i] = q * rest[i];
  scene.solids[0].orientation = q * scene.solids[0].orientation;
  SphGpuHostSolver<float> host(
      makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
  SphGpuParticleArrays<float> a;
  host.download(a);
  float max_strain = 0.0f;
  for (float e : a.strain) max_strain = std::max(max_strain, e);
  std::printf("rigidly rotated block: max strain %.2e (float)\n", max_strain);
  EXPECT_LT(max_strain, 1e-5f);
}

TEST(SphGpuSetup, RejectsWhatTheGpuPathDoesNotSupport) {
  SphGpuScene scene = makeSphGpuTankScene(smallDamBreak(0));
  SphFluidConfig adaptive = scene.config;
  adaptive.fixed_dt = 0.0;
  EXPECT_THROW(makeSphGpuSystem<float>(adaptive, scene.planes, scene.solids, scene.particles),
               std::invalid_argument);
  SphFluidConfig flat = scene.config;
  flat.dimension = 2;
  EXPECT_THROW(makeSphGpuSystem<float>(flat, scene.planes, scene.solids, scene.particles),
               std::invalid_argument);
  SphGpuSolidSpec implicit_solid;
  implicit_solid.config.lattice_spacing = 0.03;
  implicit_solid.config.implicit_goal = true;
  try {
    makeSphGpuSystem<float>(scene.config, scene.planes, {implicit_solid}, scene.particles);
    FAIL() << "implicit_goal accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("implicit_goal"), std::string::npos) << e.what();
  }
  scene.particles.positions[3].x() = NAN;
  EXPECT_THROW(makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles),
               std::invalid_argument);
}

}  // namespace
}  // namespace rc
