#include "tachi/common/latency.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

using tachi::common::DurationHistogram;
using tachi::common::LatencyWindow;

TEST(LatencyWindow, NearestRankPercentilesOfTheDelays) {
  LatencyWindow w;
  for (int i = 1; i <= 100; ++i) w.add_ms(i);
  EXPECT_DOUBLE_EQ(w.percentile(50), 50.0);
  EXPECT_DOUBLE_EQ(w.percentile(99), 99.0);
  EXPECT_DOUBLE_EQ(w.percentile(100), 100.0);
}

TEST(LatencyWindow, EmptyReportsZero) { EXPECT_EQ(LatencyWindow{}.percentile(50), 0.0); }

TEST(LatencyWindow, KeepsOnlyTheLastCapacityValues) {
  LatencyWindow w(4);
  for (double v : {100.0, 100.0, 100.0, 100.0, 1.0, 2.0, 3.0, 4.0}) w.add_ms(v);
  EXPECT_EQ(w.size(), 4u);
  EXPECT_EQ(w.total(), 8u);
  EXPECT_DOUBLE_EQ(w.percentile(100), 4.0);
}

TEST(LatencyWindow, StampsConvertToMillisecondsAndNonsenseIsIgnored) {
  LatencyWindow w;
  w.add_since(1'000'000'000, 1'002'500'000);  // 2.5 ms
  w.add_since(0, 5'000'000'000);              // no stamp
  w.add_since(2'000'000'000, 1'000'000'000);  // from the future (another host's clock)
  w.add_since(1, 120'000'000'000);            // not a time
  w.add_ms(std::numeric_limits<double>::quiet_NaN());
  ASSERT_EQ(w.size(), 1u);
  EXPECT_DOUBLE_EQ(w.percentile(50), 2.5);
}

// A run's step times in constant memory: every quantile within 1 % of the exact nearest-rank one that a
// sorted vector of all values gives, over values spread across five decades.
TEST(DurationHistogram, QuantilesWithinOnePercentOfTheExactOnesInConstantMemory) {
  std::mt19937 rng(7);
  std::lognormal_distribution<double> duration(0.0, 1.5);  // median 1 ms, tails to ~100 ms and ~10 us
  DurationHistogram histogram;
  std::vector<double> all;
  for (int i = 0; i < 200'000; ++i) {
    const double ms = duration(rng);
    histogram.add_ms(ms);
    all.push_back(ms);
  }
  std::sort(all.begin(), all.end());
  ASSERT_EQ(histogram.count(), all.size());
  for (const double q : {0.01, 0.25, 0.5, 0.9, 0.95, 0.99, 0.999}) {
    const double exact = all[static_cast<std::size_t>(q * static_cast<double>(all.size() - 1) + 0.5)];
    EXPECT_NEAR(histogram.quantile(q), exact, 0.01 * exact) << "q " << q;
  }
  EXPECT_EQ(histogram.quantile(0.0), all.front());
  EXPECT_EQ(histogram.quantile(1.0), all.back());
  EXPECT_EQ(histogram.max_ms(), all.back());
}

TEST(DurationHistogram, EmptyIsZeroAndNonsenseIsNotCounted) {
  DurationHistogram histogram;
  EXPECT_EQ(histogram.quantile(0.5), 0.0);
  EXPECT_EQ(histogram.max_ms(), 0.0);
  histogram.add_ms(std::numeric_limits<double>::quiet_NaN());
  histogram.add_ms(-1.0);
  histogram.add_ms(std::numeric_limits<double>::infinity());
  EXPECT_EQ(histogram.count(), 0u);
  histogram.add_ms(2.5);
  EXPECT_EQ(histogram.quantile(0.5), 2.5);
  histogram.add_ms(1e9);  // beyond a minute: counted, and the maximum is the value itself
  EXPECT_EQ(histogram.max_ms(), 1e9);
  EXPECT_EQ(histogram.count(), 2u);
}
