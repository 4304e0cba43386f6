#include "bus_adapter.hpp"

namespace tachi::filter {

namespace {
tachi_msg_GateSource to_msg(GateSource s) {
  switch (s) {
    case GateSource::Threshold: return tachi_msg_GATE_SOURCE_THRESHOLD;
    case GateSource::Voice: return tachi_msg_GATE_SOURCE_VOICE;
    case GateSource::None: break;
  }
  return tachi_msg_GATE_SOURCE_NONE;
}
}  // namespace

HandSample from_msg(const tachi_msg_RawHandSample& msg) {
  HandSample s;
  s.frame = msg.frame;
  s.stamp_ns = msg.capture_time_ns;
  s.position_m = {msg.position_m.x, msg.position_m.y, msg.position_m.z};
  s.tracked = msg.tracked;
  s.confidence = msg.confidence;
  return s;
}

VoiceCommandKind from_msg(const tachi_msg_VoiceCommand& msg) {
  switch (msg.command) {
    case tachi_msg_VOICE_START: return VoiceCommandKind::Start;
    case tachi_msg_VOICE_GRAB: return VoiceCommandKind::Grab;
    case tachi_msg_VOICE_RELEASE: return VoiceCommandKind::Release;
    default: return VoiceCommandKind::Stop;
  }
}

tachi_msg_StrokeSample to_msg(const StrokeSample& s, std::uint32_t sensor_id, std::uint64_t session_id) {
  tachi_msg_StrokeSample m{};
  m.sensor_id = sensor_id;
  m.session_id = session_id;
  m.stroke_id = s.stroke_id;
  m.frame = s.frame;
  m.time_ns = s.stamp_ns;
  m.position_m = {s.position_m.x(), s.position_m.y(), s.position_m.z()};
  m.tracked = s.tracked;
  m.gate = s.gate == GateOutput::Cutting   ? tachi_msg_GATE_CUTTING
           : s.gate == GateOutput::Holding ? tachi_msg_GATE_HOLDING
           : s.gate == GateOutput::Grabbing ? tachi_msg_GATE_GRABBING
                                           : tachi_msg_GATE_IDLE;
  m.opened_by = to_msg(s.opened_by);
  m.closed_by = to_msg(s.closed_by);
  m.hand_outside_cloth = s.hand_outside_cloth;
  m.distance_to_cloth_m = s.distance_to_cloth_m;
  return m;
}

}  // namespace tachi::filter
