#include <gtest/gtest.h>

#include <cmath>

#include "relaxed_connectivity/core/weight_function.h"

namespace rc {
namespace {

TEST(WeightFunction, GaussianMatchesFormula) {  // (3.10)
  const WeightFunction w = WeightFunction::gaussian(0.5);
  EXPECT_DOUBLE_EQ(w(0.0), 1.0);
  EXPECT_NEAR(w(0.5), std::exp(-1.0), 1e-15);
  EXPECT_TRUE(std::isinf(w.support()));
}

TEST(WeightFunction, ClippedGaussianIsZeroBeyondClip) {  // (3.11)
  const WeightFunction w = WeightFunction::clippedGaussian(0.5, 3.0);
  EXPECT_DOUBLE_EQ(w.support(), 1.5);
  EXPECT_NEAR(w(1.49), std::exp(-1.49 * 1.49 / 0.25), 1e-15);
  EXPECT_EQ(w(1.5), 0.0);
}

TEST(WeightFunction, WendlandIsC2WithCompactSupport) {  // (3.12)
  const WeightFunction w = WeightFunction::wendland(2.0);
  EXPECT_DOUBLE_EQ(w(0.0), 1.0);
  EXPECT_EQ(w(2.0), 0.0);
  // w'(0) = 0 (smooth at the centre) and w, w', w'' vanish at the support boundary: finite differences.
  const double h = 1e-4;
  EXPECT_NEAR((w(h) - w(0.0)) / h, 0.0, 1e-3);
  const double r = 2.0 - h;
  EXPECT_NEAR(w(r), 0.0, 1e-12);
  EXPECT_NEAR((w(r) - w(r - h)) / h, 0.0, 1e-8);
  // Monotone decreasing on [0, r].
  for (double d = 0; d < 2.0; d += 0.01) EXPECT_GE(w(d), w(d + 0.01));
}

TEST(WeightFunction, EllipticalDistanceUsesAxisLengths) {  // (3.13)
  const Vec3 t1(2, 0, 0), t2(0, 0.5, 0);
  EXPECT_NEAR(ellipticalDistance(t1, t2, Vec3(2, 0, 0)), 1.0, 1e-15);
  EXPECT_NEAR(ellipticalDistance(t1, t2, Vec3(0, 0.5, 0)), 1.0, 1e-15);
  EXPECT_NEAR(ellipticalDistance(t1, t2, Vec3(1, 0.25, 0)), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(ellipticalDistance(t1, t2, Vec3(0, 0, 7)), 0.0, 1e-15);  // normal offsets do not count
}

TEST(WeightFunction, ParseNames) {
  EXPECT_EQ(parseWeightKind("wendland"), WeightKind::kWendlandC2);
  EXPECT_EQ(parseWeightKind("clipped_gaussian"), WeightKind::kClippedGaussian);
  EXPECT_THROW(parseWeightKind("box"), std::invalid_argument);
}

}  // namespace
}  // namespace rc
