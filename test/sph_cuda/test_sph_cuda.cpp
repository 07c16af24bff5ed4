// GPU test of the SPH CUDA path (a plain program; exit code 0 = passed): the GPU step against the host
// driver of the same per-particle functions (float), a freely rotating elastic body (momenta, zero strain),
// and a hydrostatic tank (p = rho g (H - y) within 5%). `--quick`: only the comparison with the host driver.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/gpu/sph_gpu_host_solver.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_scene.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_setup.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_solver.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

int failures = 0;

void expectLess(const char* what, double value, double bound) {
  const bool ok = value < bound;
  std::printf("  [%s] %s = %.3e (bound %.1e)\n", ok ? "ok" : "FAILED", what, value, bound);
  if (!ok) ++failures;
}

/// Largest differences of two downloads.
struct Difference {
  double density = 0.0, acceleration = 0.0, position = 0.0, velocity = 0.0, strain = 0.0;
};

Difference compare(const SphGpuParticleArrays<float>& a, const SphGpuParticleArrays<float>& b,
                   double rest_density, double dx) {
  Difference d;
  double amax = 0.0, vmax = 0.0;
  for (size_t i = 0; i < b.size(); ++i) {
    const auto& ab = b.acceleration[i];
    const auto& vb = b.velocity[i];
    amax = std::max(amax, std::sqrt(double(ab.x * ab.x + ab.y * ab.y + ab.z * ab.z)));
    vmax = std::max(vmax, std::sqrt(double(vb.x * vb.x + vb.y * vb.y + vb.z * vb.z)));
  }
  const auto dist = [](const SphGpuVec4<float>& p, const SphGpuVec4<float>& q) {
    const double x = double(p.x) - q.x, y = double(p.y) - q.y, z = double(p.z) - q.z;
    return std::sqrt(x * x + y * y + z * z);
  };
  for (size_t i = 0; i < b.size(); ++i) {
    d.density = std::max(d.density, std::abs(double(a.density[i]) - b.density[i]) / rest_density);
    d.acceleration = std::max(d.acceleration, dist(a.acceleration[i], b.acceleration[i]) / amax);
    d.position = std::max(d.position, dist(a.pos_mass[i], b.pos_mass[i]) / dx);
    if (vmax > 0.0) d.velocity = std::max(d.velocity, dist(a.velocity[i], b.velocity[i]) / vmax);
    d.strain = std::max(d.strain, std::abs(double(a.strain[i]) - b.strain[i]));
  }
  return d;
}

void gpuMatchesHostDriver() {
  std::printf("GPU vs host driver (float), dam break with two elastic cubes:\n");
  SphGpuTankScene s;
  s.tank = Vec3(0.6, 0.45, 0.3);
  s.column = Vec3(0.24, 0.36, 0.3);
  s.dx = 0.015;
  s.num_blocks = 2;
  s.block_size = 0.1;
  const SphGpuScene scene = makeSphGpuTankScene(s);
  std::printf("  %zu particles (%zu fluid, %zu solid, %zu boundary), dt %.3g s\n", scene.particles.size(),
              scene.fluid_particles, scene.solid_particles, scene.boundary_particles, scene.config.fixed_dt);
  const SphGpuSystem<float> system =
      makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles);
  SphGpuHostSolver<float> host(system);
  SphGpuSolver gpu(system);
  SphGpuParticleArrays<float> h, g;
  host.download(h);
  gpu.download(g);
  const double rho0 = scene.config.rest_density;
  Difference d = compare(g, h, rho0, s.dx);
  std::printf("  first evaluation (neighbours per particle %.1f GPU, %.1f host):\n",
              gpu.neighborsPerParticle(), host.neighborsPerParticle());
  expectLess("max |rho_gpu - rho_host| / rho_0", d.density, 2e-6);
  expectLess("max |a_gpu - a_host| / max |a|", d.acceleration, 1e-3);
  expectLess("max |strain_gpu - strain_host|", d.strain, 1e-5);
  const int steps = 25;
  host.step(steps);
  gpu.step(steps);
  host.download(h);
  gpu.download(g);
  d = compare(g, h, rho0, s.dx);
  std::printf("  after %d steps:\n", steps);
  expectLess("max |x_gpu - x_host| / dx", d.position, 1e-3);
  expectLess("max |v_gpu - v_host| / max |v|", d.velocity, 1e-2);
  expectLess("max |rho_gpu - rho_host| / rho_0", d.density, 1e-3);
}

/// Linear (0-2) and angular (3-5) momentum about `center`; scale = sum |m v| (1 + |x - center|).
void momenta(const SphGpuParticleArrays<float>& a, const Vec3& center, double out[6], double& scale) {
  for (int k = 0; k < 6; ++k) out[k] = 0.0;
  scale = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const Vec3 x = Vec3(a.pos_mass[i].x, a.pos_mass[i].y, a.pos_mass[i].z) - center;
    const Vec3 mv = double(a.pos_mass[i].w) * Vec3(a.velocity[i].x, a.velocity[i].y, a.velocity[i].z);
    const Vec3 l = x.cross(mv);
    for (int k = 0; k < 3; ++k) out[k] += mv[k], out[3 + k] += l[k];
    scale += mv.norm() * (1.0 + x.norm());
  }
}

void freelyRotatingBodyKeepsMomentaAndHasNoStrain() {
  std::printf("freely rotating elastic sphere (no gravity, no walls):\n");
  const double d = 0.02;
  SphFluidConfig c;
  c.smoothing_length = 2.0 * d;
  c.stiffness = 100.0;
  c.viscosity = 0.0;
  c.xsph = 0.0;
  c.gravity = Vec3::Zero();
  c.fixed_dt = 1e-3;
  SphGpuSolidSpec spec;
  spec.phase = 1;
  spec.config.lattice_spacing = d;
  spec.config.goal_stiffness = 1e4;
  const Eigen::Matrix3d q = Eigen::AngleAxisd(0.9, Vec3(1, 1, -2).normalized()).toRotationMatrix();
  spec.orientation = q;
  const SphLattice lattice(3, d);
  const Vec3 center(0.1, 0.2, 0.3);
  SphLatticeFrame frame;
  frame.orientation = q;
  frame.origin = center;
  const std::vector<Vec3> points = sampleLatticeSphere(lattice, center, 4.2 * d, frame);
  const double mass = lattice.particleMass(SphKernels(3, c.smoothing_length), c.rest_density);
  const Vec3 spin(0.3, -0.6, 0.9), velocity(0.3, -0.1, 0.2);
  SphParticles p;
  for (const Vec3& x : points) {
    p.add(x, velocity + spin.cross(x - center), mass, SphParticleKind::kFluid);
    p.phases.back() = 1;
  }
  SphGpuSolver gpu(makeSphGpuSystem<float>(c, {}, {spec}, p));
  SphGpuParticleArrays<float> a;
  gpu.download(a);
  float strain0 = 0.0f;
  for (float e : a.strain) strain0 = std::max(strain0, e);
  double m0[6], scale;
  momenta(a, Vec3::Zero(), m0, scale);  // about the origin: both momenta are conserved
  const int steps = 300;
  float max_strain = 0.0f;
  for (int k = 0; k < steps / 10; ++k) {
    gpu.step(10);
    gpu.download(a);
    for (float e : a.strain) max_strain = std::max(max_strain, e);
  }
  double m1[6], scale1;
  momenta(a, Vec3::Zero(), m1, scale1);
  const auto drift = [&](int k0) {
    const double x = m1[k0] - m0[k0], y = m1[k0 + 1] - m0[k0 + 1], z = m1[k0 + 2] - m0[k0 + 2];
    return std::sqrt(x * x + y * y + z * z) / scale;
  };
  const double dp = drift(0), dl = drift(3);
  std::printf("  %zu particles, %d steps, t = %.2f s, body turned by %.2f rad\n", points.size(), steps,
              steps * c.fixed_dt, spin.norm() * steps * c.fixed_dt);
  expectLess("initial max strain (rigid lattice)", strain0, 1e-5);
  expectLess("max strain while spinning", max_strain, 0.02);
  expectLess("linear momentum drift / sum |m v|", dp, 1e-5);
  expectLess("angular momentum drift / sum |x| |m v|", dl, 1e-5);
}

/// Asserted for `checked`; otherwise only reported.
void hydrostaticTankSettles(double height, bool checked) {
  // Spiky pressure gradient with h = 3 dx: on the cubic lattice sum_j V r_ji (x) grad W_ij = 0.987 I (poly6
  // at h = 2.2 dx: 0.973 I, but under compression the poly6 gradient, which vanishes at r = 0, lets the
  // lattice collapse locally: interior pressures then drift to 13% low by 0.4 s, on the CPU solver alike).
  std::printf(
      "hydrostatic tank %.2f m deep (boundary-particle walls, spiky gradient, h = 3 dx, mu = 20 Pa s)%s:\n",
      height, checked ? "" : " [reported only]");
  SphGpuTankScene s;
  s.tank = Vec3(height, height + 0.05, height);
  s.column = Vec3(height, height, height);
  s.dx = 0.01;
  s.smoothing_ratio = 3.0;
  s.wall_layers = 3;
  s.viscosity = 20.0;
  SphGpuScene scene = makeSphGpuTankScene(s);
  scene.config.pressure_kernel = SphPressureKernel::kSpiky;
  const SphFluidConfig& c = scene.config;
  SphGpuSolver gpu(makeSphGpuSystem<float>(c, scene.planes, scene.solids, scene.particles));
  const double settle = 0.4, sample_every = 0.006;
  const int settle_steps = int(settle / c.fixed_dt),
            sample_steps = std::max(1, int(sample_every / c.fixed_dt));
  gpu.step(settle_steps);
  const double h = c.smoothing_length, g = 9.81, rho0 = c.rest_density;
  const double band_depth = 2 * s.dx, top = 0.25 * height;  // pairs of rows (see the CPU test)
  const int num_bands = int((height - h - top) / band_depth);
  std::vector<double> sum_p(num_bands, 0.0), sum_ref(num_bands, 0.0);
  std::vector<int> count(num_bands, 0);
  double fit_num = 0.0, fit_den = 0.0;  // least-squares slope of p over rho g (H - y) in the interior
  SphGpuParticleArrays<float> a;
  double max_speed = 0.0;
  Vec3 fastest = Vec3::Zero();
  const int samples = 50;
  for (int k = 0; k < samples; ++k) {
    gpu.step(sample_steps);
    gpu.download(a);
    max_speed = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
      if (sphKind(a.material[i]) != kSphGpuFluid) continue;
      const auto& x = a.pos_mass[i];
      const auto& v = a.velocity[i];
      const double speed = std::sqrt(double(v.x * v.x + v.y * v.y + v.z * v.z));
      if (speed > max_speed) {
        max_speed = speed;
        fastest = Vec3(x.x, x.y, x.z);
      }
      const double depth = height - x.y;
      if (x.x < h || x.x > s.tank.x() - h || x.z < h || x.z > s.tank.z() - h || depth < top) continue;
      const int band = int((depth - top) / band_depth);
      if (band >= num_bands) continue;
      sum_p[band] += a.pressure[i];
      sum_ref[band] += rho0 * g * depth;
      fit_num += a.pressure[i] * rho0 * g * depth;
      fit_den += (rho0 * g * depth) * (rho0 * g * depth);
      ++count[band];
    }
  }
  double worst = 0.0;
  int bands = 0;
  for (int b = 0; b < num_bands; ++b) {
    if (count[b] < 10 * samples) continue;
    const double ratio = sum_p[b] / sum_ref[b];
    std::printf("  band depth [%.3f, %.3f): %d samples, p / rho g (H - y) = %.4f\n", top + b * band_depth,
                top + (b + 1) * band_depth, count[b], ratio);
    worst = std::max(worst, std::abs(ratio - 1.0));
    ++bands;
  }
  std::printf(
      "  %zu particles, %d + %d steps of %.3g s, %d bands, max speed %.2e m/s at (%.3f, %.3f, %.3f)\n",
      scene.particles.size(), settle_steps, samples * sample_steps, c.fixed_dt, bands, max_speed, fastest.x(),
      fastest.y(), fastest.z());
  const double slope = fit_num / fit_den;
  std::printf("  interior fit p = %.4f rho g (H - y); worst band of two rows %.4f\n", slope, 1.0 + worst);
  if (!checked) return;
  expectLess("|fit p / rho g (H - y) - 1|", std::abs(slope - 1.0), 0.05);
  expectLess("worst band of two rows |p / rho g (H - y) - 1|", worst, 0.10);
  // Settled: the spiky gradient (not an energy gradient) keeps single particles at the walls moving a little.
  expectLess("max fluid speed / sqrt(2 g H)", max_speed / std::sqrt(2.0 * g * height), 0.15);
  if (bands < 5) {
    std::printf("  [FAILED] only %d bands\n", bands);
    ++failures;
  }
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  std::string device;
  if (!rc::SphGpuSolver::deviceAvailable(&device)) {
    std::printf("no CUDA device: %s\n", device.c_str());
    return 2;
  }
  std::printf("device: %s\n", device.c_str());
  try {
    rc::gpuMatchesHostDriver();
    if (!quick) {
      rc::freelyRotatingBodyKeepsMomentaAndHasNoStrain();
      rc::hydrostaticTankSettles(0.2, true);
      rc::hydrostaticTankSettles(0.3, false);
    }
  } catch (const std::exception& e) {
    std::printf("FAILED with exception: %s\n", e.what());
    return 1;
  }
  std::printf("%s: %d failure(s)\n", rc::failures ? "FAILED" : "PASSED", rc::failures);
  return rc::failures ? 1 : 0;
}
