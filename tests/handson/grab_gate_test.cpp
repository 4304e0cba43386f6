// The filter's side of grabbing: voice grab / release beside the cutting gate's phases.
#include "tachi/filter/gate.hpp"
#include "tachi/sensor/voice_commands.hpp"

#include <gtest/gtest.h>

namespace {

using namespace tachi::filter;

GateParams params(GateMode mode) {
  GateParams p;
  p.mode = mode;
  return p;
}

TEST(GrabGate, GrabHoldsTheClothWhateverTheDistanceAndReleaseLetsGoWithoutStartingACut) {
  for (const GateMode mode : {GateMode::Threshold, GateMode::Voice, GateMode::Either}) {
    Gate gate{params(mode)};
    EXPECT_FALSE(gate.on_voice(VoiceCommandKind::Grab).has_value());
    for (int i = 0; i < 10; ++i) {
      const GateStatus& s = gate.on_sample(0.0F);  // the hand at the cloth: no cut while grabbing
      EXPECT_EQ(s.output, GateOutput::Grabbing) << to_string(mode);
      EXPECT_EQ(s.stroke_id, 0u);
    }
    EXPECT_EQ(gate.on_sample(std::nullopt).output, GateOutput::Grabbing) << "a lost hand keeps holding";
    EXPECT_FALSE(gate.on_voice(VoiceCommandKind::Release).has_value());
    EXPECT_FALSE(gate.grabbing());
    // Letting go at the cloth must not open a threshold cut there.
    for (int i = 0; i < 10; ++i) EXPECT_EQ(gate.on_sample(0.0F).output, GateOutput::Idle) << to_string(mode);
    if (mode == GateMode::Voice) continue;
    gate.on_sample(1.0F);  // the hand went away: the threshold works again
    for (int i = 0; i < 5; ++i) gate.on_sample(0.0F);
    EXPECT_EQ(gate.status().output, GateOutput::Cutting) << to_string(mode);
  }
}

TEST(GrabGate, AGrabWhileCuttingIsRefusedWithTheReason) {
  Gate gate{params(GateMode::Either)};
  gate.on_voice(VoiceCommandKind::Start);
  ASSERT_EQ(gate.on_sample(0.0F).output, GateOutput::Cutting);
  const auto why = gate.on_voice(VoiceCommandKind::Grab);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("cutting"), std::string::npos) << *why;
  EXPECT_FALSE(gate.grabbing());
  EXPECT_EQ(gate.on_sample(0.0F).output, GateOutput::Cutting);
}

TEST(GrabGate, StartWhileGrabbingLetsGoAndCuts) {
  Gate gate{params(GateMode::Voice)};
  gate.on_voice(VoiceCommandKind::Grab);
  gate.on_voice(VoiceCommandKind::Start);
  EXPECT_FALSE(gate.grabbing());
  EXPECT_EQ(gate.on_sample(0.0F).output, GateOutput::Cutting);
}

TEST(GrabVoice, GrabAndReleasePhrasesAreConfigurableLikeStartAndStop) {
  using namespace tachi::sensor;
  const VoiceConfig c = parse_voice_config(R"({"phrases": [
      {"phrase": "start cutting", "command": "start"}, {"phrase": "stop cutting", "command": "stop"},
      {"phrase": "grab cloth", "command": "grab"}, {"phrase": "release cloth", "command": "release"}]})");
  ASSERT_EQ(c.phrases.size(), 4u);
  EXPECT_EQ(c.phrases[2].command, VoiceCommand::Grab);
  EXPECT_EQ(c.phrases[3].command, VoiceCommand::Release);
  const auto found = phrases_in_hypothesis("grab cloth release cloth", c.phrases);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(to_string(found[0].command), "grab");
  EXPECT_EQ(to_string(found[1].command), "release");
  VoiceConfig d;
  set_phrase(d, VoiceCommand::Grab, "Hold  It");
  EXPECT_EQ(d.phrases.back().phrase, "hold it");
  EXPECT_FALSE(validate(d).has_value());
  EXPECT_THROW((void)parse_voice_config(R"({"phrases": [{"phrase": "a", "command": "grasp"}]})"), std::invalid_argument);
}

}  // namespace
