#include "tachi/filter/stroke_filter.hpp"

#include "synthetic_hands.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <set>

namespace tachi::filter {
namespace {

std::set<std::uint32_t> cut_strokes(StrokeFilter& f, const std::vector<HandSample>& hands) {
  std::set<std::uint32_t> ids;
  for (const auto& h : hands) {
    const auto s = f.on_hand(h);
    if (s.gate == GateOutput::Cutting) ids.insert(s.stroke_id);
  }
  return ids;
}

TEST(StrokeFilter, PushTowardTheClothAndBackIsOneStroke) {
  for (unsigned seed = 1; seed <= 10; ++seed) {
    StrokeFilter f{FilterConfig{}};
    const auto strokes = cut_strokes(f, testing::push_and_back(seed));
    EXPECT_EQ(strokes, std::set<std::uint32_t>{1}) << "seed " << seed;
  }
}

// The seed paper's gate (one threshold, no dwell, no smoothing) fragments the same push: this is what
// the hysteresis, the dwell and the smoothing fix, and it shows the test above can fail.
TEST(StrokeFilter, TheSeedsSingleThresholdFragmentsThePush) {
  FilterConfig seed_gate;
  seed_gate.smoother.kind = SmootherKind::None;
  seed_gate.gate.enter_distance_m = 0.05F;
  seed_gate.gate.exit_distance_m = 0.0500001F;
  seed_gate.gate.enter_dwell_samples = 1;
  seed_gate.gate.exit_dwell_samples = 1;
  std::size_t fragmented = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    StrokeFilter f{seed_gate};
    if (cut_strokes(f, testing::push_and_back(seed)).size() > 1) ++fragmented;
  }
  EXPECT_GE(fragmented, 8U);
}

// A cut along the cloth, then the hand pulled out diagonally (as in recordings/straight_cut): the
// samples of the pull-out must not cut, even while still within the exit distance.
std::vector<GateOutput> cut_then_pull_out(float max_normal_speed_mps) {
  FilterConfig config;
  config.gate.max_normal_speed_mps = max_normal_speed_mps;
  StrokeFilter f{config};
  std::vector<GateOutput> pull_out;
  for (int i = 0; i < 40; ++i) {
    HandSample h;
    h.frame = static_cast<std::uint64_t>(i);
    h.stamp_ns = static_cast<std::int64_t>(i) * 33'333'333LL;
    h.tracked = true;
    const bool leaving = i >= 30;
    const float out = leaving ? 0.02F * static_cast<float>(i - 29) : 0.0F;  // 0.6 m/s away from the cloth
    h.position_m = {-0.3F + 0.02F * static_cast<float>(std::min(i, 30)) + out, out, 0.98F + out};
    const auto s = f.on_hand(h);
    if (leaving) pull_out.push_back(s.gate);
  }
  return pull_out;
}

TEST(StrokeFilter, AHandPulledOutOfTheClothHoldsInsteadOfCutting) {
  // The smoothed speed needs one sample to see the motion: only the first pull-out sample may cut.
  const auto with = cut_then_pull_out(0.25F);
  for (std::size_t i = 1; i < with.size(); ++i) EXPECT_NE(with[i], GateOutput::Cutting) << "pull-out sample " << i;
  const auto without = cut_then_pull_out(0.0F);
  EXPECT_EQ(without[1], GateOutput::Cutting) << "without the speed limit the pull-out cuts (the seed's failure)";
}

TEST(StrokeFilter, OutputIsInTheWorldFrameAndFlagsTheHandOutsideTheCloth) {
  StrokeFilter f{FilterConfig{}};
  HandSample h;
  h.tracked = true;
  h.position_m = {-0.2F, -0.1F, 1.1F};  // user's right, up, 10 cm in front of the cloth
  const auto s = f.on_hand(h);
  EXPECT_TRUE(s.position_m.isApprox(Eigen::Vector3f(0.2F, 0.1F, 0.1F), 1e-5F));
  EXPECT_TRUE(s.camera_position_m.isApprox(h.position_m));
  EXPECT_NEAR(s.distance_to_cloth_m, 0.1F, 1e-5F);
  EXPECT_FALSE(s.hand_outside_cloth);
  h.position_m = {-0.7F, 0.0F, 1.1F};
  h.stamp_ns = 33'000'000;
  StrokeFilter g{FilterConfig{}};
  EXPECT_TRUE(g.on_hand(h).hand_outside_cloth);
}

TEST(StrokeFilter, ClothStateReplacesTheRestPlane) {
  StrokeFilter f{FilterConfig{}};
  // A cloth bulging toward the user by 0.2 m under the hand.
  const std::vector<float> xyz{0.0F, 0.0F, 0.2F, 0.1F, 0.0F, 0.0F};
  f.on_cloth_state(xyz);
  HandSample h;
  h.tracked = true;
  h.position_m = {0.0F, 0.0F, 1.22F};  // world z = 0.22
  EXPECT_NEAR(f.on_hand(h).distance_to_cloth_m, 0.02F, 1e-5F);
}

TEST(StrokeFilter, ALostHandResetsTheSmoother) {
  FilterConfig c;
  c.smoother.kind = SmootherKind::MovingAverage;
  c.smoother.moving_average_window = 9;
  StrokeFilter f{c};
  HandSample h;
  h.tracked = true;
  for (int i = 0; i < 5; ++i) {
    h.stamp_ns = i * 33'000'000LL;
    h.position_m = {0.0F, 0.0F, 1.5F};
    f.on_hand(h);
  }
  HandSample lost = h;
  lost.tracked = false;
  lost.stamp_ns += 33'000'000;
  const auto stale = f.on_hand(lost);
  EXPECT_FALSE(stale.tracked);
  EXPECT_TRUE(stale.camera_position_m.isApprox(Eigen::Vector3f(0.0F, 0.0F, 1.5F)));  // where it was last seen
  EXPECT_EQ(stale.distance_to_cloth_m, -1.0F);
  h.stamp_ns = lost.stamp_ns + 33'000'000;
  h.position_m = {0.3F, 0.0F, 1.2F};
  EXPECT_TRUE(f.on_hand(h).camera_position_m.isApprox(h.position_m));
}

TEST(StrokeFilter, VoiceGatingProducesOneStrokePerStartStop) {
  FilterConfig c;
  c.gate.mode = GateMode::Voice;
  StrokeFilter f{c};
  HandSample h;
  h.tracked = true;
  h.position_m = {0.0F, 0.0F, 1.4F};
  EXPECT_EQ(f.on_hand(h).gate, GateOutput::Idle);
  f.on_voice(VoiceCommandKind::Start);
  auto s = f.on_hand(h);
  EXPECT_EQ(s.gate, GateOutput::Cutting);
  EXPECT_EQ(s.opened_by, GateSource::Voice);
  f.on_voice(VoiceCommandKind::Stop);
  s = f.on_hand(h);
  EXPECT_EQ(s.gate, GateOutput::Idle);
  EXPECT_EQ(s.closed_by, GateSource::Voice);
  EXPECT_EQ(s.stroke_id, 1U);
}

// One stroke row 2-100 m away (a hand cannot get there in 1/30 s) is an outlier: counted, not
// published as a hand, and the stroke neither jumps to it nor comes back from it: it stays one stroke
// and no published position is more than a few cm from the push's path.
TEST(StrokeFilter, ARowMetresAwayIsAnOutlierAndNeverCutAlong) {
  for (const float away_m : {2.0F, 10.0F, 100.0F}) {
    auto hands = testing::push_and_back(3);
    hands[60].position_m.x() += away_m;  // mid-stroke (the hand is within reach from ~frame 40 to ~80)
    StrokeFilter f{FilterConfig{}};
    std::set<std::uint32_t> cutting;
    for (const auto& h : hands) {
      const auto s = f.on_hand(h);
      if (s.gate == GateOutput::Cutting) cutting.insert(s.stroke_id);
      if (s.tracked) {
        EXPECT_LT(std::abs(s.position_m.x()), 0.3F) << away_m << " m, frame " << h.frame;
      }
      EXPECT_EQ(s.outlier, h.frame == 60) << away_m << " m, frame " << h.frame;
      if (h.frame == 60) {
        EXPECT_FALSE(s.tracked);
      }
    }
    EXPECT_EQ(f.outliers(), 1U) << away_m << " m";
    EXPECT_EQ(cutting, std::set<std::uint32_t>{1}) << away_m << " m";
  }
}

// A 60 m/s jump (2 m in one frame) that the sensor then holds: refused until the run agrees with itself
// (outliers.reanchor_samples, 3), never cut along: every published cutting step stays under 10 m/s.
TEST(StrokeFilter, ASixtyMetrePerSecondJumpIsRefusedAndNeverCutAlong) {
  auto hands = testing::push_and_back(5);
  for (std::size_t i = 60; i < hands.size(); ++i) hands[i].position_m.y() += 2.0F;  // 2 m in 1/30 s = 60 m/s
  StrokeFilter f{FilterConfig{}};
  std::optional<StrokeSample> previous_cut;
  for (const auto& h : hands) {
    const auto s = f.on_hand(h);
    if (s.tracked && s.gate == GateOutput::Cutting) {
      if (previous_cut && previous_cut->stroke_id == s.stroke_id) {
        const float dt = static_cast<float>(s.stamp_ns - previous_cut->stamp_ns) * 1e-9F;
        EXPECT_LE((s.position_m - previous_cut->position_m).norm() / dt, 10.0F) << "frame " << s.frame;
      }
      previous_cut = s;
    }
  }
  EXPECT_EQ(f.outliers(), 2U);  // frames 60 and 61; frame 62 agrees with both and is taken as the hand
}

// A real fast hand is not refused: a 5 m/s swipe (17 cm a frame) across the cloth, and a 3 m/s one.
TEST(StrokeFilter, AFastSwipeIsNotAnOutlier) {
  for (const float speed : {3.0F, 5.0F, 9.0F}) {
    StrokeFilter f{FilterConfig{}};
    for (int i = 0; i < 30; ++i) {
      HandSample h;
      h.frame = static_cast<std::uint64_t>(i);
      h.stamp_ns = 1'000'000'000LL + i * 33'333'333LL;
      h.position_m = {-1.0F + speed * static_cast<float>(i) / 30.0F, 0.0F, 1.0F};
      h.tracked = true;
      EXPECT_TRUE(f.on_hand(h).tracked) << speed << " m/s, frame " << i;
    }
    EXPECT_EQ(f.outliers(), 0U) << speed << " m/s";
  }
}

// A faulty first sample does not lock the real hand out: three agreeing samples re-anchor.
TEST(StrokeFilter, AWrongFirstSampleDoesNotLockTheHandOut) {
  auto hands = testing::push_and_back(2);
  hands[0].position_m.z() = 15.0F;
  StrokeFilter f{FilterConfig{}};
  std::vector<bool> tracked;
  for (const auto& h : hands) tracked.push_back(f.on_hand(h).tracked);
  EXPECT_EQ(f.outliers(), 2U);
  EXPECT_TRUE(tracked[3]);
  EXPECT_TRUE(tracked.back());
}

}  // namespace
}  // namespace tachi::filter
