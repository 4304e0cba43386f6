// tachi-voice: spots "begin cutting" / "stop cutting" (configurable) in a WAV file, a raw file, an ALSA
// capture device or the Kinect's microphones; prints time_s,command,phrase per command and publishes
// tachi_msg_VoiceCommand on the bus unless --no-dds.
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/sensor/voice_audio.hpp"
#include "tachi/sensor/voice_spotter.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

namespace {

struct Options {
  std::string wav;
  std::string raw;
  std::string device;
  bool use_device = false;
  bool kinect_mic = false;
  int kinect_index = 0;
  std::string config_file;
  std::string start_phrase;
  std::string stop_phrase;
  std::string grab_phrase;
  std::string release_phrase;
  bool no_dds = false;
  double wait_readers_s = 1.0;
  unsigned source_id = 0;
  std::string log_level;
  tachi::common::BusOptions bus;
};

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// Publishes commands; nothing when --no-dds.
class CommandPublisher {
 public:
  CommandPublisher(const Options& o) : source_id_(o.source_id), waiting_for_filter_("tachi-filter", o.bus.domain) {
    if (o.no_dds) return;
    dds_.emplace(o.bus.domain, o.bus.dds_config, tachi::bus::Security{o.bus.secure_dir, o.bus.identity});
    writer_.emplace(*dds_, tachi::bus::topics::voice_command);
    heartbeat_.emplace(*dds_, "tachi-voice");
  }
  /// Heartbeat on tachi/node/status (no-op without DDS).
  void alive(std::uint64_t samples_in) {
    if (heartbeat_) heartbeat_->update(tachi_msg_NODE_RUNNING, samples_in, published_);
    if (writer_) waiting_for_filter_.warn_if_waiting(writer_->matched_readers() > 0);
  }
  void wait_for_readers(double seconds) {
    if (writer_ && seconds > 0 && !writer_->wait_for_readers(1, std::chrono::milliseconds(static_cast<long>(seconds * 1000))))
      spdlog::warn("no subscriber to {} after {} s; publishing anyway", tachi::bus::topics::voice_command.name, seconds);
  }
  void publish(const tachi::sensor::VoiceDetection& d, std::int64_t time_ns) {
    if (!writer_) return;
    tachi_msg_VoiceCommand msg{};
    msg.source_id = source_id_;
    msg.time_ns = time_ns;
    switch (d.command) {
      case tachi::sensor::VoiceCommand::Start: msg.command = tachi_msg_VOICE_START; break;
      case tachi::sensor::VoiceCommand::Stop: msg.command = tachi_msg_VOICE_STOP; break;
      case tachi::sensor::VoiceCommand::Grab: msg.command = tachi_msg_VOICE_GRAB; break;
      case tachi::sensor::VoiceCommand::Release: msg.command = tachi_msg_VOICE_RELEASE; break;
    }
    std::snprintf(msg.phrase, sizeof msg.phrase, "%s", d.phrase.c_str());
    writer_->write(msg);
    ++published_;
  }
  /// Reliable delivery of what was written before the process exits.
  void flush() {
    if (writer_) dds_wait_for_acks(writer_->handle(), DDS_SECS(2));
  }

 private:
  std::uint32_t source_id_;
  std::optional<tachi::bus::Participant> dds_;
  std::optional<tachi::bus::Writer<tachi_msg_VoiceCommand>> writer_;
  std::optional<tachi::bus::Heartbeat> heartbeat_;
  tachi::common::PeerWait waiting_for_filter_;
  std::uint64_t published_ = 0;
};

void report(const tachi::sensor::VoiceDetection& d) {
  std::printf("%.3f,%s,%s\n", d.time_s, tachi::sensor::to_string(d.command).c_str(), d.phrase.c_str());
  if (!std::isnan(d.verification_score))
    spdlog::debug("\"{}\" at {:.3f} s: second-pass log-likelihood ratio {:.2f} per frame, {:.2f} above the best other command", d.phrase,
                  d.time_s, d.verification_score, d.command_margin);
  std::fflush(stdout);
}

int run_file(const Options& o, const tachi::sensor::VoiceConfig& config) {
  using namespace tachi::sensor;
  const PcmAudio audio = o.wav.empty() ? read_raw_file(o.raw) : read_wav_file(o.wav);
  const auto samples = resample_to_16k(audio);
  KeywordSpotter spotter{config};
  CommandPublisher publisher{o};
  publisher.wait_for_readers(o.wait_readers_s);
  const std::int64_t start_ns = now_ns();
  constexpr std::size_t kBlock = 512;
  std::size_t count = 0;
  for (std::size_t at = 0; at < samples.size() && !tachi::common::stop_requested(); at += kBlock) {
    const std::span<const std::int16_t> block{samples.data() + at, std::min(kBlock, samples.size() - at)};
    for (const auto& d : spotter.process(block)) {
      report(d);
      publisher.publish(d, start_ns + static_cast<std::int64_t>(d.time_s * 1e9));
      ++count;
    }
  }
  for (const auto& d : spotter.finish()) {
    report(d);
    publisher.publish(d, start_ns + static_cast<std::int64_t>(d.time_s * 1e9));
    ++count;
  }
  publisher.flush();
  spdlog::info("{:.2f} s of audio, {} commands", spotter.time_s(), count);
  return tachi::common::kExitOk;
}

int run_live(const Options& o, const tachi::sensor::VoiceConfig& config) {
  using namespace tachi::sensor;
  auto source = o.kinect_mic ? open_kinect_mic_source(o.kinect_index) : open_alsa_source(o.device);
  KeywordSpotter spotter{config};
  CommandPublisher publisher{o};
  spdlog::info("listening on {}", o.kinect_mic ? "the Kinect's microphones" : "audio device '" + o.device + "'");
  std::vector<std::int16_t> buffer(512);
  std::uint64_t samples_in = 0;
  tachi::common::run_until_stopped([&] {
    const long n = source->read(buffer);
    if (n < 0) return false;
    samples_in += static_cast<std::uint64_t>(n);
    publisher.alive(samples_in);
    for (const auto& d : spotter.process({buffer.data(), static_cast<std::size_t>(n)})) {
      report(d);
      publisher.publish(d, now_ns());
    }
    return true;
  });
  publisher.flush();
  return tachi::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-voice: spots the spoken start/stop cutting commands and publishes them"};
  app.name("tachi-voice");
  Options o;
  auto* wav = app.add_option("--wav", o.wav, "Process a WAV file (16-bit PCM, any rate/channels) and exit")
                  ->check(CLI::ExistingFile);
  auto* raw = app.add_option("--raw", o.raw, "Process a headerless 16 kHz s16le mono file and exit")->check(CLI::ExistingFile);
  auto* device = app.add_option("--device", o.device, "Listen to an ALSA capture device (e.g. default, hw:1,0)");
  auto* kinect = app.add_flag("--kinect-mic", o.kinect_mic, "Listen to the Kinect v1's microphone array");
  app.add_option("--kinect-index", o.kinect_index, "Which Kinect, with --kinect-mic")->check(CLI::Range(0, 15));
  wav->excludes(raw)->excludes(device)->excludes(kinect);
  raw->excludes(device)->excludes(kinect);
  device->excludes(kinect);
  app.add_option("--config", o.config_file, "Voice config JSON (see config/voice.json)")->check(CLI::ExistingFile);
  app.add_option("--start-phrase", o.start_phrase, "Phrase that starts cutting (default \"begin cutting\"; \"start cutting\" was the default before issue 22)");
  app.add_option("--stop-phrase", o.stop_phrase, "Phrase that stops cutting (default \"stop cutting\")");
  app.add_option("--grab-phrase", o.grab_phrase, "Phrase that makes the hand grab the cloth (none by default; e.g. \"grab cloth\")");
  app.add_option("--release-phrase", o.release_phrase, "Phrase that lets the grabbed cloth go (none by default; e.g. \"release cloth\")");
  app.add_flag("--no-dds", o.no_dds, "Do not publish on the bus; only print");
  app.add_option("--wait-readers", o.wait_readers_s, "With a file: seconds to wait for a subscriber before publishing")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  app.add_option("--source-id", o.source_id, "Key of the published commands")->capture_default_str();
  tachi::common::add_log_level_flag(app, o.log_level);
  tachi::common::add_bus_flags(app, o.bus);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  // Logs go to stderr: stdout carries the command lines (tachi-voice) and must stay parseable.
  tachi::common::set_log_level(o.log_level);
  o.use_device = device->count() > 0;

  tachi::sensor::VoiceConfig config;
  try {
    if (!o.config_file.empty()) config = tachi::sensor::load_voice_config(o.config_file);
    if (!o.start_phrase.empty()) tachi::sensor::set_phrase(config, tachi::sensor::VoiceCommand::Start, o.start_phrase);
    if (!o.stop_phrase.empty()) tachi::sensor::set_phrase(config, tachi::sensor::VoiceCommand::Stop, o.stop_phrase);
    if (!o.grab_phrase.empty()) tachi::sensor::set_phrase(config, tachi::sensor::VoiceCommand::Grab, o.grab_phrase);
    if (!o.release_phrase.empty()) tachi::sensor::set_phrase(config, tachi::sensor::VoiceCommand::Release, o.release_phrase);
    if (const auto why = tachi::sensor::validate(config)) throw std::invalid_argument(*why);
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi-voice: " << e.what() << '\n';
    return tachi::common::kExitUsage;
  }
  tachi::common::install_stop_handlers();
  try {
    if (!o.wav.empty() || !o.raw.empty()) return run_file(o, config);
    if (!o.use_device && !o.kinect_mic) {
      std::cerr << "tachi-voice: give an input: --wav FILE, --raw FILE, --device NAME or --kinect-mic\n";
      return tachi::common::kExitUsage;
    }
    return run_live(o, config);
  } catch (const tachi::sensor::AudioDeviceNotFound& e) {
    std::cerr << "tachi-voice: " << e.what() << '\n';
    return tachi::common::kExitNoDevice;
  }
} catch (const std::exception& e) {
  std::cerr << "tachi-voice: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
