// The run's loop-timing histogram (motormix run --timing-report) against
// percentiles of the same values, sorted.

#include "node/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace motormix::test {
namespace {

// The nearest-rank percentile of `sorted`, rounded up to the microsecond:
// what the histogram promises.
double nearest_rank_us(const std::vector<double>& sorted, double fraction) {
  const auto rank =
      static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(sorted.size())));
  return std::ceil(sorted[std::max<std::size_t>(rank, 1) - 1]);
}

TEST(LatencyHistogram, PercentilesAreTheSortedValuesRoundedUp) {
  std::mt19937_64 rng(20261203);
  std::lognormal_distribution<double> late(2.5, 0.8);  // a few to a few hundred microseconds
  for (const int n : {1, 2, 7, 100, 1001, 20000}) {
    node::LatencyHistogram h(2000);
    std::vector<double> values;
    for (int i = 0; i < n; ++i) {
      const double v = std::min(late(rng), 1999.0);
      values.push_back(v);
      h.add(v, i);
    }
    std::sort(values.begin(), values.end());
    for (const double f : {0.01, 0.5, 0.9, 0.99, 0.999, 1.0}) {
      EXPECT_EQ(h.percentile(f), nearest_rank_us(values, f)) << "n " << n << " fraction " << f;
    }
    EXPECT_EQ(h.max(), values.back());
    EXPECT_EQ(h.min(), values.front());
    EXPECT_EQ(h.count(), n);
  }
}

TEST(LatencyHistogram, AFractionalValueReadsAsTheNextMicrosecond) {
  node::LatencyHistogram h(100);
  h.add(5.7, 1);
  EXPECT_EQ(h.percentile(0.5), 6.0);  // 5.7 does not exceed 6, and does exceed 5
  h.add(5.0, 2);
  EXPECT_EQ(h.percentile(0.5), 5.0);
  EXPECT_EQ(h.max_at_us(), 1);
}

TEST(LatencyHistogram, ValuesPastTheRangeShareTheLastBinAndKeepTheirMaximum) {
  node::LatencyHistogram h(100);
  h.add(5000.0, 42);
  EXPECT_EQ(h.percentile(0.5), 100.0);
  EXPECT_EQ(h.max(), 5000.0);
  EXPECT_EQ(h.max_at_us(), 42);
  EXPECT_EQ(node::LatencyHistogram().percentile(0.99), 0.0);  // empty
}

}  // namespace
}  // namespace motormix::test
