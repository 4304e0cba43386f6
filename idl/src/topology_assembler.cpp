#include "tachi/bus/topology_assembler.hpp"

#include <algorithm>

namespace tachi::bus {

namespace {
/// Deltas kept aside while one is missing; beyond this the reader just waits for the next keyframe.
constexpr std::size_t kMaxPending = 256;
}  // namespace

bool TopologyAssembler::on_keyframe(const tachi_msg_ClothTopology& msg) {
  const bool same_session = has_topology_ && msg.session_id == session_id_;
  if (same_session && msg.version <= version_) return false;  // not newer than what the deltas built
  has_topology_ = true;
  session_id_ = msg.session_id;
  version_ = msg.version;
  triangles_.clear();
  where_.clear();
  for (std::uint32_t i = 0; i + 2 < msg.triangles._length; i += 3) {
    add_triangle({msg.triangles._buffer[i], msg.triangles._buffer[i + 1], msg.triangles._buffer[i + 2]});
  }
  grid_.assign(msg.particle_grid._buffer, msg.particle_grid._buffer + msg.particle_grid._length);
  pinned_.assign(msg.pinned._buffer, msg.pinned._buffer + msg.pinned._length);
  pinned_.resize(grid_.size(), 0);
  columns_ = msg.columns;
  rows_ = msg.rows;
  duplicated_since_.clear();
  // Kept-aside deltas of another session or already covered by the keyframe are of no use any more.
  std::erase_if(pending_, [&](const Delta& d) { return d.session_id != session_id_ || d.base_version < version_; });
  drain_pending();
  return true;
}

bool TopologyAssembler::on_delta(const tachi_msg_ClothTopologyDelta& msg) {
  Delta d{msg.session_id, msg.base_version, msg.version, {}, {}, {}, {}, {}};
  d.grid.assign(msg.new_particle_grid._buffer, msg.new_particle_grid._buffer + msg.new_particle_grid._length);
  d.pinned.assign(msg.new_particle_pinned._buffer, msg.new_particle_pinned._buffer + msg.new_particle_pinned._length);
  d.removed.assign(msg.removed_triangles._buffer, msg.removed_triangles._buffer + msg.removed_triangles._length);
  d.added.assign(msg.added_triangles._buffer, msg.added_triangles._buffer + msg.added_triangles._length);
  d.duplicated_from.assign(msg.duplicated_from._buffer, msg.duplicated_from._buffer + msg.duplicated_from._length);
  if (!has_topology_ || msg.session_id != session_id_ || msg.base_version > version_) {
    // Not applicable yet: before the first keyframe, of a session not seen yet, or after a missed delta.
    if (pending_.size() >= kMaxPending) pending_.erase(pending_.begin());
    pending_.push_back(std::move(d));
    return false;
  }
  if (msg.base_version < version_) {
    ++dropped_;  // already in the topology held (a keyframe overtook it)
    return false;
  }
  apply(d);
  drain_pending();
  return true;
}

void TopologyAssembler::apply(const Delta& delta) {
  // Split-off particles of the deltas since the last take, as long as they stay the last particles.
  if (delta.duplicated_from.size() == delta.grid.size()) {
    duplicated_since_.insert(duplicated_since_.end(), delta.duplicated_from.begin(), delta.duplicated_from.end());
  } else {
    duplicated_since_.clear();
  }
  grid_.insert(grid_.end(), delta.grid.begin(), delta.grid.end());
  pinned_.insert(pinned_.end(), delta.pinned.begin(), delta.pinned.end());
  pinned_.resize(grid_.size(), 0);
  for (std::size_t i = 0; i + 2 < delta.removed.size(); i += 3) {
    remove_triangle({delta.removed[i], delta.removed[i + 1], delta.removed[i + 2]});
  }
  for (std::size_t i = 0; i + 2 < delta.added.size(); i += 3) {
    add_triangle({delta.added[i], delta.added[i + 1], delta.added[i + 2]});
  }
  version_ = delta.version;
  ++applied_;
}

void TopologyAssembler::drain_pending() {
  for (bool progress = true; progress;) {
    progress = false;
    for (auto it = pending_.begin(); it != pending_.end(); ++it) {
      if (it->session_id != session_id_ || it->base_version != version_) continue;
      const Delta d = std::move(*it);
      pending_.erase(it);
      apply(d);
      progress = true;
      break;
    }
  }
  std::erase_if(pending_, [&](const Delta& d) {
    const bool stale = d.session_id == session_id_ && d.base_version < version_;
    dropped_ += stale ? 1 : 0;
    return stale;
  });
}

void TopologyAssembler::add_triangle(const std::array<std::uint32_t, 3>& t) {
  if (where_.count(t) != 0) return;
  where_.emplace(t, triangles_.size());
  triangles_.push_back(t);
}

void TopologyAssembler::remove_triangle(const std::array<std::uint32_t, 3>& t) {
  const auto it = where_.find(t);
  if (it == where_.end()) return;
  const std::size_t at = it->second;
  where_.erase(it);
  if (at + 1 != triangles_.size()) {
    triangles_[at] = triangles_.back();
    where_[triangles_[at]] = at;
  }
  triangles_.pop_back();
}

}  // namespace tachi::bus
