// Timing statistics of a fixed-rate loop (the 1 kHz haptic loop of thesis 5.4.2): measured period and jitter
// (start - scheduled start) percentiles over a window of recent ticks, and missed ticks since the start.
#pragma once

#include <cstdint>
#include <vector>

namespace rc {

struct LoopTimingSummary {
  uint64_t ticks = 0;         ///< since the start
  uint64_t missed_ticks = 0;  ///< since the start: ticks that began more than one period late, or skipped
  int window_ticks = 0;       ///< ticks the percentiles below are taken over
  double period_p50 = 0, period_p99 = 0, period_max = 0;  ///< [s]
  double jitter_p50 = 0, jitter_p99 = 0, jitter_max = 0;  ///< [s]
};

/// Records ticks without allocating (fixed ring of `window` ticks); summary() sorts a copy.
class LoopTimingStats {
 public:
  /// `period` [s]: the nominal period; `window`: how many recent ticks the percentiles cover.
  LoopTimingStats(double period, int window);

  /// A tick scheduled at `scheduled` began at `started` (same clock, seconds).
  void record(double scheduled, double started);
  /// `count` scheduled ticks were skipped (the loop fell behind by whole periods): they count as missed.
  void recordSkipped(uint64_t count) { missed_ += count; }
  /// Percentiles over the ticks recorded since the last clearWindow() (at most `window` of them).
  LoopTimingSummary summary() const;
  /// Starts a new window (e.g. after each 1 Hz report); the counts since the start stay.
  void clearWindow() { window_count_ = 0; }
  double period() const { return period_; }

 private:
  double period_;
  std::vector<double> periods_, jitters_;  // rings of `window` entries
  int next_ = 0, window_count_ = 0;
  uint64_t ticks_ = 0, missed_ = 0;
  double last_start_ = 0;
  mutable std::vector<double> scratch_;
};

/// The p-quantile (0..1, nearest rank) of `values` (reordered in place); 0 for none.
double nearestRankPercentile(std::vector<double>& values, int count, double p);

}  // namespace rc
