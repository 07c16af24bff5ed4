// Monaghan's (2000) tensile-instability correction: a 2D lattice of fluid in uniform tension (5 % lighter
// than it holds at rest, full negative pressure, zeta = 1) is unstable: its particles pair up (the nearest
// neighbour of many particles comes far closer than the lattice spacing). With epsilon = 0.2 they stay apart.
// The key is read and checked like every solver key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_setup.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

constexpr double kDx = 0.01;

std::string patchScene(const std::string& correction) {
  return "dimension: 2\nspacing: 0.01\n"
         "solver: {smoothing_ratio: 2.5, rest_density: 1000, speed_of_sound: 20, gamma: 1, gravity: [0, 0],"
         " negative_pressure_scale: 1, xsph: 0, max_compression: 0, instability_window: 0" +
         correction +
         "}\n"
         "fluid:\n  - {lo: [-0.1, -0.1], hi: [0.1, 0.1], velocity: {gradient: [[2, 0], [0, 2]]}}\n"
         "frames: {count: 1, time: 0.1}\n";
}

struct PatchRun {
  double paired = 0;   ///< fraction of central particles with a neighbour closer than half the spacing
  double closest = 0;  ///< smallest central pair distance / spacing
  double density = 0;  ///< mean density of the central particles at the start / rho_0
};

/// A 2D lattice of n x n fluid particles, 5 % lighter than the lattice holds at rest: the interior is in
/// uniform tension (p = -0.05 K with zeta = 1); positions jittered by 2 % of the spacing. Measured on the
/// central quarter before the free edges' disturbance (at the sound speed) arrives.
PatchRun runPatch(double epsilon, double seconds, int n = 40) {
  SphFluidConfig config;
  config.dimension = 2;
  config.smoothing_length = 2.5 * kDx;
  config.rest_density = 1000;
  config.gamma = 1;
  config.stiffness = 20.0 * 20.0 * config.rest_density;  // c = 20 m/s
  config.negative_pressure_scale = 1;
  config.gravity = Vec3::Zero();
  config.xsph = 0;
  config.max_compression = 0;
  config.instability_window = 0;
  config.throw_on_instability = false;
  config.num_threads = 1;
  config.tensile_correction = epsilon;
  config.tensile_spacing = kDx;
  SphParticles particles;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.02 * kDx, 0.02 * kDx);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      particles.add(Vec3((i - 0.5 * (n - 1)) * kDx + jitter(rng), (j - 0.5 * (n - 1)) * kDx + jitter(rng), 0),
                    Vec3::Zero(), 0.95 * config.rest_density * kDx * kDx, SphParticleKind::kFluid);
  std::vector<size_t> central;
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.positions[i].cwiseAbs().maxCoeff() < 0.25 * n * kDx) central.push_back(i);
  SphFluidSolver solver(config, particles);
  solver.computeForces();
  PatchRun run;
  for (size_t i : central) run.density += solver.particles().densities[i] / config.rest_density;
  run.density /= double(central.size());
  while (solver.time() < seconds) solver.step();
  const std::vector<Vec3>& x = solver.particles().positions;
  run.closest = std::numeric_limits<double>::max();
  size_t paired = 0;
  for (size_t i : central) {
    double nearest = std::numeric_limits<double>::max();
    for (size_t j = 0; j < x.size(); ++j)
      if (j != i) nearest = std::min(nearest, (x[i] - x[j]).norm());
    paired += nearest < 0.5 * kDx;
    run.closest = std::min(run.closest, nearest / kDx);
  }
  run.paired = double(paired) / double(central.size());
  return run;
}

TEST(SphTensileCorrection, AFluidInUniformTensionDoesNotClumpWithIt) {
  // 140 x 140 particles: the free edges' disturbance reaches the central quarter after about 17 ms (35
  // spacings at c = 20 m/s); measured at 16 ms: without the correction 30-60 % of the central particles
  // have paired up (a neighbour within half a spacing), with epsilon = 0.2 none, the closest pair 0.79 apart
  // (poly6 pressure gradient, the correction along the spiky gradient).
  const PatchRun plain = runPatch(0, 0.016, 140), corrected = runPatch(0.2, 0.016, 140);
  std::printf(
      "central density %.4f rho_0; at 16 ms without correction %.1f %% paired (closest %.3f dx), "
      "epsilon 0.2 %.1f %% (closest %.3f dx)\n",
      plain.density, 100 * plain.paired, plain.closest, 100 * corrected.paired, corrected.closest);
  EXPECT_LT(plain.density, 0.96);  // in tension
  EXPECT_GT(plain.paired, 0.2);
  EXPECT_LT(plain.closest, 0.1);
  EXPECT_EQ(corrected.paired, 0.0);
  EXPECT_GT(corrected.closest, 0.6);
}

TEST(SphTensileCorrection, TheKeyIsCheckedWithItsLine) {
  expectErrorAt(patchScene(", tensile_correction: 1.5"), 3, "tensile_correction");
  expectErrorAt(
      "dimension: 2\nsolver: {smoothing_length: 0.025, tensile_correction: 0.2}\n"
      "fluid:\n  - {lo: [0, 0], hi: [0.1, 0.1], spacing: 0.01}\nframes: {count: 1, time: 0.1}\n",
      2, "needs the scene's 'spacing'");
  SphFluidConfig c;
  c.tensile_correction = 0.2;
  EXPECT_THROW(c.validate(), std::invalid_argument);  // no spacing
  c.tensile_spacing = c.smoothing_length / 4;
  EXPECT_NO_THROW(c.validate());
}

}  // namespace
}  // namespace rc
