// Keyword spotting with CMU pocketsphinx: one keyword list holds every command phrase, and the decoder
// restarts after each detection (otherwise the same hit is reported again and again).
#pragma once

#include "tachi/sensor/voice_commands.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tachi::sensor {

struct VoiceDetection {
  double time_s = 0.0;  ///< end of the audio block in which the phrase was spotted, from stream start
  VoiceCommand command = VoiceCommand::Start;
  std::string phrase;
};

class KeywordSpotter {
 public:
  /// Loads the acoustic model and dictionary and sets up the keyword list. Throws std::runtime_error
  /// with context when the model or dictionary is missing or a phrase has a word the dictionary lacks.
  explicit KeywordSpotter(const VoiceConfig& config);
  ~KeywordSpotter();
  KeywordSpotter(const KeywordSpotter&) = delete;
  KeywordSpotter& operator=(const KeywordSpotter&) = delete;

  /// Feeds 16 kHz mono samples; returns the commands spotted in them.
  std::vector<VoiceDetection> process(std::span<const std::int16_t> samples);
  /// Seconds of audio processed so far.
  double time_s() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Runs a whole buffer through a fresh spotter in 32 ms blocks (as a microphone would deliver it).
std::vector<VoiceDetection> spot_commands(const VoiceConfig& config, std::span<const std::int16_t> samples);

}  // namespace tachi::sensor
