#include "tachi/common/peer_wait.hpp"

#include <gtest/gtest.h>

using namespace std::chrono_literals;
using tachi::common::PeerWait;

TEST(PeerWait, WarnsEveryPeriodWhileThePeerIsAway) {
  const auto t0 = PeerWait::Clock::time_point{} + 100s;
  PeerWait wait("tachi-sim", 7, 3s, t0);
  EXPECT_FALSE(wait.check(false, t0 + 1s));
  const auto first = wait.check(false, t0 + 3s);
  ASSERT_TRUE(first);
  EXPECT_EQ(*first, "waiting for tachi-sim on domain 7 (3 s)");
  EXPECT_FALSE(wait.check(false, t0 + 4s));
  const auto second = wait.check(false, t0 + 6s);
  ASSERT_TRUE(second);
  EXPECT_EQ(*second, "waiting for tachi-sim on domain 7 (6 s)");
}

TEST(PeerWait, SilentWhileThePeerIsThereAndCountsAgainWhenItLeaves) {
  const auto t0 = PeerWait::Clock::time_point{} + 100s;
  PeerWait wait("tachi-filter", 0, 3s, t0);
  EXPECT_FALSE(wait.check(true, t0 + 10s));
  EXPECT_FALSE(wait.check(false, t0 + 11s));  // just left
  EXPECT_FALSE(wait.check(false, t0 + 13s));
  EXPECT_TRUE(wait.check(false, t0 + 14s));
}
