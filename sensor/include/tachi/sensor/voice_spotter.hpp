// Keyword spotting with CMU pocketsphinx: one keyword list holds every command phrase, and the decoder
// restarts after each detection (otherwise the same hit is reported again and again). By default each
// hit is verified by a second pass (VoiceConfig::verify_min_log_ratio): the phrase aligned again to
// the audio around the hit against a phone loop, a likelihood-ratio test (voice_spotter.cpp).
// With VoiceConfig::warps (vocal tract length normalisation) one keyword search and second pass per warp
// hear the audio, and each utterance's hits are judged once: by the unwarped lane, and only where it
// gives no command by all the lanes, each phrase at its best warp.
#pragma once

#include "tachi/sensor/voice_commands.hpp"

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tachi::sensor {

struct VoiceDetection {
  /// From stream start: the end of the audio block in which the phrase was spotted, or, with the
  /// second pass, in which it was verified (once 0.6 s of audio after the keyword hit had come).
  double time_s = 0.0;
  VoiceCommand command = VoiceCommand::Start;
  std::string phrase;
  /// The second pass's score (VoiceConfig::verify_min_log_ratio); NaN when there is no second pass.
  double verification_score = std::numeric_limits<double>::quiet_NaN();
  /// The second pass's score minus that of the best phrase of another command (VoiceConfig::
  /// verify_min_margin); +infinity when no other command's phrase fits, NaN without a second pass.
  double command_margin = std::numeric_limits<double>::quiet_NaN();
  /// The second pass's score with words allowed around the phrase (a phrase inside a sentence), and its
  /// margin over another command; NaN without a second pass.
  double phrase_score = std::numeric_limits<double>::quiet_NaN();
  double phrase_margin = std::numeric_limits<double>::quiet_NaN();
  /// The phrase's level above the background's floor (dB); NaN without a second pass.
  double level_db = std::numeric_limits<double>::quiet_NaN();
  /// The second pass's score with a garbage model (a phone loop) before and after the phrase instead of
  /// silence alone, and its margin over the best phrase of another command so scored (negative: the
  /// garbage grammar prefers another command; VoiceConfig::verify_min_garbage_margin); NaN without a
  /// second pass.
  double garbage_score = std::numeric_limits<double>::quiet_NaN();
  double garbage_margin = std::numeric_limits<double>::quiet_NaN();
  /// How long the phrase lasts (s) as the phrase grammar (silence fillers around it) and the garbage
  /// grammar align it; NaN without a second pass.
  double phrase_duration_s = std::numeric_limits<double>::quiet_NaN();
  double garbage_duration_s = std::numeric_limits<double>::quiet_NaN();
  /// With the second pass: whether the unwarped lane's keyword search (warp 1.0) hit this utterance, and
  /// whether the warped lanes judged it (VoiceConfig::warps: only where the unwarped lane gave no command).
  bool unwarped_hit = false;
  bool by_warps = false;
  /// Where things lie in the stream (s), for the analysis of wrong commands (tachi-voice-eval --dump):
  /// the keyword hit that opened the utterance (its phrase), the second pass's window start, and the
  /// phrase and the best phrase of another command (the rival) as the garbage grammar aligns them:
  /// first frame, end of the first word, end; and the ratio against the phone loop per frame of the
  /// first word and of the rest (the phone loop's score pro-rated over the same frames). NaN: none.
  struct Alignment {
    double begin_s = std::numeric_limits<double>::quiet_NaN();
    double first_word_end_s = std::numeric_limits<double>::quiet_NaN();
    double end_s = std::numeric_limits<double>::quiet_NaN();
    double first_word_ratio = std::numeric_limits<double>::quiet_NaN();
    double rest_ratio = std::numeric_limits<double>::quiet_NaN();
    double garbage_score = std::numeric_limits<double>::quiet_NaN();
  };
  std::string hit_phrase{};
  double hit_begin_s = std::numeric_limits<double>::quiet_NaN();
  double hit_end_s = std::numeric_limits<double>::quiet_NaN();
  double window_begin_s = std::numeric_limits<double>::quiet_NaN();
  Alignment aligned{}, rival{};
};

/// The second pass's decision on one scored hit (VoiceConfig's verify_* thresholds): a command when
/// its level is high enough, it beats every other command by the margins, the phrase lasts long enough
/// as the garbage grammar aligns it, and its whole-window ratio, its garbage-model ratio or its
/// phrase-frames ratio reaches its threshold (the garbage ratio's the phrase's own when its VoicePhrase sets
/// one and the top-level one is on). The spotter and tachi-voice-eval use this.
bool verification_accepts(const VoiceConfig& config, const VoiceDetection& scored);

class KeywordSpotter {
 public:
  /// Loads the acoustic model and dictionary and sets up the keyword list. Throws std::runtime_error
  /// with context when the model or dictionary is missing or a phrase has a word the dictionary lacks.
  /// `report_refused`: also return each utterance's verdict that the second pass's thresholds refused
  /// (tachi-voice-eval applies them itself; with several warps the verdict returned is the one the
  /// thresholds chose between the unwarped and the warped lanes).
  explicit KeywordSpotter(const VoiceConfig& config, bool report_refused = false);
  ~KeywordSpotter();
  KeywordSpotter(const KeywordSpotter&) = delete;
  KeywordSpotter& operator=(const KeywordSpotter&) = delete;

  /// Feeds 16 kHz mono samples; returns the commands spotted in them.
  std::vector<VoiceDetection> process(std::span<const std::int16_t> samples);
  /// At the end of the audio: the commands still waiting for the second pass's audio after them
  /// (VoiceConfig::verify_min_log_ratio), judged on the audio there is.
  std::vector<VoiceDetection> finish();
  /// Seconds of audio processed so far.
  double time_s() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Runs a whole buffer through a fresh spotter in 32 ms blocks (as a microphone would deliver it).
std::vector<VoiceDetection> spot_commands(const VoiceConfig& config, std::span<const std::int16_t> samples);

}  // namespace tachi::sensor
