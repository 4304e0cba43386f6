// The one place where tachi_filter's types meet the generated DDS messages.
#pragma once

#include "tachi.h"
#include "tachi/filter/types.hpp"

#include <cstdint>

namespace tachi::filter {

HandSample from_msg(const tachi_msg_RawHandSample& msg);
VoiceCommandKind from_msg(const tachi_msg_VoiceCommand& msg);
/// `session_id` names this filter run (bus::new_session_id): with sensor_id and stroke_id it names a stroke.
tachi_msg_StrokeSample to_msg(const StrokeSample& sample, std::uint32_t sensor_id, std::uint64_t session_id);

}  // namespace tachi::filter
