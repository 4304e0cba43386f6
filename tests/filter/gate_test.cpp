#include "tachi/filter/gate.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace tachi::filter {
namespace {

using P = GatePhase;
using E = GateEvent;

// Every transition of the gate, one matrix per mode: rows are phases (in enum order), columns are
// events in the order Near, Between, Far, Lost, VoiceStart, VoiceStop, DwellElapsed.
using Row = std::array<P, kGateEventCount>;
using Table = std::array<Row, kGatePhaseCount>;
constexpr P I = P::Idle, A = P::Arming, T = P::CuttingByThreshold, D = P::Disarming, V = P::CuttingByVoice,
            H = P::HeldOff;

constexpr Table kEither{{
    //        Near Betw Far Lost VStart VStop Dwell
    /* I */ {{A, I, I, I, V, I, I}},
    /* A */ {{A, A, I, I, V, H, T}},
    /* T */ {{T, T, D, D, T, H, T}},
    /* D */ {{T, T, D, D, D, H, I}},
    /* V */ {{V, V, V, V, V, H, V}},
    /* H */ {{H, H, I, I, V, H, H}},
}};
constexpr Table kThreshold{{
    /* I */ {{A, I, I, I, I, I, I}},
    /* A */ {{A, A, I, I, A, A, T}},
    /* T */ {{T, T, D, D, T, T, T}},
    /* D */ {{T, T, D, D, D, D, I}},
    /* V */ {{V, V, V, V, V, V, V}},
    /* H */ {{H, H, I, I, H, H, H}},
}};
constexpr Table kVoice{{
    /* I */ {{I, I, I, I, V, I, I}},
    /* A */ {{A, A, A, A, V, I, A}},
    /* T */ {{T, T, T, T, T, I, T}},
    /* D */ {{D, D, D, D, D, I, D}},
    /* V */ {{V, V, V, V, V, I, V}},
    /* H */ {{H, H, H, H, V, H, H}},
}};

void check_table(GateMode mode, const Table& table) {
  for (int p = 0; p < kGatePhaseCount; ++p)
    for (int e = 0; e < kGateEventCount; ++e) {
      const auto phase = static_cast<P>(p);
      const auto event = static_cast<E>(e);
      EXPECT_EQ(next_phase(mode, phase, event), table[p][e])
          << to_string(mode) << ": " << to_string(phase) << " + " << to_string(event) << " -> "
          << to_string(next_phase(mode, phase, event)) << ", expected " << to_string(table[p][e]);
    }
}

TEST(GateTransitions, EitherModeMatchesTheTable) { check_table(GateMode::Either, kEither); }
TEST(GateTransitions, ThresholdModeMatchesTheTable) { check_table(GateMode::Threshold, kThreshold); }
TEST(GateTransitions, VoiceModeMatchesTheTable) { check_table(GateMode::Voice, kVoice); }

TEST(GateTransitions, CuttingPhasesAreExactlyTheOpenOnes) {
  EXPECT_FALSE(is_cutting(P::Idle));
  EXPECT_FALSE(is_cutting(P::Arming));
  EXPECT_TRUE(is_cutting(P::CuttingByThreshold));
  EXPECT_TRUE(is_cutting(P::Disarming));
  EXPECT_TRUE(is_cutting(P::CuttingByVoice));
  EXPECT_FALSE(is_cutting(P::HeldOff));
}

GateParams threshold_params() {
  GateParams p;
  p.mode = GateMode::Threshold;
  p.enter_distance_m = 0.05F;
  p.exit_distance_m = 0.08F;
  p.enter_dwell_samples = 2;
  p.exit_dwell_samples = 3;
  return p;
}

TEST(Gate, OpensAfterTheEnterDwellAndCountsStrokes) {
  Gate g{threshold_params()};
  EXPECT_EQ(g.on_sample(0.2F).output, GateOutput::Idle);
  EXPECT_EQ(g.on_sample(0.01F).phase, P::Arming);
  const auto& s = g.on_sample(0.01F);
  EXPECT_EQ(s.output, GateOutput::Cutting);
  EXPECT_EQ(s.stroke_id, 1U);
  EXPECT_EQ(s.opened_by, GateSource::Threshold);
  EXPECT_EQ(s.closed_by, GateSource::None);
}

TEST(Gate, ABriefTouchDoesNotOpen) {
  Gate g{threshold_params()};
  g.on_sample(0.01F);
  EXPECT_EQ(g.on_sample(0.2F).phase, P::Idle);
  EXPECT_EQ(g.status().stroke_id, 0U);
}

TEST(Gate, FluctuationAtTheThresholdsKeepsOneStroke) {
  Gate g{threshold_params()};
  // Start: the hand wobbles across the enter distance; end: it wobbles across the exit distance
  // for fewer samples than the exit dwell before leaving for good.
  const std::vector<float> d{0.2F,  0.06F, 0.04F, 0.06F, 0.04F, 0.03F, 0.02F, 0.09F, 0.07F,
                             0.09F, 0.09F, 0.06F, 0.02F, 0.09F, 0.10F, 0.12F, 0.2F,  0.3F};
  for (float x : d) g.on_sample(x);
  EXPECT_EQ(g.status().stroke_id, 1U);
  EXPECT_EQ(g.status().output, GateOutput::Idle);
  EXPECT_EQ(g.status().closed_by, GateSource::Threshold);
}

TEST(Gate, ClosesAfterTheExitDwellAndReopensAsANewStroke) {
  Gate g{threshold_params()};
  g.on_sample(0.0F);
  g.on_sample(0.0F);
  // Beyond reach, the stroke stays open but holds: the leaving hand must not cut.
  EXPECT_EQ(g.on_sample(0.5F).output, GateOutput::Holding);  // 1 of 3
  EXPECT_EQ(g.on_sample(0.5F).output, GateOutput::Holding);  // 2 of 3
  EXPECT_EQ(g.on_sample(0.5F).output, GateOutput::Idle);     // 3 of 3: closed
  g.on_sample(0.0F);
  EXPECT_EQ(g.on_sample(0.0F).stroke_id, 2U);
}

TEST(Gate, AShortDropoutDoesNotEndTheStrokeButALongOneDoes) {
  Gate g{threshold_params()};
  g.on_sample(0.0F);
  g.on_sample(0.0F);
  g.on_sample(std::nullopt);
  g.on_sample(std::nullopt);
  EXPECT_EQ(g.on_sample(0.01F).output, GateOutput::Cutting);
  EXPECT_EQ(g.status().stroke_id, 1U);
  for (int i = 0; i < 3; ++i) g.on_sample(std::nullopt);
  EXPECT_EQ(g.status().output, GateOutput::Idle);
}

TEST(Gate, VoiceModeIgnoresDistance) {
  GateParams p = threshold_params();
  p.mode = GateMode::Voice;
  Gate g{p};
  g.on_sample(0.0F);
  g.on_sample(0.0F);
  EXPECT_EQ(g.status().output, GateOutput::Idle);
  g.on_voice(VoiceCommandKind::Start);
  EXPECT_EQ(g.on_sample(1.0F).output, GateOutput::Cutting);
  EXPECT_EQ(g.status().opened_by, GateSource::Voice);
  g.on_voice(VoiceCommandKind::Stop);
  EXPECT_EQ(g.on_sample(0.0F).output, GateOutput::Idle);
  EXPECT_EQ(g.status().closed_by, GateSource::Voice);
  EXPECT_EQ(g.status().stroke_id, 1U);
}

TEST(Gate, EitherModeHoldsOffTheThresholdAfterAVoiceStop) {
  GateParams p = threshold_params();
  p.mode = GateMode::Either;
  Gate g{p};
  g.on_sample(0.0F);
  g.on_sample(0.0F);
  EXPECT_EQ(g.status().opened_by, GateSource::Threshold);
  g.on_voice(VoiceCommandKind::Stop);
  // The hand is still at the cloth: the threshold must not reopen at once.
  for (int i = 0; i < 5; ++i) EXPECT_EQ(g.on_sample(0.0F).output, GateOutput::Idle);
  EXPECT_EQ(g.status().closed_by, GateSource::Voice);
  g.on_sample(0.5F);  // away from the cloth
  g.on_sample(0.0F);
  EXPECT_EQ(g.on_sample(0.0F).stroke_id, 2U);
  EXPECT_EQ(g.status().opened_by, GateSource::Threshold);
}

TEST(Gate, EitherModeVoiceStrokeIgnoresTheThreshold) {
  GateParams p = threshold_params();
  p.mode = GateMode::Either;
  Gate g{p};
  g.on_voice(VoiceCommandKind::Start);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(g.on_sample(0.5F).output, GateOutput::Cutting);
  EXPECT_EQ(g.status().opened_by, GateSource::Voice);
}

TEST(GateParams, ValidationRequiresHysteresis) {
  GateParams p;
  p.exit_distance_m = p.enter_distance_m;
  ASSERT_TRUE(validate(p).has_value());
  EXPECT_NE(validate(p)->find("exit_distance_m"), std::string::npos);
  p = {};
  p.enter_dwell_samples = 0;
  EXPECT_TRUE(validate(p).has_value());
  EXPECT_FALSE(validate(GateParams{}).has_value());
}

}  // namespace
}  // namespace tachi::filter
