// Loop timing statistics from given tick times (no real clock: these tests assert numbers, not timing).
#include <gtest/gtest.h>

#include <atomic>

#include "relaxed_connectivity/paint/fixed_rate_loop.h"
#include "relaxed_connectivity/paint/loop_timing_stats.h"

namespace rc {
namespace {

TEST(LoopTimingStats, PercentilesAndMissedTicks) {
  const double T = 1e-3;
  LoopTimingStats stats(T, 1000);
  // 100 ticks: 97 on time (+10 us), two 0.5 ms late, one 1.5 ms late (missed).
  for (int k = 0; k < 100; ++k) {
    double late = 10e-6;
    if (k == 50 || k == 70) late = 0.5e-3;
    if (k == 90) late = 1.5e-3;
    stats.record(k * T, k * T + late);
  }
  const LoopTimingSummary s = stats.summary();
  EXPECT_EQ(s.ticks, 100u);
  EXPECT_EQ(s.missed_ticks, 1u);
  EXPECT_EQ(s.window_ticks, 100);
  EXPECT_NEAR(s.jitter_p50, 10e-6, 1e-12);
  EXPECT_NEAR(s.jitter_p99, 0.5e-3, 1e-12);  // nearest rank 99 of 100
  EXPECT_NEAR(s.jitter_max, 1.5e-3, 1e-12);
  EXPECT_NEAR(s.period_p50, T, 1e-12);
  EXPECT_NEAR(s.period_max, T + 1.49e-3, 1e-12);
  stats.recordSkipped(3);
  stats.clearWindow();
  stats.record(100 * T, 100 * T);
  const LoopTimingSummary next = stats.summary();
  EXPECT_EQ(next.window_ticks, 1);
  EXPECT_EQ(next.missed_ticks, 4u);
  EXPECT_EQ(next.ticks, 101u);
}

TEST(LoopTimingStats, WindowKeepsTheLatestTicks) {
  LoopTimingStats stats(1e-3, 10);
  for (int k = 0; k < 25; ++k) stats.record(k * 1e-3, k * 1e-3 + (k < 15 ? 0.9e-3 : 0.0));
  EXPECT_EQ(stats.summary().window_ticks, 10);
  EXPECT_EQ(stats.summary().jitter_max, 0.0);
}

TEST(FixedRateLoop, UnpacedLoopRunsTicksWithVirtualTime) {
  FixedRateLoopOptions options;
  options.paced = false;
  options.rate = 1000;
  FixedRateLoop loop(options);
  std::atomic<uint64_t> ticks{0};
  std::atomic<double> last_t{-1};
  loop.start([&](uint64_t k, double t) {
    ticks = k + 1;
    last_t = t;
    return k < 499;
  });
  while (loop.running()) std::this_thread::yield();
  loop.stop();
  EXPECT_EQ(ticks.load(), 500u);
  EXPECT_EQ(last_t.load(), 0.499);
}

}  // namespace
}  // namespace rc
