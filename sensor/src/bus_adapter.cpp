#include "bus_adapter.hpp"

#include <cstdio>

namespace tachi::sensor {

tachi_msg_RawHandSample to_msg(const HandObservation& hand, std::uint32_t sensor_id, std::uint64_t frame,
                               std::int64_t capture_time_ns, std::int64_t acquired_ns) {
  tachi_msg_RawHandSample m{};
  m.sensor_id = sensor_id;
  m.frame = frame;
  m.capture_time_ns = capture_time_ns;
  m.acquired_ns = acquired_ns;
  if (hand.tracked) {
    m.position_m = {hand.position_m.x(), hand.position_m.y(), hand.position_m.z()};
    m.pixel_u = hand.u;
    m.pixel_v = hand.v;
    m.confidence = hand.confidence;
  }
  m.tracked = hand.tracked;
  return m;
}

tachi_msg_VoiceCommand to_msg(const VoiceDetection& d, std::uint32_t source_id, std::int64_t time_ns) {
  tachi_msg_VoiceCommand msg{};
  msg.source_id = source_id;
  msg.time_ns = time_ns;
  switch (d.command) {
    case VoiceCommand::Start: msg.command = tachi_msg_VOICE_START; break;
    case VoiceCommand::Stop: msg.command = tachi_msg_VOICE_STOP; break;
    case VoiceCommand::Grab: msg.command = tachi_msg_VOICE_GRAB; break;
    case VoiceCommand::Release: msg.command = tachi_msg_VOICE_RELEASE; break;
  }
  std::snprintf(msg.phrase, sizeof msg.phrase, "%s", d.phrase.c_str());
  return msg;
}

}  // namespace tachi::sensor
