// Paint drying (thesis 5.6.1, (5.12), (5.13)): exact over any split of an interval, volume conserved, the dry
// colour mixed through the drying function G.
#include "relaxed_connectivity/paint/paint_drying.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rc {
namespace {

PaintState wetSurfel() {
  PaintState s;
  s.wet.rgb = Vec3(0.2, 0.4, 0.8);
  s.wet.reflectivity = 0.6;
  s.wet.shininess = 30;
  s.dry.rgb = Vec3(0.9, 0.9, 0.9);  // the object's own colour, as a base layer of dry paint
  s.dry_volume = 0.5;
  s.wet_volume = 1.2;
  return s;
}

TEST(PaintDrying, FollowsTheExponentialOverAnySplitOfTheInterval) {
  const DryingFunction g;
  const double kappa = 0.35, interval = 1.0;
  PaintState once = wetSurfel();
  dryPaint(once, kappa, interval, g);
  EXPECT_NEAR(once.wet_volume, 1.2 * std::exp(-kappa * interval), 1e-15);  // (5.12)
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    // 1000 random steps summing to the interval.
    std::vector<double> steps(1000);
    double sum = 0;
    for (double& s : steps) sum += s = std::uniform_real_distribution<double>(0.1, 1.0)(rng);
    PaintState split = wetSurfel();
    for (double s : steps) dryPaint(split, kappa, s * interval / sum, g);
    EXPECT_NEAR(split.wet_volume, once.wet_volume, 1e-12 * once.wet_volume);
    EXPECT_NEAR(split.dry_volume, once.dry_volume, 1e-12 * once.dry_volume);
    EXPECT_LT((split.dry.rgb - once.dry.rgb).norm(), 1e-12);
    EXPECT_NEAR(split.dry.reflectivity, once.dry.reflectivity, 1e-12);
    EXPECT_NEAR(split.wet_volume + split.dry_volume, 1.7, 1e-12);
  }
}

TEST(PaintDrying, TheDryColourMixesInTheDriedPaintThroughG) {
  const DryingFunction g{0.1, 0.5, 0.25};
  PaintState s = wetSurfel();
  const double dried = dryPaint(s, 0.35, 1.0, g);
  const Vec3 g_rgb = Vec3(0.2, 0.4, 0.8) + 0.1 * (Vec3::Ones() - Vec3(0.2, 0.4, 0.8));  // brightened
  EXPECT_LT((s.dry.rgb - (0.5 * Vec3(0.9, 0.9, 0.9) + dried * g_rgb) / (0.5 + dried)).norm(), 1e-15);
  EXPECT_NEAR(s.dry.reflectivity, dried * 0.5 * 0.6 / (0.5 + dried), 1e-15);  // (5.13), G halves it
  EXPECT_NEAR(s.dry.shininess, dried * 0.25 * 30 / (0.5 + dried), 1e-13);
  EXPECT_EQ(s.wet.rgb, Vec3(0.2, 0.4, 0.8));  // drying does not change the wet colour
  // Fully dried, the surfel shows G(C_w) mixed with its base: no wet paint left.
  for (int i = 0; i < 200; ++i) dryPaint(s, 0.35, 1.0, g);
  EXPECT_LT(s.wet_volume, 1e-20);
  EXPECT_LT((visibleColour(s).rgb - s.dry.rgb).norm(), 1e-15);
}

TEST(PaintDrying, NothingDriesAtZeroRateAndBadInputIsRefused) {
  PaintState s = wetSurfel();
  EXPECT_EQ(dryPaint(s, 0.0, 10.0, DryingFunction()), 0.0);
  EXPECT_EQ(s, wetSurfel());
  EXPECT_THROW(dryPaint(s, -1.0, 1.0, DryingFunction()), std::invalid_argument);
  EXPECT_THROW(dryPaint(s, 1.0, std::nan(""), DryingFunction()), std::invalid_argument);
}

}  // namespace
}  // namespace rc
