// 3D hydrostatic tank (issue 4 item 8, REFERENCES): after settling, p = rho g (H - y) within 5% in the
// interior, with the 3D settings of config/sph/hydrostatic_tank_3d.yaml (poly6 pressure gradient, h = 2.5
// dx).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

/// Bounding box of the fluid particles (lattice points are cell-centred: the block reaches dx/2 further).
struct FluidBounds {
  Vec3 lo = Vec3::Constant(1e9), hi = Vec3::Constant(-1e9);
};

FluidBounds fluidBounds(const SphParticles& particles) {
  FluidBounds b;
  for (size_t i = 0; i < particles.size(); ++i) {
    if (particles.kinds[i] != SphParticleKind::kFluid) continue;
    b.lo = b.lo.cwiseMin(particles.positions[i]);
    b.hi = b.hi.cwiseMax(particles.positions[i]);
  }
  return b;
}

// -(1/3) sum_j V_j r_ij . grad W(r_ij) over the full cubic lattice (V_j = 1 / sum_k W_k, the lattice mass):
// the factor by which the SPH pressure gradient (8.17) reads the true gradient there, so pressures that
// balance gravity settle at rho g (H - y) / M.
double latticeGradientMoment(const SphKernels& kernels, double dx, bool spiky) {
  const long r = static_cast<long>(std::ceil(kernels.h / dx));
  double sum_w = 0.0, moment = 0.0;
  for (long k = -r; k <= r; ++k)
    for (long j = -r; j <= r; ++j)
      for (long i = -r; i <= r; ++i) {
        const Vec3 x = dx * Vec3(double(i), double(j), double(k));
        sum_w += kernels.poly6(x.squaredNorm());
        moment -= x.dot(spiky ? kernels.spikyGradient(x) : kernels.poly6Gradient(x));
      }
  return moment / (3.0 * sum_w);
}

// Why the 3D default is the poly6 gradient at h = 2.5 dx: on the rest lattice the spiky gradient reads the
// pressure gradient 5-6% short at h = 2-2.2 dx (the tank settles 5-7% high there), poly6 at 2 dx 5.5% long
// (the tank: 6-8% low), poly6 at 2.5 dx 3.4% short (the tank: 0.5-1.7% high, the summation walls read low).
TEST(SphHydrostatic3D, LatticeGradientMomentExplainsThePressureBias) {
  const double dx = 1.0;
  struct Case {
    double ratio;
    bool spiky;
    double expected;
  };
  const Case cases[] = {{2.0, true, 0.9470},  {2.2, true, 0.9399},  {2.5, true, 0.9542},
                        {3.0, true, 0.9874},  {2.0, false, 1.0545}, {2.2, false, 0.9732},
                        {2.5, false, 0.9657}, {3.0, false, 1.0064}};
  for (const Case& c : cases) {
    const SphKernels kernels(3, c.ratio * dx);
    const double m = latticeGradientMoment(kernels, dx, c.spiky);
    std::printf("h = %.1f dx, %s gradient: M = %.4f\n", c.ratio, c.spiky ? "spiky" : "poly6", m);
    EXPECT_NEAR(m, c.expected, 1e-4) << c.ratio << (c.spiky ? " spiky" : " poly6");
  }
}

// The shipped scene: 0.3 m deep, 0.2 x 0.2 m, dx = 0.02 m, h = 2.5 dx. After 0.25 s of settling, pressures
// averaged over bands of depth 2 dx (whole pairs of lattice rows from depth H/4 down to y = h) and over 10
// samples in [0.27 s, 0.45 s], in the interior at least h from the side walls, match rho g (H - y) (measured:
// worst band 1.7%, bands 1.005-1.017); the interior keeps its lattice spacing (no pairs: nearest neighbour >
// 0.9 dx, 80 neighbours within h as on the lattice; measured 0.967 dx, 80.0) and is at rest (3.8e-3 m/s). 554
// steps. The window ends at 0.45 s, before the tank's limit: the same averages over later 0.18 s windows
// (probe) keep the nearest interior neighbour at 0.96 dx to 0.95 s, 0.91 dx at 1.2 s and 0.82 dx at 1.45 s;
// the first pairs (< 0.5 dx, outside the interior) appear by 1.7 s, 3 % of the interior by 2.2 s, 27 % by 2.7
// s; worst band 4.8 % up to 1.95 s, 7.9 % at 2.2 s, 13 % at 2.7 s (docs/benchmarks.md: a jittered start pairs
// after ~1.2 s).
TEST(SphHydrostatic3D, TankSettlesToRhoGDepthUntil045sBeforePairing) {
  SphScene scene = loadSphScene(sphSceneDir() + "hydrostatic_tank_3d.yaml");
  scene.config.num_threads = 1;  // small: a second thread only waits at barriers (results are bitwise equal)
  ASSERT_EQ(scene.config.dimension, 3);
  ASSERT_EQ(scene.config.pressure_kernel, SphPressureKernel::kPoly6);
  const double dx = 0.02, h = scene.config.smoothing_length;
  ASSERT_NEAR(h, 2.5 * dx, 1e-12);
  const FluidBounds fluid = fluidBounds(scene.particles);
  const double width_x = fluid.hi.x() + 0.5 * dx, width_z = fluid.hi.z() + 0.5 * dx;
  const double height = fluid.hi.y() + 0.5 * dx;  // H, the free surface at rest
  ASSERT_NEAR(height, 0.3, 1e-9);
  ASSERT_NEAR(fluid.lo.x() - 0.5 * dx, 0.0, 1e-9);

  SphFluidSolver solver = makeSphSolver(scene);
  solver.advance(0.25);
  const double g = -scene.config.gravity.y(), rho0 = scene.config.rest_density;
  const double band_depth = 2 * dx, top = 0.25 * height;
  const int num_bands = static_cast<int>((height - h - top) / band_depth);  // bands above y = h
  std::vector<double> sum_p(num_bands, 0.0), sum_ref(num_bands, 0.0);
  std::vector<int> count(num_bands, 0);
  double nearest = 1e9, neighbors = 0.0, max_speed = 0.0;
  size_t interior = 0;
  const int samples = 10;
  for (int sample = 0; sample < samples; ++sample) {
    solver.advance(0.02);
    max_speed = std::max(max_speed, solver.lastStats().max_speed);
    ASSERT_TRUE(solver.neighborsCurrent());
    const SphParticles& p = solver.particles();
    const std::vector<uint32_t>& order = solver.neighborGrid().order();
    for (size_t s = 0; s < order.size(); ++s) {
      const uint32_t i = order[s];
      if (p.kinds[i] != SphParticleKind::kFluid) continue;
      const Vec3& x = p.positions[i];
      const double depth = height - x.y();
      if (x.x() < h || x.x() > width_x - h || x.z() < h || x.z() > width_z - h || depth < top) continue;
      const int band = static_cast<int>((depth - top) / band_depth);
      if (band >= num_bands) continue;
      sum_p[band] += p.pressures[i];
      sum_ref[band] += rho0 * g * depth;
      ++count[band];
      uint32_t row_size = 0;
      const uint32_t* row = solver.neighborRow(s, row_size);
      for (uint32_t e = 0; e < row_size; ++e)
        nearest = std::min(nearest, (p.positions[order[row[e]]] - x).norm());
      neighbors += row_size;
      ++interior;
    }
  }
  double worst_band = 0.0;
  int bands = 0;
  for (int b = 0; b < num_bands; ++b) {
    std::printf("band depth [%.3f, %.3f): %d samples, p / rho g (H - y) = %.4f\n", top + b * band_depth,
                top + (b + 1) * band_depth, count[b], sum_p[b] / sum_ref[b]);
    if (count[b] < 10 * samples) continue;
    worst_band = std::max(worst_band, std::abs(sum_p[b] - sum_ref[b]) / sum_ref[b]);
    ++bands;
  }
  const double mean_neighbors = neighbors / double(std::max<size_t>(1, interior));
  std::printf(
      "hydrostatic 3D: %zu fluid particles, %d bands, worst band |p - rho g (H - y)| / rho g (H - y) = %.4f, "
      "nearest neighbour %.3f dx, %.2f neighbours, max speed %.1e m/s after %llu steps\n",
      scene.particles.count(SphParticleKind::kFluid), bands, worst_band, nearest / dx, mean_neighbors,
      max_speed, (unsigned long long)solver.stepCount());
  EXPECT_GE(bands, 4);
  EXPECT_LT(worst_band, 0.05);
  EXPECT_GT(nearest, 0.9 * dx);            // no pairing (see sph_fluid_solver.h on the 3D kernel choice)
  EXPECT_NEAR(mean_neighbors, 80.0, 2.0);  // |k| < 2.5 on the cubic lattice: 80
  EXPECT_LT(max_speed, 0.01);
}

}  // namespace
}  // namespace rc
