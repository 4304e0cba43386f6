// The live simulator's policies without a process: the topology rate bound and keyframes, the grace for a
// stroke publisher that went away, the journal's replayed samples and the step schedule's overruns.
#include "tachi/sim/live_policies.hpp"

#include <gtest/gtest.h>

using namespace std::chrono_literals;
using tachi::sim::IdleEnd;
using tachi::sim::LiveClock;
using tachi::sim::ReplayedSamples;
using tachi::sim::StepSchedule;
using tachi::sim::StrokePublisherGrace;
using tachi::sim::TopologyRate;
using Verdict = StrokePublisherGrace::Verdict;

namespace {
const LiveClock::time_point t0{};

/// Deltas `rate` lets through when a change is offered every `every` for `span`.
int deltas_sent(TopologyRate& rate, LiveClock::duration every, LiveClock::duration span) {
  int sent = 0;
  for (auto t = t0; t < t0 + span; t += every)
    if (rate.delta_allowed(t)) {
      rate.delta_sent();
      ++sent;
    }
  return sent;
}
}  // namespace

TEST(TopologyRate, AllowsABurstOfTwoThenThirtyASecond) {
  TopologyRate burst{t0};
  int at_once = 0;
  while (burst.delta_allowed(t0) && at_once < 10) {
    burst.delta_sent();
    ++at_once;
  }
  EXPECT_EQ(at_once, 2) << "two tokens in hand";
  // A change every millisecond for 10 s: the bucket bounds it at 30/s (plus the first two).
  TopologyRate flood{t0};
  EXPECT_NEAR(deltas_sent(flood, 1ms, 10s), 2 + 299, 1);
}

TEST(TopologyRate, AThirtyHertzHandGetsADeltaWithEverySample) {
  TopologyRate rate{t0};
  constexpr auto k30Hz = std::chrono::nanoseconds(1s) / 30;
  EXPECT_EQ(deltas_sent(rate, k30Hz, 90 * k30Hz), 90);
}

TEST(TopologyRate, KeyframeAtMostOnceASecondAndOnlyAfterDeltas) {
  TopologyRate rate{t0};
  EXPECT_FALSE(rate.take_keyframe(t0 + 5s)) << "no delta went out: the first keyframe still holds";
  ASSERT_TRUE(rate.delta_allowed(t0 + 5s));
  rate.delta_sent();
  EXPECT_TRUE(rate.keyframe_owed());
  EXPECT_TRUE(rate.take_keyframe(t0 + 5s)) << "a second passed since the first keyframe";
  EXPECT_FALSE(rate.keyframe_owed());
  ASSERT_TRUE(rate.delta_allowed(t0 + 5s + 100ms));
  rate.delta_sent();
  EXPECT_FALSE(rate.take_keyframe(t0 + 5s + 999ms));
  EXPECT_TRUE(rate.take_keyframe(t0 + 6s));
  rate.final_delta_sent();
  EXPECT_TRUE(rate.keyframe_owed()) << "the last publication at shutdown sends the keyframe";
}

TEST(StrokePublisherGrace, ClosesTheStrokeOnlyWhenItsPublisherStaysAway) {
  StrokePublisherGrace grace{2s};
  EXPECT_EQ(grace.on_sample(7, true), Verdict::None);
  EXPECT_EQ(grace.tick(true, true, t0), Verdict::None);
  EXPECT_EQ(grace.tick(false, true, t0 + 1s), Verdict::PublisherGone);
  EXPECT_EQ(grace.tick(false, true, t0 + 2s), Verdict::None) << "within the grace";
  EXPECT_EQ(grace.tick(false, true, t0 + 3s + 1ms), Verdict::CloseStroke);
  EXPECT_EQ(grace.tick(false, true, t0 + 10s), Verdict::None) << "said once";
}

TEST(StrokePublisherGrace, APublisherBackWithinTheGraceKeepsTheStroke) {
  StrokePublisherGrace grace{2s};
  grace.on_sample(7, true);
  grace.tick(true, true, t0);
  ASSERT_EQ(grace.tick(false, true, t0 + 1s), Verdict::PublisherGone);
  EXPECT_EQ(grace.on_sample(7, true), Verdict::PublisherBack) << "same filter session: the restarted filter";
  EXPECT_EQ(grace.tick(true, true, t0 + 4s), Verdict::None);
}

TEST(StrokePublisherGrace, AnotherSessionsStrokeGoesOn) {
  StrokePublisherGrace grace{2s};
  grace.on_sample(7, true);
  grace.tick(true, true, t0);
  ASSERT_EQ(grace.tick(false, true, t0 + 1s), Verdict::PublisherGone);
  EXPECT_EQ(grace.on_sample(8, true), Verdict::None) << "a new filter, its own session";
  EXPECT_EQ(grace.tick(true, true, t0 + 4s), Verdict::GraceOver) << "the open stroke is session 8's";
}

TEST(StrokePublisherGrace, APublisherLeavingBetweenStrokesIsNothing) {
  StrokePublisherGrace grace{2s};
  grace.tick(true, false, t0);
  EXPECT_EQ(grace.tick(false, false, t0 + 1s), Verdict::None);
  EXPECT_EQ(grace.tick(false, true, t0 + 5s), Verdict::None);
}

TEST(IdleEnd, EndsSettleAfterTheLastHandSampleAndNeverBeforeTheFirst) {
  IdleEnd idle{1500ms, t0};
  EXPECT_FALSE(idle.over(t0 + 60s)) << "no hand sample yet: a run waits for its first";
  idle.hand_sample(t0 + 10s);
  EXPECT_FALSE(idle.over(t0 + 11s));
  EXPECT_TRUE(idle.over(t0 + 11s + 501ms));
}

TEST(IdleEnd, ASourceStartingAgainHoldsTheEndUntilItRunsThenSettleCountsFromThere) {
  IdleEnd idle{1500ms, t0};
  idle.hand_sample(t0 + 10s);
  idle.source_status("tachi-sensor", true, t0 + 10s + 300ms);  // killed mid-stroke, restarted, replaying
  EXPECT_FALSE(idle.over(t0 + 13s)) << "the restarted sensor is still starting: the run must not end in the gap";
  idle.source_status("tachi-sensor", true, t0 + 13s);  // a repeated heartbeat does not extend the hold
  idle.source_status("tachi-sensor", false, t0 + 14s);
  EXPECT_FALSE(idle.over(t0 + 15s)) << "settle counts from the moment it runs";
  idle.hand_sample(t0 + 15s);
  EXPECT_FALSE(idle.over(t0 + 16s));
  EXPECT_TRUE(idle.over(t0 + 16s + 600ms));
}

TEST(IdleEnd, ASourceThatDiesWhileStartingHoldsTheEndAtMostMaxHold) {
  IdleEnd idle{1500ms, t0, 10s};
  idle.hand_sample(t0 + 1s);
  idle.source_status("tachi-filter", true, t0 + 2s);
  EXPECT_FALSE(idle.over(t0 + 11s));
  EXPECT_TRUE(idle.over(t0 + 12s + 1ms)) << "never running: the hold ends after max_hold";
  idle.source_status("tachi-sensor", false, t0 + 12s);  // a running source that never started is nothing
  EXPECT_TRUE(idle.over(t0 + 12s + 1ms));
}

TEST(ReplayedSamples, SkipsWhatTheJournalAppliedPerSensorAndSession) {
  const ReplayedSamples replayed{{{{1, 42}, 1000}}};
  EXPECT_TRUE(replayed.already_applied(1, 42, 1000));
  EXPECT_TRUE(replayed.already_applied(1, 42, 10));
  EXPECT_FALSE(replayed.already_applied(1, 42, 1001));
  EXPECT_FALSE(replayed.already_applied(2, 42, 10)) << "another sensor";
  EXPECT_FALSE(replayed.already_applied(1, 43, 10)) << "another filter session";
  EXPECT_FALSE(ReplayedSamples{}.already_applied(1, 42, 0));
}

TEST(StepSchedule, StepsEveryPeriodAndDropsABacklogOfMoreThanFivePeriods) {
  StepSchedule schedule{10ms, t0};
  EXPECT_TRUE(schedule.due(t0));
  EXPECT_FALSE(schedule.stepped(t0 + 1ms));
  EXPECT_FALSE(schedule.due(t0 + 9ms));
  EXPECT_EQ(schedule.until_next(t0 + 4ms), 6ms);
  EXPECT_TRUE(schedule.due(t0 + 10ms));
  // A step that took 45 ms: 4.5 periods behind, so the loop catches up.
  EXPECT_FALSE(schedule.stepped(t0 + 65ms));
  EXPECT_EQ(schedule.until_next(t0 + 65ms), 0ns);
  EXPECT_EQ(schedule.overruns(), 0u);
  // One that took 100 ms: the backlog is dropped and the next step is a period from now.
  EXPECT_TRUE(schedule.stepped(t0 + 200ms));
  EXPECT_EQ(schedule.overruns(), 1u);
  EXPECT_EQ(schedule.until_next(t0 + 200ms), 10ms);
}
