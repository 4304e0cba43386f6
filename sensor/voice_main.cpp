// tachi-voice: spots "begin cutting" / "stop cutting" (configurable) in a WAV file, a raw file, an ALSA
// capture device or the Kinect's microphones; prints time_s,command,phrase per command and publishes
// tachi_msg_VoiceCommand on the bus unless --no-dds: VoiceNode, run until the end or a signal.
#include "cli.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/node.hpp"
#include "tachi/sensor/voice_audio.hpp"

#include <exception>
#include <iostream>
#include <optional>

int main(int argc, char** argv) try {
  tachi::sensor::VoiceFlags flags;
  if (const int rc = tachi::sensor::parse_voice_flags(argc, argv, flags); rc >= 0) return rc;
  tachi::common::install_stop_handlers();
  std::optional<tachi::bus::Participant> dds;
  const auto& b = flags.bus;
  if (!flags.no_dds) dds.emplace(b.domain, b.dds_config, tachi::bus::Security{b.secure_dir, b.identity});
  std::optional<tachi::sensor::VoiceNode> node;
  try {
    node.emplace(flags.options, flags.config, dds ? &*dds : nullptr);
  } catch (const tachi::sensor::AudioDeviceNotFound& e) {
    std::cerr << "tachi-voice: " << e.what() << '\n';
    return tachi::common::kExitNoDevice;
  }
  return tachi::common::run_until_signal(*node);
} catch (const std::exception& e) {
  std::cerr << "tachi-voice: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
