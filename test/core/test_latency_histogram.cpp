// LatencyHistogram: nearest-rank percentiles to within a bin, against sorting, for a skewed distribution;
// the overflow bin, invalid values, empty and single-value histograms.
#include "relaxed_connectivity/core/latency_histogram.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace rc {
namespace {

double nearestRank(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[size_t(std::max(1.0, std::ceil(p * double(v.size())))) - 1];
}

TEST(LatencyHistogram, PercentilesAgreeWithSortingToWithinABin) {
  std::mt19937 random(3);
  std::lognormal_distribution<double> latency(std::log(25.0), 0.4);  // p50 25 ms, a long tail
  LatencyHistogram h;
  std::vector<double> all;
  for (int i = 0; i < 100000; ++i) {
    const double ms = latency(random);
    h.add(ms);
    all.push_back(ms);
  }
  EXPECT_EQ(h.count(), all.size());
  for (const double p : {0.01, 0.5, 0.9, 0.99, 0.999, 1.0}) {
    const double exact = nearestRank(all, p);
    EXPECT_GE(h.percentile(p), exact) << p;  // the upper edge of its bin
    EXPECT_LT(h.percentile(p), exact + LatencyHistogram::kBinMs + 1e-12) << p;
  }
  EXPECT_DOUBLE_EQ(h.percentile(1.0), *std::max_element(all.begin(), all.end()));
}

TEST(LatencyHistogram, OverflowInvalidEmptyAndSingle) {
  LatencyHistogram h;
  EXPECT_EQ(h.percentile(0.99), 0.0);
  h.add(12.3);
  EXPECT_DOUBLE_EQ(h.percentile(0.5), 12.3);  // never above the largest value
  h.add(std::numeric_limits<double>::quiet_NaN());
  h.add(-1.0);
  h.add(std::numeric_limits<double>::infinity());
  EXPECT_EQ(h.count(), 1u);
  EXPECT_EQ(h.invalid(), 3u);
  for (int i = 0; i < 99; ++i) h.add(5000.0);  // beyond the last bin
  EXPECT_DOUBLE_EQ(h.percentile(0.99), 5000.0);
  EXPECT_DOUBLE_EQ(h.percentile(0.01), 12.5);  // 12.3 in the bin [12, 12.5)
  h.clear();
  EXPECT_EQ(h.count(), 0u);
}

}  // namespace
}  // namespace rc
