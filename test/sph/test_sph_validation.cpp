// 2D dam-break validation of the SPH fluid (thesis 8.1, REFERENCES): surge front x/L against
// t* = t sqrt(2 g / L) for a column of width L and height 2L, against Martin & Moyce (1952) and Koshizuka &
// Oka (1996); the reference tables and their sources are in src/sph/sph_dam_break_surge.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "relaxed_connectivity/sph/sph_dam_break_surge.h"

namespace rc {
namespace {

/// Coarse dam break: L = 0.1 m, 20 particles across the column (800 fluid particles), h = 3 dx, the
/// energy-conserving defaults (poly6 pressure gradient, summation walls; test_sph_energy.cpp), mu = 0.5 Pa s,
/// XSPH 0.1, c = 10 sqrt(2 g 2L), tank 5L wide. Max relative errors: 0.087 (Martin & Moyce), 0.051 (Koshizuka
/// & Oka). The thesis' spiky gradient with extrapolated walls and mu = 1 (the former setup) reads 0.068 and
/// 0.111 but gains 28% energy in 0.25 s; with mu = 1 the poly6 defaults read 0.106 and 0.062. mu = 0.5 Pa s
/// (about 500x water) was chosen by this error; water's 1e-3 Pa s reads 0.097 and 0.259 (the front leads from
/// t* = 0.84 on), 0.137 and 0.170 at 40 particles across (bench_sph_fluid --viscosity).
SphDamBreak2D coarseDamBreak() {
  return martinMoyceDamBreak(20, 3.0);
}

SphFluidConfig damBreakConfig(const SphDamBreak2D& scene) {
  return martinMoyceDamBreakConfig(scene);
}

void printRun(const char* name, const SphSurgeRun& run, const std::vector<SphSurgeSample>& reference) {
  std::printf("%s: %zu fluid particles, %llu steps, max |x/L - ref| = %.3f, max relative %.3f\n", name,
              run.fluid_particles, (unsigned long long)run.steps, run.max_abs_error, run.max_rel_error);
  for (const SphSurgeSample& s : run.front)
    std::printf("  t* %.3f  x/L %.3f  ref %.3f\n", s.t_star, s.x_over_l,
                interpolateSurge(reference, s.t_star));
}

TEST(SphValidation, DamBreakSurgeFrontFollowsMartinMoyce) {
  const SphDamBreak2D scene = coarseDamBreak();
  const SphSurgeRun run = runDamBreakSurge(scene, damBreakConfig(scene), martinMoyceSurge(), 3.0);
  printRun("Martin & Moyce n^2 = 2", run, martinMoyceSurge());
  ASSERT_EQ(run.front.size(), martinMoyceSurge().size());  // all samples have t* <= 3
  EXPECT_LT(run.max_rel_error, 0.09);                      // measured 0.087
  EXPECT_GT(run.front.back().x_over_l, 3.0);               // the surge has travelled (x/L = 1 at rest)
}

// At water's viscosity (1e-3 Pa s) the front runs ahead of Martin & Moyce: by 0.16 L at t* = 1.43 (9.7%, the
// largest relative error) and by 0.25 L (6.9%) at t* = 2.98, where mu = 0.5 Pa s lags by 0.32 L.
TEST(SphValidation, DamBreakSurgeFrontAtWaterViscosity) {
  const SphDamBreak2D scene = coarseDamBreak();
  SphFluidConfig config = damBreakConfig(scene);
  config.viscosity = 1e-3;
  const SphSurgeRun run = runDamBreakSurge(scene, config, martinMoyceSurge(), 3.0);
  printRun("Martin & Moyce n^2 = 2, mu = 1e-3 Pa s", run, martinMoyceSurge());
  ASSERT_EQ(run.front.size(), martinMoyceSurge().size());
  EXPECT_LT(run.max_rel_error, 0.10);  // measured 0.097
  const SphSurgeSample& last = run.front.back();
  EXPECT_GT(last.x_over_l, interpolateSurge(martinMoyceSurge(), last.t_star) + 0.2);  // measured + 0.25
}

// The two experiments differ by about 11% themselves at t* = 2.7 (Koshizuka & Oka's front is slower; Martin &
// Moyce interpolate to x/L = 3.33 there, Koshizuka & Oka measured 3.00), so the bound is 15% (the simulation
// lies between them; the former spiky setup, which follows Martin & Moyce, was 11% ahead of Koshizuka & Oka).
TEST(SphValidation, DamBreakSurgeFrontFollowsKoshizukaOka) {
  const SphDamBreak2D scene = coarseDamBreak();
  const SphSurgeRun run = runDamBreakSurge(scene, damBreakConfig(scene), koshizukaOkaSurge(), 3.0);
  printRun("Koshizuka & Oka", run, koshizukaOkaSurge());
  EXPECT_LT(run.max_rel_error, 0.15);
}

TEST(SphValidation, SurgeReferenceInterpolates) {
  EXPECT_DOUBLE_EQ(interpolateSurge(martinMoyceSurge(), 0.0), 1.0);
  EXPECT_DOUBLE_EQ(interpolateSurge(martinMoyceSurge(), 2.51), 3.0);
  EXPECT_NEAR(interpolateSurge(koshizukaOkaSurge(), 0.5 * (0.381 + 0.769)), 0.5 * (1.111 + 1.252), 1e-12);
  EXPECT_DOUBLE_EQ(interpolateSurge(koshizukaOkaSurge(), 10.0), 3.624);  // clamped
  EXPECT_THROW(interpolateSurge({}, 1.0), std::invalid_argument);
  const SphDamBreak2D scene = coarseDamBreak();
  EXPECT_THROW(runDamBreakSurge(scene, damBreakConfig(scene), {{1.0, 1.0}, {0.5, 1.2}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace rc
