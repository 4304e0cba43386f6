#include "paths.hpp"
#include "tachi/sensor/voice_commands.hpp"

#include <gtest/gtest.h>

namespace tachi::sensor {
namespace {

/// What parse_voice_config says about `json`: its error, or "accepted".
std::string error_of(const std::string& json) {
  try {
    parse_voice_config(json);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(VoiceCommands, DefaultsAreTwoWordPhrasesForStartAndStop) {
  const VoiceConfig c;
  ASSERT_EQ(c.phrases.size(), 2U);
  EXPECT_EQ(c.phrases[0].phrase, "begin cutting");
  EXPECT_EQ(c.phrases[0].command, VoiceCommand::Start);
  EXPECT_EQ(c.phrases[1].phrase, "stop cutting");
  EXPECT_EQ(c.phrases[1].command, VoiceCommand::Stop);
  EXPECT_FALSE(validate(c).has_value());
}

TEST(VoiceCommands, KeywordListHoldsEveryPhraseWithItsThreshold) {
  VoiceConfig c;
  c.phrases[1].threshold = 1e-30;
  EXPECT_EQ(kws_file_text(c.phrases), "begin cutting /1e-15/\nstop cutting /1e-30/\n");
}

TEST(VoiceCommands, HypothesisWithTrailingSpaceMapsToItsCommand) {
  const VoiceConfig c;
  const auto one = phrases_in_hypothesis("stop cutting ", c.phrases);
  ASSERT_EQ(one.size(), 1U);
  EXPECT_EQ(one[0].command, VoiceCommand::Stop);
  const auto two = phrases_in_hypothesis("stop cutting begin cutting ", c.phrases);
  ASSERT_EQ(two.size(), 2U);
  EXPECT_EQ(two[0].command, VoiceCommand::Stop);
  EXPECT_EQ(two[1].command, VoiceCommand::Start);
  EXPECT_TRUE(phrases_in_hypothesis("cutting stop", c.phrases).empty());
}

TEST(VoiceCommands, OverlappingPhrasesCountOnceWithTheLongestWinning) {
  VoiceConfig c;
  c.phrases.push_back({"stop", VoiceCommand::Stop, 1e-20});
  const auto found = phrases_in_hypothesis("stop cutting ", c.phrases);
  ASSERT_EQ(found.size(), 1U);
  EXPECT_EQ(found[0].phrase, "stop cutting");
}

TEST(VoiceCommands, SetPhraseReplacesTheCommandsPhraseAndKeepsItsThreshold) {
  VoiceConfig c;
  c.phrases[0].threshold = 1e-10;
  set_phrase(c, VoiceCommand::Start, "  Go   Forward ");
  ASSERT_EQ(c.phrases.size(), 2U);
  EXPECT_EQ(c.phrases[0].phrase, "stop cutting");
  EXPECT_EQ(c.phrases[1].phrase, "go forward");
  EXPECT_EQ(c.phrases[1].threshold, 1e-10);
}

TEST(VoiceCommands, ConfigParsesAndRejectsBadValuesByName) {
  const VoiceConfig c = parse_voice_config(R"({"phrases": [
      {"phrase": "begin cut", "command": "start", "threshold": 1e-25},
      {"phrase": "end cut", "command": "stop"}]})");
  ASSERT_EQ(c.phrases.size(), 2U);
  EXPECT_EQ(c.phrases[0].threshold, 1e-25);
  EXPECT_EQ(c.phrases[1].threshold, 1e-15);  // the default phrases' when the key is missing
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "go", "command": "start"}]})").find("stop"), std::string::npos);
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "go", "command": "jump"}]})").find("command"), std::string::npos);
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "a", "command": "start", "threshold": 2},
                                     {"phrase": "b", "command": "stop"}]})").find("threshold"), std::string::npos);
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "a", "command": "start"}, {"phrase": "a", "command": "stop"}]})")
                .find("twice"), std::string::npos);
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "a1", "command": "start"}, {"phrase": "b", "command": "stop"}]})")
                .find("letters"), std::string::npos);
  EXPECT_NE(error_of(R"({"model": "x"})").find("unknown key model"), std::string::npos);
  EXPECT_EQ(c.phone_loop_probability, 1e-10);  // the two-pass default when the key is missing
  EXPECT_EQ(c.verify_min_log_ratio, -20.0);
  // null turns the second pass off (one pass, every keyword hit is a command); a string is refused.
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_log_ratio": null})").verify_min_log_ratio.has_value());
  EXPECT_EQ(parse_voice_config(R"({"verify_min_log_ratio": -12.5})").verify_min_log_ratio, -12.5);
  EXPECT_NE(error_of(R"({"verify_min_log_ratio": "high"})").find("verify_min_log_ratio"), std::string::npos);
  EXPECT_EQ(parse_voice_config(R"({"phone_loop_probability": 1e-6})").phone_loop_probability, 1e-6);
  EXPECT_NE(error_of(R"({"phone_loop_probability": 0})").find("phone_loop_probability"), std::string::npos);
  EXPECT_NE(error_of(R"({"phone_loop_probability": 2})").find("phone_loop_probability"), std::string::npos);
  EXPECT_NE(error_of("nope").find("JSON"), std::string::npos);
}

TEST(VoiceCommands, TheShippedConfigFileMatchesTheDefaults) {
  const VoiceConfig file = load_voice_config(tachi::test::source_dir() + "/config/voice.json");
  const VoiceConfig defaults;
  EXPECT_EQ(file.model_dir, defaults.model_dir);
  EXPECT_EQ(file.dictionary, defaults.dictionary);
  EXPECT_EQ(kws_file_text(file.phrases), kws_file_text(defaults.phrases));
  EXPECT_EQ(file.phone_loop_probability, defaults.phone_loop_probability);
  EXPECT_EQ(file.verify_min_log_ratio, defaults.verify_min_log_ratio);
  EXPECT_EQ(file.verify_min_margin, defaults.verify_min_margin);
  EXPECT_EQ(file.verify_min_phrase_log_ratio, defaults.verify_min_phrase_log_ratio);
  EXPECT_EQ(file.verify_min_phrase_margin, defaults.verify_min_phrase_margin);
  EXPECT_EQ(file.verify_min_level_db, defaults.verify_min_level_db);
  EXPECT_EQ(file.verify_min_garbage_margin, defaults.verify_min_garbage_margin);
  EXPECT_EQ(file.verify_min_garbage_log_ratio, defaults.verify_min_garbage_log_ratio);
  EXPECT_EQ(file.verify_min_phrase_seconds, defaults.verify_min_phrase_seconds);
  EXPECT_EQ(file.verify_min_first_word_margin, defaults.verify_min_first_word_margin);
  EXPECT_EQ(file.warps, defaults.warps);
  ASSERT_EQ(file.phrases.size(), defaults.phrases.size());
  for (std::size_t i = 0; i < file.phrases.size(); ++i)
    EXPECT_EQ(file.phrases[i].verify_min_garbage_log_ratio, defaults.phrases[i].verify_min_garbage_log_ratio) << file.phrases[i].phrase;
}

TEST(VoiceCommands, APhrasesOwnGarbageRatioParsesIsValidatedAndIsNotCarriedToAReplacingPhrase) {
  const VoiceConfig c = parse_voice_config(R"({"phrases": [
      {"phrase": "begin cutting", "command": "start", "verify_min_garbage_log_ratio": -70},
      {"phrase": "stop cutting", "command": "stop"}]})");
  EXPECT_EQ(c.phrases[0].verify_min_garbage_log_ratio, -70.0);
  EXPECT_FALSE(c.phrases[1].verify_min_garbage_log_ratio.has_value());  // the top-level one
  EXPECT_NE(error_of(R"({"phrases": [{"phrase": "a", "command": "start", "verify_min_garbage_log_ratio": "low"},
                                     {"phrase": "b", "command": "stop"}]})").find("verify_min_garbage_log_ratio"), std::string::npos);
  VoiceConfig replaced = c;  // measured on "begin cutting"'s audio: another phrase starts from the top-level one
  set_phrase(replaced, VoiceCommand::Start, "start cutting");
  EXPECT_FALSE(replaced.phrases[1].verify_min_garbage_log_ratio.has_value());
}

TEST(VoiceCommands, ThePhraseRatioMarginAndLevelKeysParseAndAreValidated) {
  const VoiceConfig c = parse_voice_config(R"({"verify_min_phrase_log_ratio": -3, "verify_min_phrase_margin": 1.5, "verify_min_level_db": 7})");
  EXPECT_EQ(c.verify_min_phrase_log_ratio, -3.0);
  EXPECT_EQ(c.verify_min_phrase_margin, 1.5);
  EXPECT_EQ(c.verify_min_level_db, 7.0);
  // null turns a check off.
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_phrase_log_ratio": null})").verify_min_phrase_log_ratio.has_value());
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_level_db": null})").verify_min_level_db.has_value());
  EXPECT_NE(error_of(R"({"verify_min_level_db": "loud"})").find("verify_min_level_db"), std::string::npos);
  EXPECT_NE(error_of(R"({"verify_min_phrase_log_ratio": [1]})").find("verify_min_phrase_log_ratio"), std::string::npos);
  EXPECT_NE(error_of(R"({"verify_min_phrase_margin": -1})").find("verify_min_phrase_margin"), std::string::npos);
  EXPECT_EQ(parse_voice_config(R"({"verify_min_garbage_margin": 1.5})").verify_min_garbage_margin, 1.5);
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_garbage_margin": null})").verify_min_garbage_margin.has_value());
  EXPECT_NE(error_of(R"({"verify_min_garbage_margin": "x"})").find("verify_min_garbage_margin"), std::string::npos);
  EXPECT_EQ(parse_voice_config(R"({"verify_min_garbage_log_ratio": -50})").verify_min_garbage_log_ratio, -50.0);
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_garbage_log_ratio": null})").verify_min_garbage_log_ratio.has_value());
  EXPECT_NE(error_of(R"({"verify_min_garbage_log_ratio": "x"})").find("verify_min_garbage_log_ratio"), std::string::npos);
  EXPECT_EQ(parse_voice_config(R"({"verify_min_phrase_seconds": 0.4})").verify_min_phrase_seconds, 0.4);
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_phrase_seconds": null})").verify_min_phrase_seconds.has_value());
  EXPECT_NE(error_of(R"({"verify_min_phrase_seconds": -1})").find("verify_min_phrase_seconds"), std::string::npos);
  EXPECT_EQ(parse_voice_config(R"({"verify_min_first_word_margin": -2})").verify_min_first_word_margin, -2.0);
  EXPECT_FALSE(parse_voice_config(R"({"verify_min_first_word_margin": null})").verify_min_first_word_margin.has_value());
  EXPECT_NE(error_of(R"({"verify_min_first_word_margin": "x"})").find("verify_min_first_word_margin"), std::string::npos);
}

TEST(VoiceCommands, TheSecondPassMarginIsValidated) {
  EXPECT_EQ(parse_voice_config(R"({"verify_min_margin": 2.5})").verify_min_margin, 2.5);
  try {
    parse_voice_config(R"({"verify_min_margin": -1})");
    FAIL() << "accepted a negative margin";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("verify_min_margin"), std::string::npos) << e.what();
  }
}

TEST(VoiceCommands, TheWarpsParseAndAreValidatedByName) {
  EXPECT_EQ(parse_voice_config("{}").warps, VoiceConfig{}.warps);
  EXPECT_EQ(parse_voice_config(R"({"warps": [1.0]})").warps, std::vector<double>{1.0});  // no warping, as before session 37
  EXPECT_EQ(parse_voice_config(R"({"warps": [0.88, 1.0, 1.13]})").warps, (std::vector<double>{0.88, 1.0, 1.13}));
  for (const char* bad : {R"({"warps": []})", R"({"warps": 1.0})", R"({"warps": ["1"]})", R"({"warps": [0.3]})", R"({"warps": [1.0, 1.0]})"})
    EXPECT_NE(error_of(bad).find("warps"), std::string::npos) << bad << ": " << error_of(bad);
}

}  // namespace
}  // namespace tachi::sensor
