// Audio for the voice tests and the voice evaluation: real speech from Debian's pocketsphinx-testdata,
// and command phrases synthesised with flite's slt voice, laid out in sequences with pauses and noise.
#pragma once

#include "tachi/sensor/voice_audio.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace tachi::sensor::testing {

inline const std::string kTestData = "/usr/share/pocketsphinx/test/data";

inline std::vector<std::string> librivox_clips() {
  std::vector<std::string> clips;
  for (const char* id : {"0870", "0880", "0890", "0920", "0930"})
    clips.push_back(kTestData + "/librivox/sense_and_sensibility_01_austen_64kb-" + id + ".wav");
  return clips;
}

/// Speaks `text` with a flite voice (slt by default), returns 16 kHz mono samples.
/// `stretch` > 1 speaks slower (flite's duration_stretch).
inline std::vector<std::int16_t> flite_say(const std::string& text, double stretch = 1.0, const std::string& voice = "slt") {
  const auto path = std::filesystem::temp_directory_path() /
                    ("tachi_flite_" + std::to_string(::getpid()) + "_" + std::to_string(std::rand()) + ".wav");
  const std::string cmd = std::string(TACHI_FLITE) + " -voice " + voice + " --setf duration_stretch=" + std::to_string(stretch) +
                          " -t \"" + text + "\" -o " + path.string();
  const int status = std::system(cmd.c_str());
  if (status != 0) throw std::runtime_error("flite failed: " + cmd);
  auto audio = read_wav_file(path.string());
  std::filesystem::remove(path);
  return resample_to_16k(audio);
}

/// A synthetic speaker: a TTS engine's voice, optionally shifted by sox (pitch in cents, tempo factor).
struct Speaker {
  std::string engine;  ///< "espeak-ng", "flite" or "festival"
  std::string voice;   ///< espeak-ng "-v" (en+m3), flite "-voice" (rms), festival voice function (voice_kal_diphone)
  int pitch_cents = 0;
  double tempo = 1.0;
  std::string label() const {
    std::string l = engine + ":" + voice;
    if (pitch_cents != 0) l += " pitch" + std::string(pitch_cents > 0 ? "+" : "") + std::to_string(pitch_cents);
    if (tempo != 1.0) l += " tempo" + std::to_string(tempo).substr(0, 4);
    return l;
  }
};

/// `text` said by `speaker`, as 16 kHz mono samples; `reverb` adds sox's room reverb (and its 0.5 s
/// tail). Synthesised once and kept in `cache_dir` (a build folder): espeak-ng, flite, festival and
/// sox cost CPU the evaluation needs for decoding.
inline std::vector<std::int16_t> synthesize(const Speaker& speaker, const std::string& text, bool reverb, const std::string& cache_dir) {
  namespace fs = std::filesystem;
  std::string key = speaker.label() + (reverb ? " reverb" : "") + " " + text;
  for (auto& c : key)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '-' && c != '.') c = '_';
  const fs::path cached = fs::path(cache_dir) / (key + ".wav");
  if (!fs::exists(cached)) {
    fs::create_directories(cache_dir);
    const std::string tmp = (fs::path(cache_dir) / ("tmp_" + std::to_string(::getpid()) + "_" + key)).string();
    std::string say;
    if (speaker.engine == "espeak-ng")
      say = "espeak-ng -v '" + speaker.voice + "' -w '" + tmp + ".raw.wav' '" + text + "'";
    else if (speaker.engine == "flite")
      say = std::string(TACHI_FLITE) + " -voice " + speaker.voice + " -t '" + text + "' -o '" + tmp + ".raw.wav'";
    else if (speaker.engine == "festival")
      say = "echo '" + text + "' | text2wave -eval '(" + speaker.voice + ")' -o '" + tmp + ".raw.wav'";
    else
      throw std::invalid_argument("unknown speech engine " + speaker.engine);
    std::string shift = " channels 1";
    if (speaker.pitch_cents != 0) shift += " pitch " + std::to_string(speaker.pitch_cents);
    if (speaker.tempo != 1.0) shift += " tempo -s " + std::to_string(speaker.tempo);
    if (reverb) shift += " pad 0 0.5 reverb";
    // -R: sox dithers when it writes 16 bits after an effect (and when it only resamples), from a fresh
    // random seed per run; the same phrase was then different audio in every fresh cache, so a verdict
    // near a threshold came out one way in one build tree and the other way in the next. -R seeds it the
    // same every run: one synthesis per key, on every machine.
    const std::string convert = "sox -R '" + tmp + ".raw.wav' -b 16 '" + tmp + ".wav'" + shift + " rate 16000";
    const std::string cmd = "(" + say + ") >/dev/null 2>&1 && " + convert + " >/dev/null 2>&1 && mv '" + tmp + ".wav' '" + cached.string() + "'";
    const int status = std::system(cmd.c_str());
    fs::remove(tmp + ".raw.wav");
    if (status != 0) throw std::runtime_error("speech synthesis failed: " + cmd);
  }
  return resample_to_16k(read_wav_file(cached.string()));
}

/// Where an utterance sits in a sequence, in seconds.
struct Placed {
  std::string phrase;
  double begin_s;
  double end_s;
};

/// Concatenates utterances with pauses; adds white noise of the given RMS (in sample units) everywhere.
class Sequence {
 public:
  explicit Sequence(unsigned seed = 1) : rng_(seed) {}
  void pause(double seconds) { samples_.resize(samples_.size() + static_cast<std::size_t>(seconds * kVoiceSampleRate), 0); }
  void say(const std::string& phrase, const std::vector<std::int16_t>& audio, double gain = 1.0) {
    const double begin = seconds();
    for (auto s : audio) samples_.push_back(clip(s * gain));
    placed_.push_back({phrase, begin, seconds()});
  }
  void add(const std::vector<std::int16_t>& audio) { samples_.insert(samples_.end(), audio.begin(), audio.end()); }
  void noise(double rms) {
    std::normal_distribution<double> n{0.0, rms};
    for (auto& s : samples_) s = clip(s + n(rng_));
  }
  /// Adds babble: `talkers` of the `speech` clips at once, each from a random point and looped, scaled
  /// together to the given RMS (other people talking in the room).
  void babble(const std::vector<std::vector<std::int16_t>>& speech, int talkers, double rms) {
    std::vector<double> mix(samples_.size(), 0.0);
    std::uniform_int_distribution<std::size_t> pick(0, speech.size() - 1);
    for (int t = 0; t < talkers; ++t) {
      const auto& clip_samples = speech[pick(rng_)];
      std::size_t at = std::uniform_int_distribution<std::size_t>(0, clip_samples.size() - 1)(rng_);
      for (auto& m : mix) {
        m += clip_samples[at];
        at = (at + 1) % clip_samples.size();
      }
    }
    double sum = 0.0;
    for (double m : mix) sum += m * m;
    const double scale = sum > 0.0 ? rms / std::sqrt(sum / static_cast<double>(mix.size())) : 0.0;
    for (std::size_t i = 0; i < mix.size(); ++i) samples_[i] = clip(samples_[i] + scale * mix[i]);
  }
  double seconds() const { return static_cast<double>(samples_.size()) / kVoiceSampleRate; }
  const std::vector<std::int16_t>& samples() const { return samples_; }
  const std::vector<Placed>& placed() const { return placed_; }

 private:
  static std::int16_t clip(double v) { return static_cast<std::int16_t>(std::clamp(v, -32768.0, 32767.0)); }
  std::mt19937 rng_;
  std::vector<std::int16_t> samples_;
  std::vector<Placed> placed_;
};

}  // namespace tachi::sensor::testing
