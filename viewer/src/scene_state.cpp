#include "tachi/viewer/scene_state.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

namespace tachi::viewer {
namespace {
std::size_t particle_count(const TopologyUpdate& update) {
  if (!update.grid.empty()) return update.grid.size();
  std::size_t count = 0;
  for (const auto& tri : update.triangles)
    for (const std::uint32_t i : tri) count = std::max<std::size_t>(count, std::size_t{i} + 1);
  return count;
}

std::optional<Rejection> check(const TopologyUpdate& update) {
  if (update.malformed || update.triangles.empty()) return Rejection::Malformed;
  const std::size_t particles = particle_count(update);
  if (particles > SceneState::kMaxParticles) return Rejection::OutOfRange;
  if (!update.pinned.empty() && update.pinned.size() != particles) return Rejection::Malformed;
  for (const auto& tri : update.triangles)
    if (tri[0] >= particles || tri[1] >= particles || tri[2] >= particles) return Rejection::OutOfRange;
  if (!update.grid.empty() && update.columns > 0 && update.rows > 0) {
    // Cuts duplicate particles, never remove them: the grid's particles are all there.
    if (particles < static_cast<std::size_t>(update.columns) * static_cast<std::size_t>(update.rows))
      return Rejection::Malformed;
    for (const std::uint32_t g : update.grid)
      if (static_cast<int>(g & 0xffffu) >= update.columns || static_cast<int>(g >> 16) >= update.rows)
        return Rejection::OutOfRange;
  }
  return std::nullopt;
}

std::optional<Rejection> check(const StateUpdate& update) {
  if (update.malformed) return Rejection::Malformed;
  if (update.positions.size() > SceneState::kMaxParticles) return Rejection::OutOfRange;
  for (const auto& p : update.positions) {
    if (!p.allFinite()) return Rejection::NonFinite;
    if (p.cwiseAbs().maxCoeff() > SceneState::kMaxCoordinate_m) return Rejection::OutOfRange;
  }
  return std::nullopt;
}
}  // namespace

std::string_view to_string(Rejection reason) {
  switch (reason) {
    case Rejection::Malformed: return "malformed";
    case Rejection::OutOfRange: return "out_of_range";
    case Rejection::NonFinite: return "nonfinite";
    case Rejection::VersionJump: return "version_jump";
    case Rejection::StaleSession: return "stale_session";
  }
  return "unknown";
}

Rejection SceneState::reject(Rejection reason) {
  ++rejected_total_;
  const auto name = to_string(reason);
  if (auto it = rejected_.find(name); it != rejected_.end()) {
    ++it->second;
  } else {
    rejected_.emplace(std::string(name), 1);
  }
  return reason;
}

void SceneState::adopt(TopologyUpdate update) {
  if (has_topology_ && update.session_id != session_id_) {
    // The simulator restarted: what was counted and cut belongs to the previous run.
    split_since_cut_.clear();
    pieces_.reset();
    fallen_.reset();
    scene_.cut_particles.clear();
    scene_.flash = 0.0f;
  }
  // Remember what the cuts split (both sides of each split), for the flash of the next cut event.
  const std::size_t count = particle_count(update);
  if (update.duplicated_from.size() <= count && split_since_cut_.size() < kMaxParticles)
    for (std::size_t i = 0; i < update.duplicated_from.size(); ++i) {
      const auto original = update.duplicated_from[i];
      if (original >= count) continue;
      split_since_cut_.push_back(original);
      split_since_cut_.push_back(static_cast<std::uint32_t>(count - update.duplicated_from.size() + i));
    }
  has_topology_ = true;
  candidate_.reset();
  session_id_ = update.session_id;
  particles_ = particle_count(update);
  columns_ = update.columns;
  rows_ = update.rows;
  grid_ = std::move(update.grid);
  scene_.mesh.topology_version = update.version;
  scene_.mesh.triangles = std::move(update.triangles);
  scene_.mesh.pinned = std::move(update.pinned);
  update_status();
}

std::optional<Rejection> SceneState::on_topology(TopologyUpdate update) {
  if (const auto bad = check(update)) return reject(*bad);
  if (!has_topology_) {
    adopt(std::move(update));  // the first one is taken whatever its version
    return std::nullopt;
  }
  if (update.session_id != session_id_) {
    // A restarted simulator, or a stray publisher: taken once a cloth state of that session confirms it
    // (a restarted simulator publishes one at its first step).
    candidate_ = std::move(update);
    return std::nullopt;
  }
  const std::uint32_t shown = scene_.mesh.topology_version;
  if (update.version < shown) {
    // An older topology arriving late changes nothing, unless the cloth states show it is the real
    // one (the shown one was an implausible jump taken as the first topology).
    candidate_ = std::move(update);
    return std::nullopt;
  }
  if (update.version - shown > kMaxVersionStep) {
    candidate_ = std::move(update);
    return reject(Rejection::VersionJump);
  }
  adopt(std::move(update));
  return std::nullopt;
}

std::optional<Rejection> SceneState::on_state(StateUpdate update) {
  if (const auto bad = check(update)) return reject(*bad);
  if (candidate_ && update.session_id == candidate_->session_id && update.topology_version == candidate_->version &&
      (update.topology_version != scene_.mesh.topology_version || update.session_id != session_id_) &&
      update.positions.size() == particle_count(*candidate_))
    adopt(std::move(*candidate_));
  if (has_topology_) {
    if (update.session_id != session_id_) return reject(Rejection::StaleSession);
    // A state of a topology a cut has already replaced (it was queued behind the cut's delta) is
    // outdated, not bad input: it is dropped without counting as a rejection.
    if (update.topology_version < scene_.mesh.topology_version) {
      ++outdated_states_;
      return std::nullopt;
    }
    // Fewer positions than the shown triangles index would blank part of the cloth; the same version
    // must have exactly its particle count. (More positions: a newer topology is on its way.)
    if (update.positions.size() < particles_ ||
        (update.topology_version == scene_.mesh.topology_version && update.positions.size() != particles_))
      return reject(Rejection::Malformed);
  }
  scene_.mesh.positions = std::move(update.positions);
  positions_version_ = update.topology_version;
  frame_ = update.frame;
  acquired_ns_ = update.acquired_ns;
  scene_.held_particle = update.held_particle;
  ++states_received_;
  update_status();
  return std::nullopt;
}

void SceneState::on_hand(const HandUpdate& update) {
  // Several hand sources (camera, mouse blade) may publish at once: a source that is cutting keeps the
  // mark until its stroke ends, so the others' idle samples do not make it flicker.
  if (hand_cutting_ && update.sensor_id != hand_sensor_ && !update.cutting) return;
  hand_sensor_ = update.sensor_id;
  const bool lost = !update.tracked || !update.position_m.allFinite();
  hand_cutting_ = update.cutting && !lost;
  gate_ = update.gate.empty() ? (update.cutting ? "cutting" : "idle") : update.gate;
  const bool was_lost = !scene_.hand;
  if (lost) {
    scene_.hand.reset();
  } else {
    scene_.hand = Hand{update.position_m, update.cutting ? HandState::Cutting : HandState::Idle, update.outside_cloth};
    if (update.cutting) {
      // A new stroke replaces the trail of the previous one; the last stroke stays visible until then.
      // (sensor, session, stroke id) names a stroke: two sources may both be at their stroke 1.
      if (update.stroke_id != stroke_id_ || update.sensor_id != stroke_sensor_ || update.session_id != stroke_session_)
        scene_.stroke.clear();
      stroke_id_ = update.stroke_id;
      stroke_sensor_ = update.sensor_id;
      stroke_session_ = update.session_id;
      scene_.stroke.push_back(update.position_m);
    }
  }
  if (lost != was_lost) update_status();
}

std::optional<Rejection> SceneState::on_cut(const CutUpdate& update, double now_s) {
  if (has_topology_ && update.session_id != session_id_) return reject(Rejection::StaleSession);
  pieces_ = update.pieces;
  fallen_ = update.fallen_pieces;
  // Every particle at a grid coordinate of the cut line flashes (both sides of the cut share it).
  const std::unordered_set<std::uint32_t> line(update.cut_line.begin(), update.cut_line.end());
  scene_.cut_particles.clear();
  for (std::size_t i = 0; i < grid_.size(); ++i)
    if (line.count(grid_[i]) != 0) scene_.cut_particles.push_back(static_cast<std::uint32_t>(i));
  // Exact cuts follow the stroke's own path and report no grid line: flash what they split instead.
  if (scene_.cut_particles.empty()) scene_.cut_particles = split_since_cut_;
  split_since_cut_.clear();
  cut_time_s_ = now_s;
  scene_.flash = scene_.cut_particles.empty() ? 0.0f : 1.0f;
  return std::nullopt;
}

void SceneState::advance(double now_s) {
  if (scene_.flash <= 0.0f) return;
  scene_.flash = static_cast<float>(std::clamp(1.0 - (now_s - cut_time_s_) / kFlashSeconds, 0.0, 1.0));
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
