// Densities by the continuity equation (SphDensityMethod::kContinuity, scene key solver.density): the rate
// sum_j m_j (v_i - v_j) . grad W_ij against the analytic -rho div v on a 2D lattice: a rigid rotation leaves
// every density unchanged (to round-off, at the free edge too), a uniform compression v = -a x raises the
// interior density at 2 a rho, a straining flow keeps the interior's. The key is checked like every solver
// key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "relaxed_connectivity/sph/sph_dam_break_surge.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_setup.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

constexpr double kDx = 0.01;
constexpr int kN = 40;

SphFluidConfig latticeConfig(SphPressureKernel kernel) {
  SphFluidConfig config;
  config.dimension = 2;
  config.smoothing_length = 2.5 * kDx;
  config.rest_density = 1000;
  config.stiffness = 20.0 * 20.0 * config.rest_density;  // c = 20 m/s
  config.gravity = Vec3::Zero();
  config.density = SphDensityMethod::kContinuity;
  config.pressure_kernel = kernel;
  config.num_threads = 1;
  return config;
}

/// kN x kN particles at rest density, centred on the origin, with velocity field(x).
template <class Field>
SphFluidSolver latticeWithVelocity(SphPressureKernel kernel, Field field) {
  const SphFluidConfig config = latticeConfig(kernel);
  SphParticles particles;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const Vec3 x((i - 0.5 * (kN - 1)) * kDx, (j - 0.5 * (kN - 1)) * kDx, 0);
      particles.add(x, field(x), config.rest_density * kDx * kDx, SphParticleKind::kFluid);
    }
  SphFluidSolver solver(config, particles);
  solver.computeForces();
  return solver;
}

bool interior(const Vec3& x) {
  return x.cwiseAbs().maxCoeff() < 0.5 * kN * kDx - 3 * kDx;
}

TEST(SphContinuityDensity, RatesMatchMinusRhoDivV) {
  const double a = 3.0, omega = 5.0, rho0 = 1000;
  for (SphPressureKernel kernel : {SphPressureKernel::kPoly6, SphPressureKernel::kSpiky}) {
    const char* name = kernel == SphPressureKernel::kPoly6 ? "poly6" : "spiky";
    // Rigid rotation: (v_i - v_j) . r_ij = 0 pair by pair.
    const SphFluidSolver rotating =
        latticeWithVelocity(kernel, [&](const Vec3& x) { return Vec3(-omega * x.y(), omega * x.x(), 0); });
    double worst_rotation = 0;
    for (double rate : rotating.densityRates()) worst_rotation = std::max(worst_rotation, std::abs(rate));
    // Uniform compression: div v = -2 a, drho/dt = 2 a rho.
    const SphFluidSolver compressed =
        latticeWithVelocity(kernel, [&](const Vec3& x) { return Vec3(-a * x); });
    // Straining (Monaghan's elliptical drop): div v = 0.
    const SphFluidSolver strained =
        latticeWithVelocity(kernel, [&](const Vec3& x) { return Vec3(-a * x.x(), a * x.y(), 0); });
    double worst_compression = 0, worst_strain = 0;
    size_t inside = 0;
    for (size_t i = 0; i < compressed.particles().size(); ++i) {
      if (!interior(compressed.particles().positions[i])) continue;
      ++inside;
      worst_compression =
          std::max(worst_compression, std::abs(compressed.densityRates()[i] / (2 * a * rho0) - 1));
      worst_strain = std::max(worst_strain, std::abs(strained.densityRates()[i]) / (a * rho0));
    }
    std::printf(
        "%s: rotation max |D| %.2e, compression max |D / (2 a rho) - 1| %.4f, strain max |D| / (a rho) "
        "%.2e (%zu interior particles)\n",
        name, worst_rotation, worst_compression, worst_strain, inside);
    EXPECT_LT(worst_rotation, 1e-9 * omega * rho0) << name;
    // The lattice's kernel sums: measured 0.31 % (poly6), 7.5 % (spiky, its gradient peaks at r = 0).
    EXPECT_LT(worst_compression, kernel == SphPressureKernel::kPoly6 ? 0.01 : 0.1) << name;
    EXPECT_LT(worst_strain, 1e-9) << name;  // the square lattice's symmetry
    EXPECT_GT(inside, 1000u);
  }
}

/// A free 2D blob (15 x 15 particles, jittered, random velocities, no gravity, inviscid, no XSPH) for 0.2 s
/// at the adaptive step: kinetic + compression energy, relative change at the end and largest gain.
std::pair<double, double> blobEnergyChange(SphPressureKernel kernel) {
  SphFluidConfig c;
  c.dimension = 2;
  c.xsph = 0;
  const double dx = 0.02;
  c.smoothing_length = 3.0 * dx;
  c.stiffness = 400.0 * c.rest_density;  // c = 20 m/s
  c.gravity = Vec3::Zero();
  c.num_threads = 1;
  c.density = SphDensityMethod::kContinuity;
  c.pressure_kernel = kernel;
  SphParticles p;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 15; ++j)
      p.add(Vec3(i * dx + 0.1 * dx * uni(rng), j * dx + 0.1 * dx * uni(rng), 0), Vec3(uni(rng), uni(rng), 0),
            c.rest_density * dx * dx, SphParticleKind::kFluid);
  SphFluidSolver solver(c, std::move(p));
  solver.computeForces();
  auto energy = [&] { return solver.lastStats().kinetic_energy + solver.lastStats().compression_energy; };
  const double first = energy();
  double max_gain = 0;
  for (int frame = 0; frame < 10; ++frame) {
    solver.advance(0.02);
    max_gain = std::max(max_gain, energy() / first - 1);
  }
  return {energy() / first - 1, max_gain};
}

TEST(SphContinuityDensity, AFreeBlobKeepsItsEnergyWithThePoly6Gradient) {
  // The rate uses the pressure force's gradient, so kinetic + compression energy is conserved in time; the
  // densities advance after the drift with the half-step velocities (symplectic Euler; the trapezoidal rule
  // gained 21 % here). Measured at the adaptive step: poly6 -1.1 % (largest gain +0.3 %); spiky +7.7 %.
  const auto [poly6_change, poly6_gain] = blobEnergyChange(SphPressureKernel::kPoly6);
  const auto [spiky_change, spiky_gain] = blobEnergyChange(SphPressureKernel::kSpiky);
  std::printf(
      "free blob energy over 0.2 s: poly6 %+.2f %% (largest gain %+.2f %%), spiky %+.2f %% (%+.2f %%)\n",
      100 * poly6_change, 100 * poly6_gain, 100 * spiky_change, 100 * spiky_gain);
  EXPECT_LT(std::abs(poly6_change), 0.02);
  EXPECT_LT(poly6_gain, 0.01);
  EXPECT_GT(spiky_gain, 0.03);  // why the scene reader warns about spiky with either density
}

TEST(SphContinuityDensity, DamBreakSurgeFrontStillFollowsTheExperiments) {
  // test_sph_validation's coarse dam break with continuity densities. Measured max relative errors: Martin &
  // Moyce 0.124 (summation 0.087), Koshizuka & Oka 0.065 (0.051); re-initialised every 20 steps 0.102, 0.071.
  const SphDamBreak2D scene = martinMoyceDamBreak(20, 3.0);
  for (int reinit : {0, 20}) {
    SphFluidConfig config = martinMoyceDamBreakConfig(scene);
    config.density = SphDensityMethod::kContinuity;
    config.density_reinit_interval = reinit;
    const SphSurgeRun mm = runDamBreakSurge(scene, config, martinMoyceSurge(), 3.0);
    const SphSurgeRun ko = runDamBreakSurge(scene, config, koshizukaOkaSurge(), 3.0);
    std::printf("continuity, reinit %d: max relative error Martin & Moyce %.3f, Koshizuka & Oka %.3f\n",
                reinit, mm.max_rel_error, ko.max_rel_error);
    ASSERT_EQ(mm.front.size(), martinMoyceSurge().size());
    EXPECT_LT(mm.max_rel_error, 0.13) << reinit;
    EXPECT_LT(ko.max_rel_error, 0.08) << reinit;
    EXPECT_GT(mm.front.back().x_over_l, 3.0);
  }
}

TEST(SphContinuityDensity, BitwiseIdenticalForAnyThreadCount) {
  // 70 x 70 particles (enough for several threads), jittered, random velocities, re-initialised every 3
  // steps.
  auto run = [](int threads) {
    SphFluidConfig c = latticeConfig(SphPressureKernel::kPoly6);
    c.density_reinit_interval = 3;
    c.num_threads = threads;
    SphParticles p;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (int i = 0; i < 70; ++i)
      for (int j = 0; j < 70; ++j)
        p.add(Vec3((i + 0.2 * uni(rng)) * kDx, (j + 0.2 * uni(rng)) * kDx, 0), Vec3(uni(rng), uni(rng), 0),
              c.rest_density * kDx * kDx, SphParticleKind::kFluid);
    SphFluidSolver solver(c, std::move(p));
    for (int s = 0; s < 10; ++s) solver.step();
    return solver.particles();
  };
  const SphParticles one = run(1), two = run(2);
  EXPECT_EQ(0, std::memcmp(one.positions.data(), two.positions.data(), one.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(one.densities.data(), two.densities.data(), one.size() * sizeof(double)));
  EXPECT_NE(one.densities[0], 1000.0);  // the densities moved
}

TEST(SphContinuityDensity, SummationHasNoRates) {
  SphFluidConfig config = latticeConfig(SphPressureKernel::kPoly6);
  config.density = SphDensityMethod::kSummation;
  SphParticles particles;
  particles.add(Vec3::Zero(), Vec3::Zero(), 0.1, SphParticleKind::kFluid);
  SphFluidSolver solver(config, particles);
  solver.computeForces();
  EXPECT_TRUE(solver.densityRates().empty());
}

TEST(SphContinuityDensity, TheKeyIsCheckedWithItsLine) {
  const std::string scene =
      "dimension: 2\nspacing: 0.01\n"
      "solver: {smoothing_ratio: 2.5, density: %s}\n"
      "fluid:\n  - {lo: [0, 0], hi: [0.1, 0.1]}\nframes: {count: 1, time: 0.1}\n";
  auto with = [&](const std::string& value) {
    std::string s = scene;
    return s.replace(s.find("%s"), 2, value);
  };
  EXPECT_EQ(parseSphScene(with("continuity"), "continuity.yaml").config.density,
            SphDensityMethod::kContinuity);
  EXPECT_EQ(parseSphScene(with("summation"), "summation.yaml").config.density, SphDensityMethod::kSummation);
  expectErrorAt(with("continuous"), 3, "solver.density");
  expectErrorAt(with("continuity, density_reinit_interval: -1"), 3, "density_reinit_interval");
  expectErrorAt(with("summation, density_reinit_interval: 20"), 3, "density_reinit_interval");
  EXPECT_EQ(parseSphScene(with("continuity, density_reinit_interval: 20"), "reinit.yaml")
                .config.density_reinit_interval,
            20);
}

}  // namespace
}  // namespace rc
