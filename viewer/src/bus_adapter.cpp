#include "bus_adapter.hpp"

namespace tachi::viewer {

TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg) {
  TopologyUpdate update;
  update.version = msg.version;
  update.session_id = msg.session_id;
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

namespace {
// 4096 x 4096 particles (tachi-sim's largest grid), cut up to twice over.
constexpr std::size_t kMaxParticles = std::size_t{4096} * 4096 * 2;
}  // namespace

bool plausible(const tachi_msg_ClothTopology& msg, bus::InputGuard& guard) {
  const std::size_t particles = msg.particle_grid._length;
  if (!guard.size(particles, kMaxParticles) || !guard.size(msg.triangles._length, 6 * kMaxParticles, 3)) return false;
  if (msg.pinned._length != particles) return guard.reject("inconsistent_topology");
  for (std::uint32_t i = 0; i < msg.triangles._length; ++i)
    if (msg.triangles._buffer[i] >= particles) return guard.reject("inconsistent_topology");
  return true;
}

bool plausible(const tachi_msg_ClothState& msg, bus::InputGuard& guard) {
  return guard.size(msg.positions._length, 3 * kMaxParticles, 3);
}

}  // namespace tachi::viewer
