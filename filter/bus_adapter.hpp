// The one place where tachi_filter's types meet the generated DDS messages.
#pragma once

#include "tachi.h"
#include "tachi/filter/types.hpp"

#include <cstdint>

namespace tachi::filter {

HandSample from_msg(const tachi_msg_RawHandSample& msg);
VoiceCommandKind from_msg(const tachi_msg_VoiceCommand& msg);
tachi_msg_StrokeSample to_msg(const StrokeSample& sample, std::uint32_t sensor_id);

}  // namespace tachi::filter
