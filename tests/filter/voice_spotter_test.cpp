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
  // decoder after the first hit without replaying the audio it held lost the second.
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
  // One pass: the second pass wants a command said on its own, and "of clubs" here sits inside
  // "four of clubs seven" (log-likelihood ratio -64 per frame against -20 to pass; docs/voice.md).
  VoiceConfig c;
  c.phrases = {{"of spades", VoiceCommand::Stop, 1e-20},
               {"of clubs", VoiceCommand::Start, 1e-20},
               {"of hearts", VoiceCommand::Stop, 1e-20}};
  c.phone_loop_probability = 0.1;
  c.verify_min_log_ratio.reset();
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
  const auto start = testing::flite_say("begin cutting");
  const auto stop = testing::flite_say("stop cutting");
  testing::Sequence seq{3};
  seq.pause(0.7);
  seq.say("begin cutting", start);
  seq.pause(1.3);
  seq.say("stop cutting", stop, 0.6);
  seq.pause(0.5);
  seq.say("begin cutting", start, 0.8);
  seq.pause(2.0);
  seq.say("stop cutting", stop);
  seq.pause(0.8);
  seq.noise(150.0);
  const auto found = spot_commands(VoiceConfig{}, seq.samples());
  ASSERT_EQ(phrases_of(found), (std::vector<std::string>{"begin cutting", "stop cutting", "begin cutting", "stop cutting"}));
  for (std::size_t i = 0; i < found.size(); ++i) {
    // Reported once the second pass has the 0.6 s of audio after the keyword hit (the hit itself may
    // come before the phrase ends): within a second of the phrase's end. With the keyword search's
    // frames taken for stream time, the hits after the first were verified on the wrong audio and lost.
    EXPECT_GT(found[i].time_s, seq.placed()[i].begin_s) << i;
    EXPECT_LT(found[i].time_s, seq.placed()[i].end_s + 1.0) << i;
  }
  EXPECT_EQ(found[0].command, VoiceCommand::Start);
  EXPECT_EQ(found[1].command, VoiceCommand::Stop);
}

TEST(VoiceSpotter, TwoPassesFindCommandsInWhiteNoiseThatOnePassMissesWithoutFalseAlarms) {
  // Six commands at 20 dB SNR (white noise against the voice at full gain, the phrases at 0.5-1 of
  // it): one pass at pocketsphinx's phone-loop probability (0.1) finds few; the default, a keyword
  // search at 1e-10 whose hits a second pass verifies (docs/voice.md), finds nearly all, with no false
  // alarm there nor in the LibriVox reading, where the same keyword search alone false-alarms.
  const auto start = testing::flite_say("begin cutting");
  const auto stop = testing::flite_say("stop cutting");
  double sum = 0;
  for (auto v : start) sum += static_cast<double>(v) * v;
  const double speech_rms = std::sqrt(sum / static_cast<double>(start.size()));
  testing::Sequence seq{7};
  const std::array<double, 6> gains{0.9, 0.6, 1.0, 0.7, 0.8, 0.55};
  seq.pause(0.8);
  for (std::size_t i = 0; i < gains.size(); ++i) {
    seq.say(i % 2 == 0 ? "begin cutting" : "stop cutting", i % 2 == 0 ? start : stop, gains[i]);
    seq.pause(1.0);
  }
  seq.noise(speech_rms * std::pow(10.0, -20.0 / 20.0));
  // A detection counts for an utterance when it names its phrase between its start and 1 s after
  // its end (as tachi-voice-eval scores); any other detection is a false alarm.
  const auto count_right = [&](const std::vector<VoiceDetection>& found) {
    std::size_t right = 0;
    std::vector<bool> used(found.size(), false);
    for (const auto& utterance : seq.placed())
      for (std::size_t i = 0; i < found.size(); ++i)
        if (!used[i] && found[i].phrase == utterance.phrase && found[i].time_s > utterance.begin_s &&
            found[i].time_s < utterance.end_s + 1.0) {
          used[i] = true;
          ++right;
          break;
        }
    for (std::size_t i = 0; i < found.size(); ++i)
      EXPECT_TRUE(used[i]) << "false alarm: " << found[i].phrase << " at " << found[i].time_s << " s";
    return right;
  };
  VoiceConfig one_pass;
  one_pass.phone_loop_probability = 0.1;
  for (auto& p : one_pass.phrases) p.threshold = 1e-20;
  one_pass.verify_min_log_ratio.reset();
  const std::size_t by_one_pass = count_right(spot_commands(one_pass, seq.samples()));
  const std::size_t by_default = count_right(spot_commands(VoiceConfig{}, seq.samples()));
  RecordProperty("found_by_one_pass", static_cast<int>(by_one_pass));
  RecordProperty("found_by_default", static_cast<int>(by_default));
  EXPECT_GE(by_default, 5U) << "one pass " << by_one_pass;
  EXPECT_GE(by_default, by_one_pass + 2) << "two passes " << by_default;
  VoiceConfig keyword_search_alone;  // the default's first pass without its second
  keyword_search_alone.verify_min_log_ratio.reset();
  std::size_t unverified_false_alarms = 0;
  for (const auto& clip : testing::librivox_clips()) {
    const auto reading = read_wav_file(clip).samples;
    EXPECT_TRUE(spot_commands(VoiceConfig{}, reading).empty()) << clip;
    unverified_false_alarms += spot_commands(keyword_search_alone, reading).size();
  }
  // Measured: 3 in the 24.7 s; the second pass is what keeps the default at none.
  EXPECT_GE(unverified_false_alarms, 1U);
}

TEST(VoiceSpotter, ABritishVoiceSaysTheDefaultCommandsRightAndTheOldStartPhraseIsMissedNotHeardAsStop) {
  // espeak-ng's en voices say "start" without its R, and the en-us model heard "stop cutting" for it.
  // The default "begin cutting" is told apart; with the old phrase the second pass's margin (the two
  // commands score within 2.5 of each other there) makes it a miss, never a stop.
  const std::string cache = (std::filesystem::temp_directory_path() / "tachi_voice_test_cache").string();
  const testing::Speaker british{"espeak-ng", "en+m1"};
  const auto sequence = [&](const std::string& start) {
    testing::Sequence seq{11};
    seq.pause(0.5);
    seq.say(start, testing::synthesize(british, start, false, cache));
    seq.pause(2.0);
    seq.say("stop cutting", testing::synthesize(british, "stop cutting", false, cache));
    seq.pause(1.5);
    return seq;
  };
  EXPECT_EQ(phrases_of(spot_commands(VoiceConfig{}, sequence("begin cutting").samples())),
            (std::vector<std::string>{"begin cutting", "stop cutting"}));
  VoiceConfig old;
  set_phrase(old, VoiceCommand::Start, "start cutting");
  // The stop that follows scores a command margin of 7.96-8.0 here, at the default's 8 (measured on
  // two machines: found on one, missed on the other), so whether it is heard is not asserted; what
  // is: nothing said before 3 s is taken for a stop.
  const auto found = spot_commands(old, sequence("start cutting").samples());
  for (const auto& d : found) EXPECT_TRUE(d.command == VoiceCommand::Start || d.time_s > 3.0) << d.phrase << " at " << d.time_s;
  if (!found.empty()) {
    EXPECT_EQ(found.back().phrase, "stop cutting");
  }
  VoiceConfig no_margin = old;
  no_margin.verify_min_margin = 0.0;  // as before the second pass's margin check: the start was reported as a stop
  const auto before = spot_commands(no_margin, sequence("start cutting").samples());
  ASSERT_FALSE(before.empty());
  EXPECT_EQ(before.front().command, VoiceCommand::Stop);
  EXPECT_LT(before.front().time_s, 3.0);
}

TEST(VoiceSpotter, TheSecondPassDecisionNeedsTheLevelTheMarginsAndOneOfTheTwoRatios) {
  VoiceConfig c;
  c.verify_min_log_ratio = -20.0;
  c.verify_min_margin = 4.0;
  c.verify_min_phrase_log_ratio = -5.0;
  c.verify_min_phrase_margin = 2.0;
  c.verify_min_level_db = 8.0;
  c.verify_min_garbage_margin.reset();
  c.verify_min_garbage_log_ratio.reset();
  c.verify_min_phrase_seconds.reset();
  VoiceDetection d;
  d.verification_score = -10.0;  // said alone: the whole window passes
  d.command_margin = 6.0;
  d.phrase_score = -30.0;
  d.phrase_margin = 3.0;
  d.level_db = 15.0;
  EXPECT_TRUE(verification_accepts(c, d));
  VoiceDetection in_sentence = d;  // words around it: only the phrase's own frames pass
  in_sentence.verification_score = -40.0;
  in_sentence.phrase_score = -2.0;
  EXPECT_TRUE(verification_accepts(c, in_sentence));
  in_sentence.phrase_score = -6.0;
  EXPECT_FALSE(verification_accepts(c, in_sentence));
  VoiceDetection quiet = d;  // no louder than the babble around it
  quiet.level_db = 3.0;
  EXPECT_FALSE(verification_accepts(c, quiet));
  quiet.level_db = std::nan("");
  EXPECT_FALSE(verification_accepts(c, quiet));
  VoiceDetection close = d;  // either margin too small: dropped, never the wrong command
  close.command_margin = 3.0;
  EXPECT_FALSE(verification_accepts(c, close));
  close = d;
  close.phrase_margin = 1.0;
  EXPECT_FALSE(verification_accepts(c, close));
  // Without the phrase ratio and the level check, as before: the whole window and its margin decide.
  VoiceConfig before;
  before.verify_min_log_ratio = -20.0;
  before.verify_min_margin = 4.0;
  before.verify_min_phrase_margin = 0.0;
  before.verify_min_level_db.reset();
  before.verify_min_garbage_margin.reset();
  before.verify_min_garbage_log_ratio.reset();
  before.verify_min_phrase_seconds.reset();
  EXPECT_TRUE(verification_accepts(before, quiet));
  EXPECT_FALSE(verification_accepts(before, in_sentence));
  before.verify_min_log_ratio.reset();  // one pass: every hit
  EXPECT_TRUE(verification_accepts(before, close));
}

TEST(VoiceSpotter, TheGarbageMarginDropsAPhraseThatWinsOnlyByStretchingOverTheWordsAroundIt) {
  VoiceConfig c;  // the shipped gates, plus the garbage-model margin
  c.verify_min_garbage_margin = 1.0;
  VoiceDetection d;
  d.verification_score = -10.0;
  d.command_margin = 9.0;  // "begin cutting" beats "stop cutting" with silence fillers around them...
  d.phrase_margin = 3.0;
  d.level_db = 20.0;
  d.garbage_duration_s = 0.7;
  d.garbage_margin = -4.0;  // ...but not once a phone loop explains "that is enough" before it
  EXPECT_FALSE(verification_accepts(c, d));
  d.garbage_margin = std::nan("");  // not scored: refused, never a wrong command
  EXPECT_FALSE(verification_accepts(c, d));
  d.garbage_margin = 2.0;
  EXPECT_TRUE(verification_accepts(c, d));
  c.verify_min_garbage_margin.reset();  // not checked
  d.garbage_margin = -4.0;
  EXPECT_TRUE(verification_accepts(c, d));
}

TEST(VoiceSpotter, APhraseInsideWordsIsAcceptedOnItsGarbageModelRatioWhenItLastsLongEnough) {
  const VoiceConfig c;  // the shipped gates: garbage ratio -55, phrase 0.5 s
  VoiceDetection d;     // "please stop cutting now": the words around it sink the whole window
  d.verification_score = -35.0;
  d.command_margin = 9.0;
  d.phrase_score = -20.0;
  d.phrase_margin = 1.0;
  d.level_db = 25.0;
  d.garbage_score = -48.0;  // with a phone loop explaining the words, the phrase fits
  d.garbage_margin = 30.0;
  d.garbage_duration_s = 0.68;
  EXPECT_TRUE(verification_accepts(c, d));
  VoiceDetection squeezed = d;  // the phrase not said: the grammar crams it into its fewest frames
  squeezed.garbage_duration_s = 0.38;
  EXPECT_FALSE(verification_accepts(c, squeezed));
  squeezed.garbage_duration_s = std::nan("");
  EXPECT_FALSE(verification_accepts(c, squeezed));
  squeezed = d;  // the duration check holds for a phrase said alone too
  squeezed.verification_score = -5.0;
  squeezed.command_margin = 20.0;
  squeezed.garbage_duration_s = 0.4;
  EXPECT_FALSE(verification_accepts(c, squeezed));
  VoiceDetection poor = d;  // the garbage model does not find the phrase either
  poor.garbage_score = -75.0;
  EXPECT_FALSE(verification_accepts(c, poor));
  VoiceDetection other = d;  // the garbage grammar prefers the other command: never a wrong command
  other.garbage_margin = -3.0;
  EXPECT_FALSE(verification_accepts(c, other));
  other = d;  // nor when the commands score close with silence around them ("start" said without its R)
  other.command_margin = 2.0;
  EXPECT_FALSE(verification_accepts(c, other));
  VoiceDetection quiet = d;  // babble: no louder than the talkers around it
  quiet.level_db = 5.0;
  EXPECT_FALSE(verification_accepts(c, quiet));
  VoiceConfig whole_window_only = c;  // the garbage ratio off: as before, the whole window decides
  whole_window_only.verify_min_garbage_log_ratio.reset();
  EXPECT_FALSE(verification_accepts(whole_window_only, d));
  whole_window_only.verify_min_phrase_seconds.reset();
  squeezed.garbage_duration_s = 0.4;
  EXPECT_TRUE(verification_accepts(whole_window_only, squeezed));
}

TEST(VoiceSpotter, ACommandTheGarbageGrammarPrefersByLessThanTheMarginIsDropped) {
  const VoiceConfig c;  // the shipped gates: garbage margin 4, as the whole window's
  VoiceDetection d;     // the second tune set's reverb case: "begin cutting" said, "stop cutting" reported
  d.phrase = "stop cutting";
  d.verification_score = -9.1;  // every whole-window figure looks like a command said alone
  d.command_margin = 7.8;
  d.phrase_margin = 10.2;
  d.level_db = 40.0;
  d.garbage_score = -55.7;
  d.garbage_duration_s = 0.52;
  d.garbage_margin = 1.4;  // but with a phone loop around them the commands nearly tie
  EXPECT_FALSE(verification_accepts(c, d));
  VoiceConfig zero = c;  // the garbage grammar needing only to prefer the command (before session 36)
  zero.verify_min_garbage_margin = 0.0;
  EXPECT_TRUE(verification_accepts(zero, d));
  d.garbage_margin = 4.0;
  EXPECT_TRUE(verification_accepts(c, d));
}

TEST(VoiceSpotter, BeginCuttingInsideWordsIsAcceptedAtItsOwnLowerGarbageRatioAndStopCuttingIsNot) {
  const VoiceConfig c;  // the shipped gates: garbage ratio -55, "begin cutting" its own -60
  VoiceDetection d;     // "okay begin cutting now": the words around it sink the whole window
  d.phrase = "begin cutting";
  d.verification_score = -35.0;
  d.command_margin = 9.0;
  d.phrase_margin = 1.0;
  d.level_db = 25.0;
  d.garbage_score = -58.0;  // below the top-level -55, above the phrase's own -60
  d.garbage_margin = 30.0;
  d.garbage_duration_s = 0.68;
  EXPECT_TRUE(verification_accepts(c, d));
  VoiceConfig one_scale = c;  // the per-phrase threshold off: the top-level one refuses it
  for (auto& p : one_scale.phrases) p.verify_min_garbage_log_ratio.reset();
  EXPECT_FALSE(verification_accepts(one_scale, d));
  VoiceDetection stop = d;  // the same scores as "stop cutting", which keeps the top-level -55
  stop.phrase = "stop cutting";
  EXPECT_FALSE(verification_accepts(c, stop));
  stop.garbage_score = -54.0;
  EXPECT_TRUE(verification_accepts(c, stop));
  VoiceDetection poor = d;  // below the phrase's own threshold too
  poor.garbage_score = -62.0;
  EXPECT_FALSE(verification_accepts(c, poor));
  VoiceConfig whole_window_only = c;  // the top-level garbage ratio off turns it off for every phrase
  whole_window_only.verify_min_garbage_log_ratio.reset();
  EXPECT_FALSE(verification_accepts(whole_window_only, d));
  VoiceDetection squeezed = d;  // the duration check and the margins still hold
  squeezed.garbage_duration_s = 0.4;
  EXPECT_FALSE(verification_accepts(c, squeezed));
  squeezed = d;
  squeezed.garbage_margin = -1.0;
  EXPECT_FALSE(verification_accepts(c, squeezed));
}

TEST(VoiceSpotter, ACommandWhoseFirstWordScoresBelowTheRivalsFirstWordIsRefused) {
  const VoiceConfig c;  // the shipped gates, the first-word margin among them (docs/voice.md, session 40)
  VoiceDetection d;     // the second tune set's babble case: "stop cutting" said inside a sentence, "begin cutting" reported
  d.phrase = "begin cutting";
  d.verification_score = -13.6;  // the whole window accepts it, beating "stop cutting" by 14.1
  d.command_margin = 14.1;
  d.phrase_margin = 5.0;
  d.level_db = 20.0;
  d.garbage_score = -65.8;
  d.garbage_margin = 29.3;
  d.garbage_duration_s = 0.71;
  d.aligned.first_word_ratio = -63.5;  // but "begin" fits its frames worse than "stop" fits its own
  d.rival.first_word_ratio = -53.4;
  EXPECT_FALSE(verification_accepts(c, d));
  VoiceConfig off = c;  // the margin off: the shared "cutting" and the words around it decide
  off.verify_min_first_word_margin.reset();
  EXPECT_TRUE(verification_accepts(off, d));
  d.rival.first_word_ratio = -70.0;  // the reported phrase's first word the better: a command
  EXPECT_TRUE(verification_accepts(c, d));
  d.rival.first_word_ratio = std::nan("");  // no rival aligned: nothing to confuse it with, not checked
  EXPECT_TRUE(verification_accepts(c, d));
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
