// Assembles the scene to draw from the updates the pipeline publishes (topology, positions,
// hand strokes, cut events), in the viewer's own types; the DDS conversion is in the executable's
// adapter.
// Robust input: a topology or state that is malformed (wrong sizes, indices out of range,
// non-finite or absurd coordinates) or whose version jumps implausibly is rejected and counted by
// reason, and the scene keeps showing the last good cloth. A simulator restart (a topology from a
// new session, confirmed by a cloth state of that session) is followed.
#pragma once

#include "tachi/viewer/render.hpp"

#include <cstdint>
#include <map>
#include <string>

namespace tachi::viewer {

struct TopologyUpdate {
  std::uint32_t version = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint8_t> pinned;
  std::uint64_t session_id = 0;
  int columns = 0;  ///< grid of the uncut cloth (0: unknown)
  int rows = 0;
  /// (u, v) of each particle, packed as u | v << 16; its size is the particle count (may be empty:
  /// then the highest triangle index tells it).
  std::vector<std::uint32_t> grid;
  bool malformed = false;  ///< the message's arrays did not fit together (e.g. triangles not in threes)
  /// The change list: the last duplicated_from.size() particles were split off duplicated_from[i] by
  /// cuts since the previous publication (exact cuts report no grid line: these show where they were).
  std::vector<std::uint32_t> duplicated_from;
};

struct StateUpdate {
  std::uint64_t frame = 0;
  std::uint32_t topology_version = 0;
  std::vector<Eigen::Vector3f> positions;
  std::uint64_t session_id = 0;
  std::int64_t acquired_ns = 0;  ///< wall clock of the newest hand sample it reflects (0: none)
  int held_particle = -1;
  bool malformed = false;  ///< positions not in threes
};

struct HandUpdate {
  std::uint32_t stroke_id = 0;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  bool tracked = false;
  bool cutting = false;
  bool outside_cloth = false;
  std::uint32_t sensor_id = 0;
  std::uint64_t session_id = 0;
  std::string gate;  ///< for the HUD, e.g. "cutting (mouse)"
};

struct CutUpdate {
  std::uint32_t stroke_id = 0;
  std::uint32_t topology_version = 0;
  std::vector<std::uint32_t> cut_line;  ///< grid coordinates packed as u | v << 16
  std::uint32_t pieces = 0;
  std::uint32_t fallen_pieces = 0;
  std::uint64_t session_id = 0;
  std::uint32_t sensor_id = 0;
};

/// Why an input was rejected: the heartbeat's "rejected.<reason>".
enum class Rejection { Malformed, OutOfRange, NonFinite, VersionJump, StaleSession };
std::string_view to_string(Rejection reason);

class SceneState {
 public:
  /// A topology more than this many versions ahead of the shown one (same session) is implausible:
  /// it is set aside until a cloth state with that version and its particle count confirms it.
  static constexpr std::uint32_t kMaxVersionStep = 256;
  /// Coordinates beyond this are garbage, not cloth (a piece in free fall takes days to get there).
  static constexpr float kMaxCoordinate_m = 1e12f;
  /// More particles than this is not a cloth this viewer can draw.
  static constexpr std::size_t kMaxParticles = 1u << 22;
  /// How long a new cut flashes.
  static constexpr double kFlashSeconds = 1.5;

  SceneState() { update_status(); }
  /// Each returns the reason when the update was rejected (then the scene did not change).
  std::optional<Rejection> on_topology(TopologyUpdate update);
  std::optional<Rejection> on_state(StateUpdate update);
  void on_hand(const HandUpdate& update);
  std::optional<Rejection> on_cut(const CutUpdate& update, double now_s);
  /// States of a topology that a newer one (a cut's) had already replaced when they came: dropped.
  [[nodiscard]] std::uint64_t outdated_states() const { return outdated_states_; }
  /// Fades the cut flash; call before drawing a frame.
  void advance(double now_s);

  /// The scene as it stands; the status line says what is missing or stale. Kept up to date by the
  /// updates, so drawing a frame copies nothing.
  const Scene& scene() const { return scene_; }
  /// For the window and the HUD (the viewer's own figures and the blade cursor live here too).
  Scene& scene() { return scene_; }
  bool has_cloth() const { return !scene_.mesh.positions.empty() && !scene_.mesh.triangles.empty(); }
  std::uint64_t states_received() const { return states_received_; }
  std::uint64_t rejected() const { return rejected_total_; }
  const std::map<std::string, std::uint64_t, std::less<>>& rejected_by_reason() const { return rejected_; }
  /// acquired_ns of the shown state (0: none or not set).
  std::int64_t shown_acquired_ns() const { return acquired_ns_; }
  std::uint64_t session_id() const { return session_id_; }
  int columns() const { return columns_; }
  int rows() const { return rows_; }
  std::optional<std::uint32_t> pieces() const { return pieces_; }
  std::optional<std::uint32_t> fallen_pieces() const { return fallen_; }
  const std::string& gate() const { return gate_; }

 private:
  Rejection reject(Rejection reason);
  void adopt(TopologyUpdate update);  // by value: it may be candidate_, which it resets
  void update_status();

  Scene scene_;
  std::size_t particles_ = 0;  ///< particle count of the shown topology
  int columns_ = 0, rows_ = 0;
  std::vector<std::uint32_t> grid_;
  std::uint64_t session_id_ = 0;
  bool has_topology_ = false;
  std::optional<TopologyUpdate> candidate_;  ///< an implausible version jump awaiting confirmation
  std::uint32_t positions_version_ = 0;
  std::uint64_t frame_ = 0;
  std::uint64_t states_received_ = 0;
  std::uint64_t outdated_states_ = 0;
  std::int64_t acquired_ns_ = 0;
  // The hand mark and the trail: a source that is cutting keeps the mark until its stroke ends.
  std::uint32_t hand_sensor_ = 0;
  bool hand_cutting_ = false;
  std::uint32_t stroke_sensor_ = 0;
  std::uint64_t stroke_session_ = 0;
  std::uint32_t stroke_id_ = 0;
  std::string gate_ = "-";
  std::optional<std::uint32_t> pieces_, fallen_;
  std::vector<std::uint32_t> split_since_cut_;  ///< particles cuts split since the last cut event
  double cut_time_s_ = 0.0;
  std::uint64_t rejected_total_ = 0;
  std::map<std::string, std::uint64_t, std::less<>> rejected_;
};

}  // namespace tachi::viewer
