// DDS messages -> the viewer's own update types (the one place the viewer sees generated C types).
#pragma once

#include "tachi/bus/input_guard.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/viewer/scene_state.hpp"

namespace tachi::viewer {
TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg);
StateUpdate from_msg(const tachi_msg_ClothState& msg);
HandUpdate from_msg(const tachi_msg_StrokeSample& msg);

/// A topology whose arrays disagree (a triangle naming a particle that does not exist, pinned flags
/// for another particle count, more particles than any cloth tachi-sim builds) is refused before it
/// reaches the scene, with its reason counted in `guard` (issue 13).
bool plausible(const tachi_msg_ClothTopology& msg, bus::InputGuard& guard);
bool plausible(const tachi_msg_ClothState& msg, bus::InputGuard& guard);
}  // namespace tachi::viewer
