#include "tachi/common/latency.hpp"
#include <limits>

#include <gtest/gtest.h>

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
