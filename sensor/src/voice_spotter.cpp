#include "tachi/sensor/voice_spotter.hpp"

#include "tachi/sensor/voice_audio.hpp"

#include <pocketsphinx.h>

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

  ~Impl() {
    if (decoder != nullptr) {
      ps_end_utt(decoder);
      ps_free(decoder);
    }
    if (cmdln != nullptr) cmd_ln_free_r(cmdln);
  }
};

namespace {
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
  impl_->cmdln = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", config.model_dir.c_str(), "-dict", config.dictionary.c_str(),
                             "-logfn", "/dev/null", nullptr);
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
  const char* hyp = ps_get_hyp(impl_->decoder, nullptr);
  if (hyp != nullptr && hyp[0] != '\0') {
    for (const auto& p : phrases_in_hypothesis(hyp, impl_->config.phrases)) found.push_back({time_s(), p.command, p.phrase});
    // Restart, or the same hit is reported with every later block.
    ps_end_utt(impl_->decoder);
    ps_start_utt(impl_->decoder);
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
