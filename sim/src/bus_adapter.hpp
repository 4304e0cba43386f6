// The simulator's edge to the DDS bus: Cloth -> ClothTopology / ClothState / CutEvent messages,
// StrokeSample -> the simulator's own stroke input. Only tachi-sim links this (the tachi_sim
// library stays free of DDS). Messages point into buffers owned here, written without a copy.
#pragma once

#include "tachi/bus/topics.hpp"
#include "tachi/sim/blade.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cutting.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace tachi::sim {

/// A hand sample as the simulator uses it (world frame, seconds on the sender's clock).
struct StrokeInput {
  std::uint32_t sensor_id = 0;
  std::uint64_t session_id = 0;  ///< the publishing filter's run
  std::uint32_t stroke_id = 0;
  double time_s = 0.0;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  bool tracked = false;
  bool cutting = false;
  bool holding = false;
  bool grabbing = false;  ///< GATE_GRABBING: the hand holds the cloth
};

/// The blade as tachi.idl names it (the value of tachi-sim's heartbeat metric "blade").
tachi_msg_Blade to_msg(Blade blade);

/// Rejects samples a filter should never send but a faulty peer might: non-finite coordinates or a
/// hand absurdly far from the cloth (> 100 m). Returns nothing for those.
std::optional<StrokeInput> from_msg(const tachi_msg_StrokeSample& msg);

/// Owns the arrays a ClothTopology message points into.
class TopologyMessage {
 public:
  /// Full topology of `cloth` (live triangles only) plus the change list since the previously
  /// filled version (the change may merge several cuts).
  void fill(std::uint32_t cloth_id, const Cloth& cloth, const TopologyChange* change, std::uint64_t session_id = 0);
  const tachi_msg_ClothTopology& msg() const { return msg_; }
  /// Bytes of sequence payload the last filled message carries (what a cut costs on the wire, headers aside).
  [[nodiscard]] std::size_t payload_bytes() const;

 private:
  tachi_msg_ClothTopology msg_{};
  std::optional<std::uint32_t> published_version_;
  std::vector<std::uint32_t> triangles_;
  std::vector<tachi_msg_GridCoord> grid_;
  std::vector<std::uint8_t> pinned_;
  std::vector<std::uint32_t> duplicated_from_;
  std::vector<std::uint32_t> changed_triangles_;
};

/// Owns the arrays a ClothTopologyDelta message points into, and the triangles as last published, so that a
/// change (which names triangle slots) becomes the removed and added vertex triples a reader can apply.
class TopologyDeltaMessage {
 public:
  /// Remembers the cloth as published (the keyframe).
  explicit TopologyDeltaMessage(const Cloth& cloth);
  /// What changed since the last fill (or the construction), as a delta from base to cloth.topology_version.
  void fill(std::uint32_t cloth_id, const Cloth& cloth, const TopologyChange& change, std::uint64_t session_id);
  const tachi_msg_ClothTopologyDelta& msg() const { return msg_; }
  [[nodiscard]] std::size_t payload_bytes() const;

 private:
  tachi_msg_ClothTopologyDelta msg_{};
  std::uint32_t version_;
  std::size_t particles_;
  std::vector<std::array<std::uint32_t, 3>> published_;  // per triangle slot
  std::vector<std::uint8_t> published_alive_;
  std::vector<tachi_msg_GridCoord> grid_;
  std::vector<std::uint8_t> pinned_;
  std::vector<std::uint32_t> removed_;
  std::vector<std::uint32_t> added_;
  std::vector<std::uint32_t> duplicated_from_;
};

/// A ClothState message whose positions point straight at the cloth's position array
/// (Eigen::Vector3f is three packed floats). Valid until the cloth's particle arrays grow.
/// `held`: the particle the hand holds (held_particle, -1 when none).
tachi_msg_ClothState state_msg(std::uint32_t cloth_id, std::uint64_t frame, double sim_time_s, const Cloth& cloth,
                               std::uint64_t session_id = 0, std::optional<std::uint32_t> held = std::nullopt);

/// Owns the array a SceneObject message points into.
class ObjectMessage {
 public:
  const tachi_msg_SceneObject& fill(std::uint32_t cloth_id, const std::vector<Eigen::Vector3f>& points,
                                    std::uint64_t session_id = 0);

 private:
  tachi_msg_SceneObject msg_{};
  std::vector<float> xyz_;
};

}  // namespace tachi::sim
