#include "relaxed_connectivity/paint/loop_timing_stats.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rc {

LoopTimingStats::LoopTimingStats(double period, int window)
    : period_(period), periods_(size_t(std::max(window, 1)), 0.0), jitters_(periods_.size(), 0.0) {
  if (!(period > 0) || !std::isfinite(period)) throw std::invalid_argument("loop period must be > 0");
  scratch_.reserve(periods_.size());
}

void LoopTimingStats::record(double scheduled, double started) {
  const double jitter = started - scheduled;
  if (jitter > period_) ++missed_;
  // The first tick has no period: it counts the nominal one.
  periods_[size_t(next_)] = ticks_ == 0 ? period_ : started - last_start_;
  jitters_[size_t(next_)] = std::abs(jitter);
  next_ = (next_ + 1) % int(periods_.size());
  window_count_ = std::min(window_count_ + 1, int(periods_.size()));
  last_start_ = started;
  ++ticks_;
}

double nearestRankPercentile(std::vector<double>& values, int count, double p) {
  if (count <= 0) return 0;
  const int rank = std::clamp(int(std::ceil(p * count)) - 1, 0, count - 1);
  std::nth_element(values.begin(), values.begin() + rank, values.begin() + count);
  return values[size_t(rank)];
}

LoopTimingSummary LoopTimingStats::summary() const {
  LoopTimingSummary s;
  s.ticks = ticks_;
  s.missed_ticks = missed_;
  s.window_ticks = window_count_;
  const int n = window_count_;
  const int size = int(periods_.size());
  auto collect = [&](const std::vector<double>& ring) {
    scratch_.clear();
    for (int i = 0; i < n; ++i) scratch_.push_back(ring[size_t((next_ - 1 - i + size) % size)]);
  };
  collect(periods_);
  s.period_max = n ? *std::max_element(scratch_.begin(), scratch_.end()) : 0;
  s.period_p99 = nearestRankPercentile(scratch_, n, 0.99);
  s.period_p50 = nearestRankPercentile(scratch_, n, 0.50);
  collect(jitters_);
  s.jitter_max = n ? *std::max_element(scratch_.begin(), scratch_.end()) : 0;
  s.jitter_p99 = nearestRankPercentile(scratch_, n, 0.99);
  s.jitter_p50 = nearestRankPercentile(scratch_, n, 0.50);
  return s;
}

}  // namespace rc
