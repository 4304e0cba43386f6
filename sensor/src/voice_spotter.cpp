#include "tachi/sensor/voice_spotter.hpp"

#include "tachi/sensor/voice_audio.hpp"

#include <pocketsphinx.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace tachi::sensor {

struct KeywordSpotter::Impl {
  VoiceConfig config;
  cmd_ln_t* cmdln = nullptr;
  ps_decoder_t* decoder = nullptr;
  long samples = 0;
  long utterance_start = 0;         // sample at which the current utterance began
  std::vector<std::int16_t> audio;  // the latest audio, from sample audio_start on
  long audio_start = 0;
  long last_hit_end = -1L << 30;  // sample at which the last reported hit ended (none yet)

  ~Impl() {
    if (decoder != nullptr) {
      ps_end_utt(decoder);
      ps_free(decoder);
    }
    if (cmdln != nullptr) cmd_ln_free_r(cmdln);
  }
};

namespace {
constexpr long kSamplesPerFrame = kVoiceSampleRate / 100;     // pocketsphinx's 10 ms frames
constexpr std::size_t kKeepSamples = 4 * kVoiceSampleRate;   // replayable audio: longer than a phrase
constexpr long kRedetectSamples = kVoiceSampleRate / 2;      // a hit ending < 0.5 s after the last one is it again

// pocketsphinx reads keyword lists from a file only.
std::string write_kws_file(const std::string& text) {
  std::string path = (std::filesystem::temp_directory_path() / "tachi-voice-XXXXXX").string();
  const int fd = ::mkstemp(path.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary keyword list in " + std::filesystem::temp_directory_path().string());
  const auto written = ::write(fd, text.data(), text.size());
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size())) throw std::runtime_error("cannot write the temporary keyword list " + path);
  return path;
}
}  // namespace

KeywordSpotter::KeywordSpotter(const VoiceConfig& config) : impl_(std::make_unique<Impl>()) {
  if (const auto why = validate(config)) throw std::runtime_error("voice config: " + *why);
  namespace fs = std::filesystem;
  if (!fs::is_directory(config.model_dir))
    throw std::runtime_error("acoustic model " + config.model_dir + " not found (install pocketsphinx-en-us)");
  if (!fs::is_regular_file(config.dictionary))
    throw std::runtime_error("pronunciation dictionary " + config.dictionary + " not found (install pocketsphinx-en-us)");
  impl_->config = config;
  char phone_loop[32];
  std::snprintf(phone_loop, sizeof phone_loop, "%g", config.phone_loop_probability);
  impl_->cmdln = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", config.model_dir.c_str(), "-dict", config.dictionary.c_str(),
                             "-kws_plp", phone_loop, "-logfn", "/dev/null", nullptr);
  if (impl_->cmdln == nullptr) throw std::runtime_error("pocketsphinx rejected its arguments");
  impl_->decoder = ps_init(impl_->cmdln);
  if (impl_->decoder == nullptr) throw std::runtime_error("pocketsphinx could not load " + config.model_dir);
  for (const auto& p : config.phrases) {
    std::istringstream words(p.phrase);
    std::string word;
    while (words >> word)
      if (ps_lookup_word(impl_->decoder, word.c_str()) == nullptr)
        throw std::runtime_error("word \"" + word + "\" of phrase \"" + p.phrase + "\" is not in " + config.dictionary);
  }
  const std::string kws = write_kws_file(kws_file_text(config.phrases));
  const int rc = ps_set_kws(impl_->decoder, "commands", kws.c_str());
  std::filesystem::remove(kws);
  if (rc < 0 || ps_set_search(impl_->decoder, "commands") < 0) throw std::runtime_error("pocketsphinx rejected the keyword list");
  if (ps_start_utt(impl_->decoder) < 0) throw std::runtime_error("pocketsphinx could not start decoding");
}

KeywordSpotter::~KeywordSpotter() = default;

double KeywordSpotter::time_s() const noexcept { return static_cast<double>(impl_->samples) / static_cast<double>(kVoiceSampleRate); }

std::vector<VoiceDetection> KeywordSpotter::process(std::span<const std::int16_t> samples) {
  std::vector<VoiceDetection> found;
  if (samples.empty()) return found;
  if (ps_process_raw(impl_->decoder, samples.data(), samples.size(), FALSE, FALSE) < 0)
    throw std::runtime_error("pocketsphinx failed to process audio");
  impl_->samples += static_cast<long>(samples.size());
  // The utterance's audio (the last kKeepSamples of it), for the replay below.
  impl_->audio.insert(impl_->audio.end(), samples.begin(), samples.end());
  if (impl_->audio.size() > kKeepSamples) {
    const std::size_t drop = impl_->audio.size() - kKeepSamples;
    impl_->audio.erase(impl_->audio.begin(), impl_->audio.begin() + static_cast<std::ptrdiff_t>(drop));
    impl_->audio_start += static_cast<long>(drop);
  }
  for (int round = 0; round < 4; ++round) {  // a replay may hold another hit; a few at most
    const char* hyp = ps_get_hyp(impl_->decoder, nullptr);
    if (hyp == nullptr || hyp[0] == '\0') break;
    // Restart, or the same hit is reported with every later block; then replay the audio after the
    // hit's end, which the decoder held and a restart alone drops: in "go forward ten meters" the
    // second phrase follows the first at once and was never found that way (issue 14).
    int last_end = -1;
    for (ps_seg_t* seg = ps_seg_iter(impl_->decoder); seg != nullptr; seg = ps_seg_next(seg)) {
      int start_frame = 0, end_frame = 0;
      ps_seg_frames(seg, &start_frame, &end_frame);
      last_end = std::max(last_end, end_frame);
    }
    // The replay can hold the tail of the phrase just reported ("... cutting"), found again ending
    // just after it; a real next phrase ends at least a phrase's length later.
    const long hit_end = impl_->utterance_start + (last_end + 1) * kSamplesPerFrame;
    if (hit_end - impl_->last_hit_end >= kRedetectSamples) {
      for (const auto& p : phrases_in_hypothesis(hyp, impl_->config.phrases)) found.push_back({time_s(), p.command, p.phrase});
      impl_->last_hit_end = hit_end;
    }
    ps_end_utt(impl_->decoder);
    ps_start_utt(impl_->decoder);
    const long resume = std::max(impl_->utterance_start + (last_end + 1) * kSamplesPerFrame, impl_->audio_start);
    impl_->utterance_start = resume;
    const long from = resume - impl_->audio_start;
    if (from >= static_cast<long>(impl_->audio.size())) break;
    if (ps_process_raw(impl_->decoder, impl_->audio.data() + from, impl_->audio.size() - static_cast<std::size_t>(from), FALSE,
                       FALSE) < 0)
      throw std::runtime_error("pocketsphinx failed to process audio");
  }
  return found;
}

std::vector<VoiceDetection> spot_commands(const VoiceConfig& config, std::span<const std::int16_t> samples) {
  KeywordSpotter spotter{config};
  std::vector<VoiceDetection> all;
  constexpr std::size_t kBlock = 512;  // 32 ms, what a microphone read typically returns
  for (std::size_t at = 0; at < samples.size(); at += kBlock) {
    const auto found = spotter.process(samples.subspan(at, std::min(kBlock, samples.size() - at)));
    all.insert(all.end(), found.begin(), found.end());
  }
  return all;
}

}  // namespace tachi::sensor
