// The keyword spotter on real speech (pocketsphinx-testdata) and on flite-synthesised commands.
#include "tachi/sensor/voice_spotter.hpp"

#include "voice_fixture.hpp"

#include <gtest/gtest.h>

namespace tachi::sensor {
namespace {

using testing::kTestData;

std::vector<std::string> phrases_of(const std::vector<VoiceDetection>& d) {
  std::vector<std::string> out;
  for (const auto& x : d) out.push_back(x.phrase);
  return out;
}

TEST(VoiceSpotter, RealSpeechGoForwardIsSpotted) {
  VoiceConfig c;
  set_phrase(c, VoiceCommand::Start, "go forward");
  const auto audio = read_raw_file(kTestData + "/goforward.raw");  // "go forward ten meters"
  const auto found = spot_commands(c, audio.samples);
  EXPECT_EQ(phrases_of(found), std::vector<std::string>{"go forward"});
  ASSERT_EQ(found.size(), 1U);
  EXPECT_EQ(found[0].command, VoiceCommand::Start);
  EXPECT_GT(found[0].time_s, 0.5);
  EXPECT_LT(found[0].time_s, 2.0);
}

TEST(VoiceSpotter, RealSpeechAPhraseRightAfterAnotherIsSpottedToo) {
  // "go forward ten meters": the stop phrase starts as the start phrase ends. Restarting the
  // decoder after the first hit without replaying the audio it held lost the second (issue 14).
  VoiceConfig c;
  set_phrase(c, VoiceCommand::Start, "go forward");
  set_phrase(c, VoiceCommand::Stop, "ten meters");
  const auto found = spot_commands(c, read_raw_file(kTestData + "/goforward.raw").samples);
  EXPECT_EQ(phrases_of(found), (std::vector<std::string>{"go forward", "ten meters"}));
  ASSERT_EQ(found.size(), 2U);
  EXPECT_EQ(found[1].command, VoiceCommand::Stop);
  EXPECT_GT(found[1].time_s, found[0].time_s);
  EXPECT_LT(found[1].time_s, 3.0);
}

TEST(VoiceSpotter, RealSpeechTwoWordPhrasesAreSpottedInOrder) {
  // cards/005.wav says "eight of spades four of clubs seven of hearts".
  VoiceConfig c;
  c.phrases = {{"of spades", VoiceCommand::Stop, 1e-20},
               {"of clubs", VoiceCommand::Start, 1e-20},
               {"of hearts", VoiceCommand::Stop, 1e-20}};
  const auto audio = read_wav_file(kTestData + "/cards/005.wav");
  EXPECT_EQ(phrases_of(spot_commands(c, audio.samples)), (std::vector<std::string>{"of spades", "of clubs", "of hearts"}));
}

TEST(VoiceSpotter, NoFalseAlarmsOnLibriVoxReadingWithTheDefaultPhrases) {
  const VoiceConfig c;
  for (const auto& clip : testing::librivox_clips()) {
    const auto audio = read_wav_file(clip);
    EXPECT_TRUE(spot_commands(c, audio.samples).empty()) << clip;
  }
}

TEST(VoiceSpotter, SynthesisedCommandsAreSpottedInOrderBetweenPausesAndNoise) {
  const auto start = testing::flite_say("start cutting");
  const auto stop = testing::flite_say("stop cutting");
  testing::Sequence seq{3};
  seq.pause(0.7);
  seq.say("start cutting", start);
  seq.pause(1.3);
  seq.say("stop cutting", stop, 0.6);
  seq.pause(0.5);
  seq.say("start cutting", start, 0.8);
  seq.pause(2.0);
  seq.say("stop cutting", stop);
  seq.pause(0.8);
  seq.noise(150.0);
  const auto found = spot_commands(VoiceConfig{}, seq.samples());
  ASSERT_EQ(phrases_of(found), (std::vector<std::string>{"start cutting", "stop cutting", "start cutting", "stop cutting"}));
  for (std::size_t i = 0; i < found.size(); ++i) {
    // Reported at the end of the 32 ms block in which the decoder saw the phrase end.
    EXPECT_GT(found[i].time_s, seq.placed()[i].begin_s) << i;
    EXPECT_LT(found[i].time_s, seq.placed()[i].end_s + 0.5) << i;
  }
  EXPECT_EQ(found[0].command, VoiceCommand::Start);
  EXPECT_EQ(found[1].command, VoiceCommand::Stop);
}

TEST(VoiceSpotter, UnknownWordsAndMissingModelsAreClearErrors) {
  VoiceConfig c;
  set_phrase(c, VoiceCommand::Start, "start qzxqzx");
  try {
    KeywordSpotter s{c};
    FAIL() << "accepted a word the dictionary lacks";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("qzxqzx"), std::string::npos) << e.what();
  }
  VoiceConfig m;
  m.model_dir = "/nonexistent/model";
  try {
    KeywordSpotter s{m};
    FAIL() << "accepted a missing model";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/model"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tachi::sensor
