// DDS messages <-> the viewer's own update types (the one place the viewer sees generated C types).
#pragma once

#include "tachi/bus/input_guard.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/bus/topology_assembler.hpp"
#include "tachi/viewer/controls.hpp"
#include "tachi/viewer/scene_state.hpp"

#include <optional>
#include <vector>

namespace tachi::viewer {
TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg);
/// The topology a TopologyAssembler built from keyframes and deltas; takes its split-off list.
TopologyUpdate from_assembler(bus::TopologyAssembler& topology);
StateUpdate from_msg(const tachi_msg_ClothState& msg);
HandUpdate from_msg(const tachi_msg_StrokeSample& msg);
CutUpdate from_msg(const tachi_msg_CutEvent& msg);

/// "cutting (mouse)", "idle (voice)": the gate and what opened the current/last stroke, for the HUD.
std::string gate_label(tachi_msg_GateState gate, tachi_msg_GateSource opened_by);

/// Who publishes the mouse blade's samples: its own hand source on tachi/hand/stroke.
struct MouseSource {
  std::uint32_t sensor_id = 0;
  std::uint64_t session_id = 0;
};
/// A mouse blade sample as a StrokeSample: gate CUTTING (tracked) while the button is held, IDLE
/// (untracked) on release, opened by GATE_SOURCE_MOUSE, acquired_ns = time_ns = the mouse event's
/// wall-clock time.
tachi_msg_StrokeSample to_msg(const BladeSample& sample, const MouseSource& source, std::uint64_t frame,
                              std::int64_t event_ns);

/// A topology whose arrays disagree (a triangle naming a particle that does not exist, pinned flags
/// for another particle count, more particles than any cloth tachi-sim builds) is refused before it
/// reaches the scene, with its reason counted in `guard`.
bool plausible(const tachi_msg_ClothTopology& msg, bus::InputGuard& guard);
bool plausible(const tachi_msg_ClothState& msg, bus::InputGuard& guard);

/// An object's points (what the cloth drapes over), thinned to at most `max_drawn` evenly
/// spread ones (a depth frame's scene is ~300,000 points; dots beyond a few thousand add nothing to the
/// view and cost every frame). Refused, counted in `guard`, when the sequence is not xyz triples or
/// larger than any cloud tachi-sim loads (`oversized`), or a point is non-finite (`nonfinite`) or
/// beyond 100 m (`out_of_range`).
std::optional<std::vector<Eigen::Vector3f>> object_points(const tachi_msg_SceneObject& msg, bus::InputGuard& guard,
                                                          std::size_t max_drawn);
}  // namespace tachi::viewer
