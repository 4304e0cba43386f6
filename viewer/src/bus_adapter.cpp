#include "bus_adapter.hpp"

#include "tachi/bus/topics.hpp"

namespace tachi::viewer {
namespace {
std::uint32_t packed(const tachi_msg_GridCoord& g) { return std::uint32_t{g.u} | std::uint32_t{g.v} << 16; }
}  // namespace

TopologyUpdate from_msg(const tachi_msg_ClothTopology& msg) {
  TopologyUpdate update;
  update.version = msg.version;
  update.session_id = msg.session_id;
  update.columns = msg.columns;
  update.rows = msg.rows;
  update.malformed = msg.triangles._length % 3 != 0 ||
                     (msg.pinned._length != 0 && msg.particle_grid._length != 0 && msg.pinned._length != msg.particle_grid._length);
  const std::size_t count = msg.triangles._length / 3;
  update.triangles.resize(count);
  for (std::size_t t = 0; t < count; ++t)
    update.triangles[t] = {msg.triangles._buffer[3 * t], msg.triangles._buffer[3 * t + 1], msg.triangles._buffer[3 * t + 2]};
  update.pinned.assign(msg.pinned._buffer, msg.pinned._buffer + msg.pinned._length);
  update.duplicated_from.assign(msg.duplicated_from._buffer, msg.duplicated_from._buffer + msg.duplicated_from._length);
  update.grid.resize(msg.particle_grid._length);
  for (std::size_t i = 0; i < update.grid.size(); ++i) update.grid[i] = packed(msg.particle_grid._buffer[i]);
  return update;
}

TopologyUpdate from_assembler(bus::TopologyAssembler& topology) {
  TopologyUpdate update;
  update.version = topology.version();
  update.session_id = topology.session_id();
  update.columns = topology.columns();
  update.rows = topology.rows();
  update.triangles = topology.triangles();
  update.pinned = topology.pinned();
  update.grid.reserve(topology.particle_grid().size());
  for (const tachi_msg_GridCoord& g : topology.particle_grid()) update.grid.push_back(packed(g));
  update.duplicated_from = topology.take_duplicated_from();
  return update;
}

StateUpdate from_msg(const tachi_msg_ClothState& msg) {
  StateUpdate update;
  update.frame = msg.frame;
  update.topology_version = msg.topology_version;
  update.session_id = msg.session_id;
  update.acquired_ns = msg.acquired_ns;
  update.held_particle = msg.held_particle;
  update.malformed = msg.positions._length % 3 != 0;
  const std::size_t count = msg.positions._length / 3;
  update.positions.resize(count);
  for (std::size_t i = 0; i < count; ++i)
    update.positions[i] = {msg.positions._buffer[3 * i], msg.positions._buffer[3 * i + 1], msg.positions._buffer[3 * i + 2]};
  return update;
}

std::string gate_label(tachi_msg_GateState gate, tachi_msg_GateSource opened_by) {
  std::string label;
  switch (gate) {
    case tachi_msg_GATE_IDLE: label = "idle"; break;
    case tachi_msg_GATE_CUTTING: label = "cutting"; break;
    case tachi_msg_GATE_HOLDING: label = "holding"; break;
    case tachi_msg_GATE_GRABBING: label = "grabbing"; break;
  }
  switch (opened_by) {
    case tachi_msg_GATE_SOURCE_NONE: break;
    case tachi_msg_GATE_SOURCE_THRESHOLD: label += " (threshold)"; break;
    case tachi_msg_GATE_SOURCE_VOICE: label += " (voice)"; break;
    case tachi_msg_GATE_SOURCE_MOUSE: label += " (mouse)"; break;
  }
  return label;
}

HandUpdate from_msg(const tachi_msg_StrokeSample& msg) {
  HandUpdate update;
  update.stroke_id = msg.stroke_id;
  update.position_m = {msg.position_m.x, msg.position_m.y, msg.position_m.z};
  update.tracked = msg.tracked;
  update.cutting = msg.gate == tachi_msg_GATE_CUTTING;
  update.outside_cloth = msg.hand_outside_cloth;
  update.sensor_id = msg.sensor_id;
  update.session_id = msg.session_id;
  update.gate = gate_label(msg.gate, msg.opened_by);
  return update;
}

CutUpdate from_msg(const tachi_msg_CutEvent& msg) {
  CutUpdate update;
  update.stroke_id = msg.stroke_id;
  update.topology_version = msg.topology_version;
  update.cut_line.resize(msg.cut_line._length);
  for (std::size_t i = 0; i < update.cut_line.size(); ++i) update.cut_line[i] = packed(msg.cut_line._buffer[i]);
  update.pieces = msg.pieces;
  update.fallen_pieces = msg.fallen_pieces;
  update.session_id = msg.session_id;
  update.sensor_id = msg.sensor_id;
  return update;
}

tachi_msg_StrokeSample to_msg(const BladeSample& sample, const MouseSource& source, std::uint64_t frame,
                              std::int64_t event_ns) {
  tachi_msg_StrokeSample msg{};
  msg.sensor_id = source.sensor_id;
  msg.session_id = source.session_id;
  msg.stroke_id = sample.stroke_id;
  msg.frame = frame;
  msg.time_ns = event_ns;
  msg.acquired_ns = event_ns;
  msg.position_m = {sample.position_m.x(), sample.position_m.y(), sample.position_m.z()};
  // The closing sample is untracked: the stroke ends, and the simulator does not keep the released
  // cursor as a hand pushing the cloth (tachi-sim --hand-radius).
  msg.tracked = sample.cutting;
  msg.gate = sample.cutting ? tachi_msg_GATE_CUTTING : tachi_msg_GATE_IDLE;
  msg.opened_by = tachi_msg_GATE_SOURCE_MOUSE;
  msg.closed_by = sample.cutting ? tachi_msg_GATE_SOURCE_NONE : tachi_msg_GATE_SOURCE_MOUSE;
  msg.hand_outside_cloth = sample.outside_cloth;
  msg.distance_to_cloth_m = sample.outside_cloth ? -1.0f : 0.0f;
  return msg;
}

namespace {
// The largest cloth tachi-sim simulates live, cut up to twice over (the filter takes the same bound).
constexpr std::size_t kMaxParticles = bus::topics::kMaxClothStateFloats / 3;
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

std::optional<std::vector<Eigen::Vector3f>> object_points(const tachi_msg_SceneObject& msg, bus::InputGuard& guard,
                                                          std::size_t max_drawn) {
  constexpr std::size_t kMaxObjectPoints = std::size_t{4} << 20;  // a 640 x 480 depth frame is 0.3 M
  constexpr float kMaxCoordinate_m = 100.0F;
  if (!guard.size(msg.points._length, 3 * kMaxObjectPoints, 3)) return std::nullopt;
  const std::size_t n = msg.points._length / 3;
  const std::size_t stride = max_drawn == 0 ? 1 : std::max<std::size_t>(1, (n + max_drawn - 1) / max_drawn);
  std::vector<Eigen::Vector3f> points;
  points.reserve(n / stride + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = msg.points._buffer + 3 * i;
    if (!guard.position(p[0], p[1], p[2], kMaxCoordinate_m)) return std::nullopt;
    if (i % stride == 0) points.emplace_back(p[0], p[1], p[2]);
  }
  return points;
}

}  // namespace tachi::viewer
