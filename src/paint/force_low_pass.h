// The low-pass filter of the haptic forces (thesis 5.4.2): "averages the forces over the last 1/60 second".
// Exact continuous-time box filter over zero-order-held samples: a sample holds until the next one, and the
// output at time t is (1/T) * integral of that staircase over [t - T, t] (zero before the first sample). A
// step therefore reaches its value after exactly T, whatever the sample times.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rc {

/// Force (0..2) and torque (3..5).
using Wrench = Eigen::Matrix<double, 6, 1>;

class ForceLowPass {
 public:
  /// `window` T [s]; `capacity`: samples kept (fixed, no allocation after construction). More samples than
  /// that inside one window (above capacity / T samples per second) lose the oldest: the oldest kept one is
  /// then held back to t - T.
  explicit ForceLowPass(double window = 1.0 / 60.0, int capacity = 256);

  /// Adds the sample `value` from time `t` [s] on. A time equal to the last one replaces it; an earlier time
  /// (a restarted clock) clears the filter first.
  void add(double t, const Wrench& value);
  /// The average over [t - T, t]; t at or after the last sample.
  Wrench value(double t) const;
  void reset() { count_ = 0; }
  double window() const { return window_; }
  int size() const { return count_; }

 private:
  int index(int i) const { return (head_ + i) % int(times_.size()); }  // i-th oldest

  double window_;
  std::vector<double> times_;
  std::vector<Wrench> values_;
  int head_ = 0, count_ = 0;
};

}  // namespace rc
