// Assembles the scene to draw from the updates the pipeline publishes (topology, positions,
// hand strokes), in the viewer's own types; the DDS conversion is in the executable's adapter.
#pragma once

#include "tachi/viewer/render.hpp"

#include <cstdint>

namespace tachi::viewer {

struct TopologyUpdate {
  std::uint32_t version = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint8_t> pinned;
  std::uint64_t session_id = 0;  ///< the simulator run: a restarted simulator's versions start again
};

struct StateUpdate {
  std::uint64_t frame = 0;
  std::uint32_t topology_version = 0;
  std::vector<Eigen::Vector3f> positions;
};

struct HandUpdate {
  std::uint32_t stroke_id = 0;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  bool tracked = false;
  bool cutting = false;
  bool outside_cloth = false;
};

class SceneState {
 public:
  SceneState() { update_status(); }
  void on_topology(TopologyUpdate update);
  void on_state(StateUpdate update);
  void on_hand(const HandUpdate& update);

  /// The scene as it stands; the status line says what is missing or stale. Kept up to date by the
  /// updates, so drawing a frame copies nothing.
  const Scene& scene() const { return scene_; }
  bool has_cloth() const { return !scene_.mesh.positions.empty() && !scene_.mesh.triangles.empty(); }
  std::uint64_t states_received() const { return states_received_; }

 private:
  void update_status();

  Scene scene_;
  std::uint32_t positions_version_ = 0;
  std::uint64_t session_id_ = 0;
  std::uint64_t frame_ = 0;
  std::uint64_t states_received_ = 0;
  std::uint32_t stroke_id_ = 0;
};

}  // namespace tachi::viewer
