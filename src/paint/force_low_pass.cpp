#include "relaxed_connectivity/paint/force_low_pass.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

ForceLowPass::ForceLowPass(double window, int capacity)
    : window_(window), times_(size_t(std::max(capacity, 2)), 0.0), values_(times_.size(), Wrench::Zero()) {
  if (!(window > 0) || !std::isfinite(window))
    throw std::invalid_argument("low-pass window must be > 0 s (got " + std::to_string(window) + ")");
}

void ForceLowPass::add(double t, const Wrench& value) {
  if (count_ > 0) {
    const int last = index(count_ - 1);
    if (t == times_[size_t(last)]) {
      values_[size_t(last)] = value;
      return;
    }
    if (t < times_[size_t(last)]) count_ = 0;
  }
  // Samples whose successor begins at or before t - T no longer reach into any future window.
  while (count_ >= 2 && times_[size_t(index(1))] <= t - window_) {
    head_ = index(1);
    --count_;
  }
  if (count_ == int(times_.size())) {  // full: lose the oldest
    head_ = index(1);
    --count_;
  }
  const int slot = index(count_);
  times_[size_t(slot)] = t;
  values_[size_t(slot)] = value;
  ++count_;
}

Wrench ForceLowPass::value(double t) const {
  const double from = t - window_;
  Wrench integral = Wrench::Zero();
  for (int i = 0; i < count_; ++i) {
    // The oldest kept sample stands for everything before it once older ones were lost (see the header).
    const double begin =
        i == 0 && count_ == int(times_.size()) ? from : std::max(times_[size_t(index(i))], from);
    const double end = i + 1 < count_ ? std::min(times_[size_t(index(i + 1))], t) : t;
    if (end > begin) integral += values_[size_t(index(i))] * (end - begin);
  }
  return integral / window_;
}

}  // namespace rc
