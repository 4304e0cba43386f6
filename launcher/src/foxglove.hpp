// `tachi record --foxglove`: channels derived from the bus in Foxglove's own JSON schemas, so
// Foxglove (or its open-source fork Lichtblick) shows the run with no tachi plugin: the cloth as a
// foxglove.SceneUpdate (a triangle list over the particles, the blade's path while it cut as a line
// strip), the hand as a foxglove.PoseInFrame, and each stage's latency as plottable numbers. Frame
// "cloth": the simulator's world frame (metres, cloth in z = 0, y up).
#pragma once

#include "tachi.h"
#include "tachi/bus/topology_assembler.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace tachi::launcher {

struct FoxgloveChannel {
  const char* topic;
  const char* schema_name;
  const char* schema;  ///< JSON Schema (draft 2020-12) of the messages this program writes there
};
/// The derived channels: /foxglove/cloth, /foxglove/hand, /foxglove/latency.
const std::vector<FoxgloveChannel>& foxglove_channels();

/// Turns tachi's messages into the derived channels' JSON messages. Pure: messages in, JSON out.
class FoxgloveScene {
 public:
  /// `min_interval_ns`: the cloth is redrawn at most this often (a 128 x 128 cloth is ~1 MB of JSON).
  explicit FoxgloveScene(std::int64_t min_interval_ns = 33'333'333) : min_interval_ns_(min_interval_ns) {}

  void on_topology(const tachi_msg_ClothTopology& m) { assembler_.on_keyframe(m); }
  void on_topology_delta(const tachi_msg_ClothTopologyDelta& m) { assembler_.on_delta(m); }
  void on_status(const tachi_msg_NodeStatus& m);
  /// The hand's pose (/foxglove/hand); while the gate cuts, its position extends the cut path.
  nlohmann::json on_stroke(const tachi_msg_StrokeSample& m, std::uint64_t time_ns);
  /// The cloth (/foxglove/cloth) and the latency figures (/foxglove/latency), when due and the topology is known.
  struct Frame {
    nlohmann::json cloth;
    nlohmann::json latency;
  };
  std::optional<Frame> on_state(const tachi_msg_ClothState& m, std::uint64_t time_ns);

 private:
  bus::TopologyAssembler assembler_;
  std::int64_t min_interval_ns_;
  std::optional<std::uint64_t> last_cloth_ns_;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<tachi_msg_Vec3>> cuts_;  ///< (sensor, stroke) -> blade path
  std::map<std::string, double> stage_p50_ms_;
};

}  // namespace tachi::launcher
