// DDS messages -> the viewer's own update types (the one place the viewer sees generated C types).
#pragma once

#include "tachi/bus/topics.hpp"
#include "tachi/viewer/scene_state.hpp"

namespace tachi::viewer {
TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg);
StateUpdate from_msg(const tachi_msg_ClothState& msg);
HandUpdate from_msg(const tachi_msg_StrokeSample& msg);
}  // namespace tachi::viewer
