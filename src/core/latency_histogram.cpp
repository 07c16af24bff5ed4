#include "relaxed_connectivity/core/latency_histogram.h"

#include <algorithm>
#include <cmath>

namespace rc {

void LatencyHistogram::add(double ms) {
  if (!std::isfinite(ms) || ms < 0) {
    ++invalid_;
    return;
  }
  const int bin = ms >= kBins * kBinMs ? kBins : std::min(kBins - 1, int(ms / kBinMs));
  ++counts_[size_t(bin)];
  ++count_;
  max_ = std::max(max_, ms);
}

double LatencyHistogram::percentile(double p) const {
  if (count_ == 0) return 0.0;
  const uint64_t rank = std::max<uint64_t>(1, uint64_t(std::ceil(std::clamp(p, 0.0, 1.0) * double(count_))));
  uint64_t seen = 0;
  for (int bin = 0; bin < kBins; ++bin) {
    seen += counts_[size_t(bin)];
    if (seen >= rank) return std::min(max_, (bin + 1) * kBinMs);
  }
  return max_;
}

}  // namespace rc
