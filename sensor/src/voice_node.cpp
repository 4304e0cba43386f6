#include "bus_adapter.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/latency.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/sensor/node.hpp"
#include "tachi/sensor/voice_audio.hpp"
#include "tachi/sensor/voice_spotter.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <optional>

namespace tachi::sensor {
namespace {

void report(const VoiceDetection& d) {
  std::printf("%.3f,%s,%s\n", d.time_s, to_string(d.command).c_str(), d.phrase.c_str());
  if (!std::isnan(d.verification_score))
    spdlog::debug("\"{}\" at {:.3f} s: second-pass log-likelihood ratio {:.2f} per frame, {:.2f} above the best other command", d.phrase,
                  d.time_s, d.verification_score, d.command_margin);
  std::fflush(stdout);
}

/// Publishes commands; nothing without a participant (--no-dds).
class CommandPublisher {
 public:
  CommandPublisher(std::uint32_t source_id, bus::Participant* dds)
      : source_id_(source_id), waiting_for_filter_("tachi-filter", dds ? dds->domain() : 0) {
    if (dds == nullptr) return;
    writer_.emplace(*dds, bus::topics::voice_command);
    heartbeat_.emplace(*dds, "tachi-voice");
  }
  /// Heartbeat on tachi/node/status (no-op without DDS).
  void alive(std::uint64_t samples_in) {
    if (heartbeat_) heartbeat_->update(tachi_msg_NODE_RUNNING, samples_in, published_);
    if (writer_) waiting_for_filter_.warn_if_waiting(writer_->matched_readers() > 0);
  }
  void wait_for_readers(double seconds) {
    if (writer_ && seconds > 0 && !writer_->wait_for_readers(1, std::chrono::milliseconds(static_cast<long>(seconds * 1000))))
      spdlog::warn("no subscriber to {} after {} s; publishing anyway", bus::topics::voice_command.name, seconds);
  }
  void publish(const VoiceDetection& d, std::int64_t time_ns) {
    if (!writer_) return;
    writer_->write(to_msg(d, source_id_, time_ns));
    ++published_;
  }
  /// Reliable delivery of what was written before the process exits.
  void flush() {
    if (writer_) writer_->wait_for_acks(std::chrono::seconds(2));
  }

 private:
  std::uint32_t source_id_;
  std::optional<bus::Writer<tachi_msg_VoiceCommand>> writer_;
  std::optional<bus::Heartbeat> heartbeat_;
  common::PeerWait waiting_for_filter_;
  std::uint64_t published_ = 0;
};

}  // namespace

struct VoiceNode::Impl {
  static constexpr std::size_t kBlock = 512;

  Impl(const VoiceNodeOptions& options, const VoiceConfig& config, bus::Participant* dds)
      : o(options), from_file(!o.wav.empty() || !o.raw.empty()), spotter(config), publisher(o.source_id, dds) {
    if (from_file) {
      samples = resample_to_16k(o.wav.empty() ? read_raw_file(o.raw) : read_wav_file(o.wav));
      publisher.wait_for_readers(o.wait_readers_s);
      start_ns = common::wall_clock_ns();
      return;
    }
    source = o.kinect_mic ? open_kinect_mic_source(o.kinect_index) : open_alsa_source(o.device);
    spdlog::info("listening on {}", o.kinect_mic ? "the Kinect's microphones" : "audio device '" + o.device + "'");
    samples.resize(kBlock);
  }

  void say(const std::vector<VoiceDetection>& detections, bool at_stream_time) {
    for (const auto& d : detections) {
      report(d);
      // A file's commands are stamped by their place in the audio; a device's when they are spotted.
      publisher.publish(d, at_stream_time ? start_ns + static_cast<std::int64_t>(d.time_s * 1e9) : common::wall_clock_ns());
      ++count;
    }
  }

  bool spin_once() {
    if (from_file) {
      if (at >= samples.size()) return false;
      const std::span<const std::int16_t> block{samples.data() + at, std::min(kBlock, samples.size() - at)};
      at += kBlock;
      say(spotter.process(block), true);
      return true;
    }
    const long n = source->read(samples);
    if (n < 0) return false;
    samples_in += static_cast<std::uint64_t>(n);
    publisher.alive(samples_in);
    say(spotter.process({samples.data(), static_cast<std::size_t>(n)}), false);
    return true;
  }

  int finish() {
    if (from_file) say(spotter.finish(), true);
    publisher.flush();
    if (from_file) spdlog::info("{:.2f} s of audio, {} commands", spotter.time_s(), count);
    return common::kExitOk;
  }

  const VoiceNodeOptions o;
  const bool from_file;
  KeywordSpotter spotter;
  CommandPublisher publisher;
  std::vector<std::int16_t> samples;  // a file's audio at 16 kHz, or the device's read buffer
  std::unique_ptr<AudioSource> source;
  std::size_t at = 0;
  std::int64_t start_ns = 0;
  std::uint64_t samples_in = 0;
  std::size_t count = 0;
};

VoiceNode::VoiceNode(const VoiceNodeOptions& options, const VoiceConfig& config, bus::Participant* dds)
    : impl_(std::make_unique<Impl>(options, config, dds)) {}
VoiceNode::~VoiceNode() = default;
bool VoiceNode::spin_once() { return impl_->spin_once(); }
int VoiceNode::finish() { return impl_->finish(); }

}  // namespace tachi::sensor
