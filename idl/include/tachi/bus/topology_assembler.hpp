// The cloth's current topology on the reader's side, from a ClothTopology keyframe and the
// ClothTopologyDelta messages since. The one place every reader (viewer, tests, tools) turns the
// simulator's topology messages back into triangles: pure logic over the message types, no DDS calls.
// Rules: a keyframe of a new session, or a newer version of the same session, replaces everything; a delta
// applies when its base_version is the version held; one from the future (a delta was missed) is kept
// aside until the gap is filled or a keyframe catches up; older ones are dropped.
#pragma once

#include "tachi.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace tachi::bus {

class TopologyAssembler {
 public:
  /// A full topology. Returns true when it replaced what was held.
  bool on_keyframe(const tachi_msg_ClothTopology& msg);
  /// A change. Returns true when it (and any kept-aside deltas that follow it) was applied.
  bool on_delta(const tachi_msg_ClothTopologyDelta& msg);

  [[nodiscard]] bool has_topology() const { return has_topology_; }
  /// A delta was missed: waiting for it (kept aside deltas) or for the next keyframe.
  [[nodiscard]] bool waiting_for_keyframe() const { return !pending_.empty(); }
  [[nodiscard]] std::uint64_t session_id() const { return session_id_; }
  [[nodiscard]] std::uint32_t version() const { return version_; }
  /// Live triangles (3 particle indices each), in no particular order.
  [[nodiscard]] const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return triangles_; }
  [[nodiscard]] const std::vector<std::uint8_t>& pinned() const { return pinned_; }
  [[nodiscard]] const std::vector<tachi_msg_GridCoord>& particle_grid() const { return grid_; }
  [[nodiscard]] std::size_t particle_count() const { return grid_.size(); }
  /// Grid of the uncut cloth, from the keyframe.
  [[nodiscard]] int columns() const { return columns_; }
  [[nodiscard]] int rows() const { return rows_; }
  /// Per particle appended by the deltas applied since the last call (the last ones of the particle list):
  /// the particle it was split off. Cleared by the call and by a keyframe.
  std::vector<std::uint32_t> take_duplicated_from() { return std::exchange(duplicated_since_, {}); }
  /// Deltas applied, kept aside, dropped (older than what is held), since construction.
  [[nodiscard]] std::uint64_t applied() const { return applied_; }
  [[nodiscard]] std::uint64_t dropped() const { return dropped_; }

 private:
  /// A delta copied out of its message (messages are loaned and returned after the take).
  struct Delta {
    std::uint64_t session_id;
    std::uint32_t base_version;
    std::uint32_t version;
    std::vector<tachi_msg_GridCoord> grid;
    std::vector<std::uint8_t> pinned;
    std::vector<std::uint32_t> removed;
    std::vector<std::uint32_t> added;
    std::vector<std::uint32_t> duplicated_from;
  };
  struct TriangleHash {
    std::size_t operator()(const std::array<std::uint32_t, 3>& t) const {
      return (static_cast<std::size_t>(t[0]) * 0x9E3779B97F4A7C15ULL) ^ (static_cast<std::size_t>(t[1]) * 0xBF58476D1CE4E5B9ULL) ^
             (static_cast<std::size_t>(t[2]) * 0x94D049BB133111EBULL);
    }
  };
  void apply(const Delta& delta);
  void drain_pending();
  void add_triangle(const std::array<std::uint32_t, 3>& t);
  void remove_triangle(const std::array<std::uint32_t, 3>& t);

  bool has_topology_ = false;
  std::uint64_t session_id_ = 0;
  std::uint32_t version_ = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  std::unordered_map<std::array<std::uint32_t, 3>, std::size_t, TriangleHash> where_;
  std::vector<std::uint8_t> pinned_;
  std::vector<tachi_msg_GridCoord> grid_;
  int columns_ = 0;
  int rows_ = 0;
  std::vector<std::uint32_t> duplicated_since_;
  std::vector<Delta> pending_;
  std::uint64_t applied_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace tachi::bus
