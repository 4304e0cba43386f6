#include "tachi/viewer/scene_state.hpp"

#include <sstream>

namespace tachi::viewer {

void SceneState::on_topology(TopologyUpdate update) {
  // An older topology of the same simulator run arriving late changes nothing. The first one, and the
  // first of a new run (a restarted simulator counts versions afresh), is taken whatever its version.
  if (!scene_.mesh.triangles.empty() && update.session_id == session_id_ && update.version < scene_.mesh.topology_version)
    return;
  session_id_ = update.session_id;
  scene_.mesh.topology_version = update.version;
  scene_.mesh.triangles = std::move(update.triangles);
  scene_.mesh.pinned = std::move(update.pinned);
  update_status();
}

void SceneState::on_state(StateUpdate update) {
  scene_.mesh.positions = std::move(update.positions);
  positions_version_ = update.topology_version;
  frame_ = update.frame;
  ++states_received_;
  update_status();
}

void SceneState::on_hand(const HandUpdate& update) {
  const bool lost = !update.tracked || !update.position_m.allFinite();
  const bool was_lost = !scene_.hand;
  if (lost) {
    scene_.hand.reset();
  } else {
    scene_.hand = Hand{update.position_m, update.cutting ? HandState::Cutting : HandState::Idle, update.outside_cloth};
    if (update.cutting) {
      // A new stroke replaces the trail of the previous one; the last stroke stays visible until then.
      if (update.stroke_id != stroke_id_) scene_.stroke.clear();
      stroke_id_ = update.stroke_id;
      scene_.stroke.push_back(update.position_m);
    }
  }
  if (lost != was_lost) update_status();
}

void SceneState::update_status() {
  std::ostringstream status;
  if (scene_.mesh.triangles.empty()) {
    status << "waiting for the cloth topology";
  } else if (scene_.mesh.positions.empty()) {
    status << "waiting for cloth positions";
  } else {
    status << "frame " << frame_ << "  topology v" << scene_.mesh.topology_version;
    if (positions_version_ != scene_.mesh.topology_version) status << " (positions v" << positions_version_ << ")";
    status << "  particles " << scene_.mesh.positions.size();
  }
  if (!scene_.hand) status << "  hand: lost";
  scene_.status = status.str();
}

}  // namespace tachi::viewer
