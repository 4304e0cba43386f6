// The one place where the sensor's types meet the generated DDS types (tachi.idl).
#pragma once

#include <cstdint>

#include "tachi.h"
#include "tachi/sensor/hand_finder.hpp"
#include "tachi/sensor/voice_spotter.hpp"

namespace tachi::sensor {

/// A RawHandSample for one depth frame (position and pixel are zero when the hand is lost).
/// `acquired_ns`: wall clock when the frame reached this process (end-to-end latency starts there).
tachi_msg_RawHandSample to_msg(const HandObservation& hand, std::uint32_t sensor_id, std::uint64_t frame,
                               std::int64_t capture_time_ns, std::int64_t acquired_ns = 0);

/// A VoiceCommand for a spotted phrase (the phrase cut to the message's 63 characters), `time_ns` on the
/// hand samples' clock.
tachi_msg_VoiceCommand to_msg(const VoiceDetection& detection, std::uint32_t source_id, std::int64_t time_ns);

}  // namespace tachi::sensor
