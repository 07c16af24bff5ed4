// Paint exchange between brush and surface (thesis 5.6, (5.8)-(5.11)): conservation, the asymmetry of
// Fig. 5.8, mixing, the visible colour.
#include "relaxed_connectivity/paint/paint_exchange.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rc {
namespace {

PaintState paint(const Vec3& rgb, double wet_volume, double density = 1.0) {
  PaintState s;
  s.wet.rgb = rgb;
  s.wet.shininess = 10 * rgb.x();
  s.wet_volume = wet_volume;
  s.optical_density = density;
  return s;
}

TEST(PaintExchange, SymmetricRatesConserveTheWetVolume) {
  PaintState brush = paint(Vec3(0.9, 0.1, 0.1), 1.0, 2.0), surface = paint(Vec3(0.1, 0.2, 0.9), 0.37, 0.5);
  const double total = brush.wet_volume + surface.wet_volume;
  for (int step = 0; step < 1000; ++step) {
    exchangePaint(brush, surface, 3.0, 3.0, 0.7, 1.0 / 30);
    ASSERT_NEAR(brush.wet_volume + surface.wet_volume, total, 1e-12 * total) << "step " << step;
  }
  // Long contact with equal rates equalises the volumes and the colours.
  EXPECT_NEAR(brush.wet_volume, surface.wet_volume, 1e-9);
  EXPECT_LT((brush.wet.rgb - surface.wet.rgb).norm(), 1e-9);
  // The mixed colour is the volume-weighted mean of the two paints (colour "mass" is conserved too).
  const Vec3 expected = (1.0 * Vec3(0.9, 0.1, 0.1) + 0.37 * Vec3(0.1, 0.2, 0.9)) / 1.37;
  EXPECT_LT((brush.wet.rgb - expected).norm(), 1e-9);
  EXPECT_NEAR(brush.optical_density, (2.0 * 1.0 + 0.5 * 0.37) / 1.37, 1e-9);
}

TEST(PaintExchange, OneStepFollowsTheFormulas) {
  PaintState i = paint(Vec3(1, 0, 0), 0.8), j = paint(Vec3(0, 0, 1), 0.2);
  const double tau_ij = 2.0, tau_ji = 0.5, p = 1.5, dt = 0.1;
  const double di = (1 - std::exp(-tau_ij * p * dt)) * 0.8, dj = (1 - std::exp(-tau_ji * p * dt)) * 0.2;
  exchangePaint(i, j, tau_ij, tau_ji, p, dt);
  EXPECT_NEAR(i.wet_volume, 0.8 - di + dj, 1e-15);  // (5.9), (5.10)
  EXPECT_NEAR(j.wet_volume, 0.2 - dj + di, 1e-15);
  EXPECT_LT((i.wet.rgb - ((0.8 - di) * Vec3(1, 0, 0) + dj * Vec3(0, 0, 1)) / (0.8 - di + dj)).norm(), 1e-15);
  EXPECT_LT((j.wet.rgb - ((0.2 - dj) * Vec3(0, 0, 1) + di * Vec3(1, 0, 0)) / (0.2 - dj + di)).norm(), 1e-15);
}

TEST(PaintExchange, NoTransferToTheBrushKeepsItsPaintClean) {
  // Fig. 5.8 bottom: tau surface -> brush = 0. The brush only gives; its colour never changes.
  PaintState brush = paint(Vec3(0.9, 0.1, 0.1), 1.0), surface = paint(Vec3(0.1, 0.2, 0.9), 1.0);
  double previous = brush.wet_volume;
  for (int step = 0; step < 100; ++step) {
    exchangePaint(brush, surface, 3.0, 0.0, 1.0, 1.0 / 30);
    EXPECT_LT(brush.wet_volume, previous);
    previous = brush.wet_volume;
    EXPECT_EQ(brush.wet.rgb, Vec3(0.9, 0.1, 0.1));
  }
  EXPECT_NEAR(brush.wet_volume, std::exp(-3.0 * 100 / 30.0), 1e-12);  // (5.9) compounded
  EXPECT_NEAR(brush.wet_volume + surface.wet_volume, 2.0, 1e-12);
  // And with it both ways, the brush picks up the surface's blue.
  PaintState b2 = paint(Vec3(0.9, 0.1, 0.1), 1.0), s2 = paint(Vec3(0.1, 0.2, 0.9), 1.0);
  exchangePaint(b2, s2, 3.0, 3.0, 1.0, 1.0 / 30);
  EXPECT_GT(b2.wet.rgb.z(), 0.1 + 0.01);
}

TEST(PaintExchange, NothingMovesWithoutPressureAndBadInputIsRefused) {
  PaintState i = paint(Vec3(1, 0, 0), 1.0), j = paint(Vec3(0, 1, 0), 1.0);
  const PaintState i0 = i, j0 = j;
  exchangePaint(i, j, 5, 5, 0.0, 1.0);
  EXPECT_EQ(i, i0);
  EXPECT_EQ(j, j0);
  EXPECT_THROW(exchangePaint(i, j, -1, 5, 1, 1), std::invalid_argument);
  EXPECT_THROW(exchangePaint(i, j, 1, 5, std::nan(""), 1), std::invalid_argument);
}

TEST(PaintExchange, VisibleColourBlendsWetOverDryByOpticalDensity) {
  PaintState s = paint(Vec3(1, 0, 0), 0.25, 2.0);
  s.dry.rgb = Vec3(0, 0, 1);
  EXPECT_LT((visibleColour(s).rgb - Vec3(0.5, 0, 0.5)).norm(), 1e-15);  // alpha = rho V_w = 0.5 (5.8)
  s.wet_volume = 3.0;
  EXPECT_EQ(visibleColour(s).rgb, Vec3(1, 0, 0));  // alpha capped at 1
  s.wet_volume = 0;
  EXPECT_EQ(visibleColour(s).rgb, Vec3(0, 0, 1));  // dry paint is opaque
}

}  // namespace
}  // namespace rc
