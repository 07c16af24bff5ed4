// Percentiles of latencies over a long run in constant memory: counts in 0.5 ms bins up to 2 s (one overflow
// bin above), as a session's end-to-end latency (device pose -> image, thesis 5.7) is summarised.
#pragma once

#include <array>
#include <cstdint>

namespace rc {

class LatencyHistogram {
 public:
  static constexpr double kBinMs = 0.5;
  static constexpr int kBins = 4000;  ///< up to 2000 ms; one more bin holds the larger ones

  /// Adds one latency [ms]; a non-finite or negative one is counted in invalid() only.
  void add(double ms);
  uint64_t count() const { return count_; }
  uint64_t invalid() const { return invalid_; }
  double max() const { return max_; }
  /// The nearest-rank p-quantile (0 < p <= 1) to within a bin: the upper edge of the bin that holds it (an
  /// overestimate by less than kBinMs; max() above the last bin); 0 for none.
  double percentile(double p) const;
  void clear() { *this = LatencyHistogram(); }

 private:
  std::array<uint32_t, kBins + 1> counts_{};
  uint64_t count_ = 0, invalid_ = 0;
  double max_ = 0;
};

}  // namespace rc
