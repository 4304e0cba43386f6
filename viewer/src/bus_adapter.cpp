#include "bus_adapter.hpp"

namespace tachi::viewer {

TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg) {
  TopologyUpdate update;
  update.version = msg.version;
  const std::size_t count = msg.triangles._length / 3;
  update.triangles.resize(count);
  for (std::size_t t = 0; t < count; ++t)
    update.triangles[t] = {msg.triangles._buffer[3 * t], msg.triangles._buffer[3 * t + 1], msg.triangles._buffer[3 * t + 2]};
  update.pinned.assign(msg.pinned._buffer, msg.pinned._buffer + msg.pinned._length);
  return update;
}

StateUpdate from_msg(const tachi_msg_ClothState& msg) {
  StateUpdate update;
  update.frame = msg.frame;
  update.topology_version = msg.topology_version;
  const std::size_t count = msg.positions._length / 3;
  update.positions.resize(count);
  for (std::size_t i = 0; i < count; ++i)
    update.positions[i] = {msg.positions._buffer[3 * i], msg.positions._buffer[3 * i + 1], msg.positions._buffer[3 * i + 2]};
  return update;
}

HandUpdate from_msg(const tachi_msg_StrokeSample& msg) {
  return {msg.stroke_id, {msg.position_m.x, msg.position_m.y, msg.position_m.z}, msg.tracked,
          msg.gate == tachi_msg_GATE_CUTTING, msg.hand_outside_cloth};
}

}  // namespace tachi::viewer
