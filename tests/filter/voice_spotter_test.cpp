// The keyword spotter on real speech (pocketsphinx-testdata) and on flite-synthesised commands.
#include "tachi/sensor/voice_spotter.hpp"

#include "voice_fixture.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

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

TEST(VoiceSpotter, ASmallerPhoneLoopProbabilityFindsCommandsInWhiteNoiseAndNoneInReading) {
  // Six commands at 20 dB SNR (white noise against the voice at full gain, the phrases at 0.5-1 of
  // it): at pocketsphinx's phone-loop probability (0.1) few are found; at 1e-6 with thresholds 1e-15
  // (docs/voice.md) most, with no false alarm there nor in the LibriVox reading.
  const auto start = testing::flite_say("start cutting");
  const auto stop = testing::flite_say("stop cutting");
  double sum = 0;
  for (auto v : start) sum += static_cast<double>(v) * v;
  const double speech_rms = std::sqrt(sum / static_cast<double>(start.size()));
  testing::Sequence seq{7};
  const std::array<double, 6> gains{0.9, 0.6, 1.0, 0.7, 0.8, 0.55};
  seq.pause(0.8);
  for (std::size_t i = 0; i < gains.size(); ++i) {
    seq.say(i % 2 == 0 ? "start cutting" : "stop cutting", i % 2 == 0 ? start : stop, gains[i]);
    seq.pause(1.0);
  }
  seq.noise(speech_rms * std::pow(10.0, -20.0 / 20.0));
  // A detection counts for an utterance when it names its phrase between its start and 0.6 s after
  // its end (as tachi-voice-eval scores); any other detection is a false alarm.
  const auto count_right = [&](const std::vector<VoiceDetection>& found) {
    std::size_t right = 0;
    std::vector<bool> used(found.size(), false);
    for (const auto& utterance : seq.placed())
      for (std::size_t i = 0; i < found.size(); ++i)
        if (!used[i] && found[i].phrase == utterance.phrase && found[i].time_s > utterance.begin_s &&
            found[i].time_s < utterance.end_s + 0.6) {
          used[i] = true;
          ++right;
          break;
        }
    for (std::size_t i = 0; i < found.size(); ++i)
      EXPECT_TRUE(used[i]) << "false alarm: " << found[i].phrase << " at " << found[i].time_s << " s";
    return right;
  };
  VoiceConfig noisy;
  noisy.phone_loop_probability = 1e-6;
  for (auto& p : noisy.phrases) p.threshold = 1e-15;
  const std::size_t by_default = count_right(spot_commands(VoiceConfig{}, seq.samples()));
  const std::size_t tuned = count_right(spot_commands(noisy, seq.samples()));
  RecordProperty("found_by_default", static_cast<int>(by_default));
  RecordProperty("found_tuned", static_cast<int>(tuned));
  // Measured: 4 of 6 against 1 of 6 (docs/voice.md has the 48-command figures).
  EXPECT_GE(tuned, 4U) << "by default " << by_default;
  EXPECT_GE(tuned, by_default + 2) << "tuned " << tuned;
  for (const auto& clip : testing::librivox_clips()) EXPECT_TRUE(spot_commands(noisy, read_wav_file(clip).samples).empty()) << clip;
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
