// The 1/60 s moving average of thesis 5.4.2 as an exact box filter over zero-order-held samples.
#include <gtest/gtest.h>

#include <random>

#include "relaxed_connectivity/paint/force_low_pass.h"

namespace rc {
namespace {

Wrench constantWrench(double v) {
  return Wrench::Constant(v);
}

TEST(ForceLowPass, StepReachesTheStepAfterExactlyTheWindowAndNotBefore) {
  const double T = 1.0 / 60.0;
  const double step_time = 0.5;
  // Regular 1 kHz samples, then irregular ones: the response depends on the step time only.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> gap(1e-4, 3e-3);
  for (bool irregular : {false, true}) {
    ForceLowPass filter(T);
    double t = 0;
    std::vector<double> times;
    while (t < 0.6) {
      times.push_back(t);
      t += irregular ? gap(random) : 1e-3;
    }
    bool step_added = false;
    for (double ti : times) {
      if (!step_added && ti >= step_time) {
        filter.add(step_time, constantWrench(2.0));  // the step itself is a sample
        step_added = true;
      }
      if (ti == step_time) continue;
      filter.add(ti, constantWrench(ti >= step_time ? 2.0 : 0.0));
      const double y = filter.value(ti)[0];
      if (ti < step_time) {
        EXPECT_EQ(y, 0.0);
      } else if (ti < step_time + T - 1e-9) {
        EXPECT_NEAR(y, 2.0 * (ti - step_time) / T, 1e-9) << ti;  // the ramp of a box filter
        EXPECT_LT(y, 2.0) << ti;
      } else {
        EXPECT_NEAR(y, 2.0, 1e-12) << ti;
      }
    }
    // Exactly at step + T (queried between samples) and just before it.
    EXPECT_NEAR(filter.value(0.6)[3], 2.0, 1e-12);
  }
  ForceLowPass filter(T);
  filter.add(0.0, constantWrench(0));
  filter.add(step_time, constantWrench(1));
  EXPECT_NEAR(filter.value(step_time + T)[0], 1.0, 1e-12);
  EXPECT_NEAR(filter.value(step_time + T - 1e-6)[0], 1.0 - 1e-6 / T, 1e-9);
  EXPECT_LT(filter.value(step_time + T - 1e-6)[0], 1.0);
}

TEST(ForceLowPass, AveragesAStaircase) {
  ForceLowPass filter(0.01);
  filter.add(0.000, constantWrench(1));
  filter.add(0.004, constantWrench(3));
  filter.add(0.007, constantWrench(-2));
  // Over [0.002, 0.012]: 1 * 0.002 + 3 * 0.003 + (-2) * 0.005 = 0.001 -> 0.1.
  EXPECT_NEAR(filter.value(0.012)[5], 0.1, 1e-12);
  // A repeated time replaces the sample; an earlier time restarts the filter.
  filter.add(0.007, constantWrench(4));
  EXPECT_NEAR(filter.value(0.012)[0], (0.002 + 0.009 + 4 * 0.005) / 0.01, 1e-12);
  filter.add(0.001, constantWrench(5));
  EXPECT_EQ(filter.size(), 1);
  EXPECT_NEAR(filter.value(0.011)[0], 5.0, 1e-12);
}

TEST(ForceLowPass, KeepsOnlyWhatTheWindowNeeds) {
  ForceLowPass filter(1.0 / 60.0, 64);
  for (int k = 0; k < 10000; ++k) filter.add(k * 1e-3, constantWrench(k % 2));
  EXPECT_LE(filter.size(), 18);  // 1/60 s of 1 kHz samples plus the one reaching back
  EXPECT_NEAR(filter.value(9.999)[0], 0.5, 1.0 / 16.0);
  EXPECT_THROW(ForceLowPass(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rc
