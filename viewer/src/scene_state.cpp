#include "tachi/viewer/scene_state.hpp"

#include <cmath>
#include <sstream>

namespace tachi::viewer {

void SceneState::on_topology(TopologyUpdate update) {
  if (update.version < topology_.version) return;  // an older topology arriving late changes nothing
  topology_ = std::move(update);
}

void SceneState::on_state(StateUpdate update) {
  positions_ = std::move(update.positions);
  positions_version_ = update.topology_version;
  frame_ = update.frame;
  ++states_received_;
}

void SceneState::on_hand(const HandUpdate& update) {
  const bool finite = update.position_m.allFinite();
  if (!update.tracked || !finite) {
    hand_.reset();
    return;
  }
  hand_ = Hand{update.position_m, update.cutting ? HandState::Cutting : HandState::Idle, update.outside_cloth};
  if (update.cutting) {
    // A new stroke replaces the trail of the previous one; the last stroke stays visible until then.
    if (update.stroke_id != stroke_id_) stroke_.clear();
    stroke_id_ = update.stroke_id;
    stroke_.push_back(update.position_m);
  }
}

Scene SceneState::scene() const {
  Scene scene;
  scene.mesh.topology_version = topology_.version;
  scene.mesh.triangles = topology_.triangles;
  scene.mesh.pinned = topology_.pinned;
  scene.mesh.positions = positions_;
  scene.hand = hand_;
  scene.stroke = stroke_;
  std::ostringstream status;
  if (topology_.triangles.empty()) {
    status << "waiting for the cloth topology";
  } else if (positions_.empty()) {
    status << "waiting for cloth positions";
  } else {
    status << "frame " << frame_ << "  topology v" << topology_.version;
    if (positions_version_ != topology_.version) status << " (positions v" << positions_version_ << ")";
    status << "  particles " << positions_.size();
  }
  if (!hand_) status << "  hand: lost";
  scene.status = status.str();
  return scene;
}

}  // namespace tachi::viewer
