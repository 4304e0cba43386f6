#include "foxglove.hpp"

namespace tachi::launcher {
namespace {
using nlohmann::json;

json stamp(std::uint64_t ns) { return {{"sec", ns / 1'000'000'000ULL}, {"nsec", ns % 1'000'000'000ULL}}; }
json vec3(double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}}; }
json identity_pose() { return {{"position", vec3(0, 0, 0)}, {"orientation", {{"x", 0}, {"y", 0}, {"z", 0}, {"w", 1}}}}; }
json color(double r, double g, double b, double a) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }

// The parts of Foxglove's schemas this program fills; Foxglove recognises the channels by schema name.
constexpr const char* kTimeSchema = R"({"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}})";

}  // namespace

const std::vector<FoxgloveChannel>& foxglove_channels() {
  static const std::string scene = std::string(R"({"title":"foxglove.SceneUpdate","type":"object","properties":{)"
                                               R"("deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object","properties":{)"
                                               R"("timestamp":)") + kTimeSchema +
                                   R"(,"frame_id":{"type":"string"},"id":{"type":"string"},"triangles":{"type":"array"},"lines":{"type":"array"}}}}}})";
  static const std::string hand = std::string(R"({"title":"foxglove.PoseInFrame","type":"object","properties":{"timestamp":)") +
                                  kTimeSchema + R"(,"frame_id":{"type":"string"},"pose":{"type":"object"}}})";
  static const std::string latency =
      R"({"title":"tachi.Latency","type":"object","properties":{"e2e_ms":{"type":"number","description":"depth frame capture -> this cloth state published"},)"
      R"("stage_p50_ms":{"type":"object","additionalProperties":{"type":"number"},"description":"each node's heartbeat latency_p50_ms"}}})";
  static const std::vector<FoxgloveChannel> channels{{"/foxglove/cloth", "foxglove.SceneUpdate", scene.c_str()},
                                                     {"/foxglove/hand", "foxglove.PoseInFrame", hand.c_str()},
                                                     {"/foxglove/latency", "tachi.Latency", latency.c_str()}};
  return channels;
}

void FoxgloveScene::on_status(const tachi_msg_NodeStatus& m) {
  for (std::uint32_t i = 0; i < m.metrics._length; ++i)
    if (std::string(m.metrics._buffer[i].name) == "latency_p50_ms") stage_p50_ms_[m.node] = m.metrics._buffer[i].value;
}

json FoxgloveScene::on_stroke(const tachi_msg_StrokeSample& m, std::uint64_t time_ns) {
  if (m.tracked && m.gate == tachi_msg_GATE_CUTTING) cuts_[{m.sensor_id, m.stroke_id}].push_back(m.position_m);
  json pose = identity_pose();
  pose["position"] = vec3(m.position_m.x, m.position_m.y, m.position_m.z);
  return {{"timestamp", stamp(time_ns)}, {"frame_id", "cloth"}, {"pose", pose}};
}

std::optional<FoxgloveScene::Frame> FoxgloveScene::on_state(const tachi_msg_ClothState& m, std::uint64_t time_ns) {
  if (!assembler_.has_topology() || m.topology_version != assembler_.version() ||
      m.positions._length != 3 * assembler_.particle_count())
    return std::nullopt;  // positions of another topology than the one held: wait for it
  if (last_cloth_ns_ && static_cast<std::int64_t>(time_ns - *last_cloth_ns_) < min_interval_ns_) return std::nullopt;
  last_cloth_ns_ = time_ns;

  json points = json::array();
  for (std::uint32_t i = 0; i + 2 < m.positions._length; i += 3)
    points.push_back(vec3(m.positions._buffer[i], m.positions._buffer[i + 1], m.positions._buffer[i + 2]));
  json indices = json::array();
  for (const auto& t : assembler_.triangles())
    for (const auto v : t) indices.push_back(v);
  json lines = json::array();
  for (const auto& [key, path] : cuts_) {
    json line_points = json::array();
    for (const auto& p : path) line_points.push_back(vec3(p.x, p.y, p.z));
    lines.push_back({{"type", 0}, {"pose", identity_pose()}, {"thickness", 4}, {"scale_invariant", true},
                     {"points", line_points}, {"color", color(0.9, 0.1, 0.1, 1)}, {"colors", json::array()}, {"indices", json::array()}});
  }
  const json empty = json::array();
  json entity{{"timestamp", stamp(time_ns)}, {"frame_id", "cloth"}, {"id", "cloth"}, {"lifetime", {{"sec", 0}, {"nsec", 0}}},
              {"frame_locked", false}, {"metadata", {{{"key", "topology_version"}, {"value", std::to_string(m.topology_version)}}}},
              {"arrows", empty}, {"cubes", empty}, {"spheres", empty}, {"cylinders", empty}, {"lines", lines},
              {"triangles", {{{"pose", identity_pose()}, {"points", points}, {"color", color(0.75, 0.7, 0.6, 1)},
                              {"colors", empty}, {"indices", indices}}}},
              {"texts", empty}, {"models", empty}};
  Frame frame;
  frame.cloth = {{"deletions", empty}, {"entities", {entity}}};
  frame.latency = {{"stage_p50_ms", stage_p50_ms_}};
  if (m.acquired_ns > 0 && m.published_ns >= m.acquired_ns) frame.latency["e2e_ms"] = static_cast<double>(m.published_ns - m.acquired_ns) * 1e-6;
  return frame;
}

}  // namespace tachi::launcher
