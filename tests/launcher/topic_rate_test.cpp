// tachi hz / bw's figures on made-up arrival times whose rate, jitter and sizes are known.
#include "tachi/launcher/topic_rate.hpp"

#include <gtest/gtest.h>

#include <random>

using tachi::launcher::TopicRateWindow;

TEST(TopicRate, ARegular30HzTopicIs30HzWithoutJitter) {
  TopicRateWindow w;
  EXPECT_FALSE(w.rate()) << "one sample has no rate";
  for (int i = 0; i < 91; ++i) w.add(1'000'000'000LL + i * 33'333'333LL, 200);
  const auto r = w.rate();
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->rate_hz, 30.0, 1e-3);
  EXPECT_NEAR(r->jitter_s, 0.0, 1e-9);
  EXPECT_NEAR(r->bytes_per_s, 6000.0, 1.0) << "200 B at 30 Hz";
  EXPECT_EQ(r->samples, 91u);
  EXPECT_EQ(tachi::launcher::hz_report(*r).substr(0, 20), "average rate: 30.000");
}

TEST(TopicRate, JitterIsTheStandardDeviationOfTheIntervals) {
  // Intervals alternate 20 ms and 40 ms: mean 30 ms, standard deviation 10 ms; sizes 100 and 300 B.
  TopicRateWindow w;
  std::int64_t t = 0;
  for (int i = 0; i < 101; ++i) {
    w.add(t, i % 2 ? 300 : 100);
    t += (i % 2 ? 40 : 20) * 1'000'000LL;
  }
  const auto r = w.rate();
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->rate_hz, 1.0 / 0.030, 1e-6);
  EXPECT_NEAR(r->jitter_s, 0.010, 1e-9);
  EXPECT_NEAR(r->min_interval_s, 0.020, 1e-12);
  EXPECT_NEAR(r->max_interval_s, 0.040, 1e-12);
  EXPECT_EQ(r->min_bytes, 100);
  EXPECT_EQ(r->max_bytes, 300);
}

TEST(TopicRate, TheWindowForgetsOldSamples) {
  // 10 Hz for a while, then 50 Hz: a 20-sample window sees only the 50 Hz part.
  TopicRateWindow w(20);
  std::int64_t t = 0;
  for (int i = 0; i < 50; ++i) w.add(t += 100'000'000LL, 10);
  for (int i = 0; i < 40; ++i) w.add(t += 20'000'000LL, 10);
  EXPECT_NEAR(w.rate()->rate_hz, 50.0, 1e-6);
  EXPECT_EQ(w.rate()->samples, 20u);
}

TEST(TopicRate, RandomArrivalsAroundARateAverageToIt) {
  // Seeds 1-20: arrivals 25 ms +- uniform 5 ms; the rate is 40 Hz within the noise of 400 intervals.
  for (unsigned seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> noise(-5e6, 5e6);
    TopicRateWindow w;
    for (int i = 0; i < 401; ++i) w.add(static_cast<std::int64_t>(i * 25e6 + noise(rng)), 1);
    EXPECT_NEAR(w.rate()->rate_hz, 40.0, 0.1) << "seed " << seed;
  }
}
