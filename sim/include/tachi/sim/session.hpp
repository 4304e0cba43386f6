// The live simulator's logic without the bus: gated hand samples from the filter open, extend and
// close strokes on the StrokeCutter; the cloth steps at a fixed rate; topology changes accumulate
// until the caller publishes them, and each closed stroke yields a cut report.
// The same Cloth/Solver/StrokeCutter serve tachi-sim --offline; this adds only the gate handling.
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace tachi::sim {

/// One filtered hand sample with the gate's verdict, in the simulator's terms.
struct HandInput {
  std::uint32_t stroke_id = 0;
  double time_s = 0.0;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  ///< world frame
  bool tracked = false;
  bool cutting = false;
  bool holding = false;  ///< stroke open, hand beyond reach: the sample must not cut (GATE_HOLDING)
  std::uint64_t session_id = 0;  ///< the filter run that numbered the stroke: stroke 1 of a restarted filter is a new stroke
  std::uint32_t sensor_id = 0;   ///< the hand source (camera hand, mouse blade): with session and stroke id, names a stroke
};

/// What one stroke did, reported when it closes.
struct CutReport {
  std::uint32_t stroke_id = 0;
  StrokeReport stroke;
  std::size_t pieces = 0;
  std::size_t fallen_pieces = 0;
  std::uint32_t sensor_id = 0;  ///< the hand source that made the stroke
};

struct SessionOptions {
  ClothConfig cloth;
  SolverParams solver;
  StrokeOptions stroke;
  /// The hand as a collider sphere while it is not cutting (seed 000 section 2: the cloth reacts to
  /// the hand); 0 disables it. While cutting, the blade passes through the cloth.
  float hand_radius_m = 0.0F;
};

class Session {
 public:
  explicit Session(const SessionOptions& options);

  /// Feeds one hand sample. A CUTTING sample opens a stroke (or a new one when the stroke id
  /// changes) and extends it; a HOLDING sample keeps the stroke open without cutting (the hand is
  /// leaving or briefly out of reach); an IDLE sample closes the open stroke, tracked or not (the
  /// filter's gate decides when a lost hand ends a stroke). Untracked or non-finite samples never cut.
  /// Several sources may publish: while one source's stroke is open, the others' samples are ignored
  /// (one blade cuts at a time), unless that source fell silent for kSilentSource_s.
  void on_hand(const HandInput& hand);
  static constexpr double kSilentSource_s = 1.0;
  /// Closes the open stroke, if any (e.g. when the filter vanished mid-stroke).
  void end_stroke();
  /// Advances the cloth by one solver step.
  void step();

  /// Topology changes since the last call (merged), or nothing when the topology did not change.
  std::optional<TopologyChange> take_topology_change();
  /// True when topology changes are waiting for take_topology_change().
  [[nodiscard]] bool topology_changed() const { return pending_.has_value(); }
  /// Reports of strokes closed since the last call.
  std::vector<CutReport> take_cut_reports();

  [[nodiscard]] const Cloth& cloth() const { return cloth_; }
  [[nodiscard]] const StrokeCutter& cutter() const { return cutter_; }
  [[nodiscard]] std::uint64_t steps() const { return steps_; }
  [[nodiscard]] double time_s() const { return static_cast<double>(steps_) * solver_.params().dt; }

 private:
  void absorb(const TopologyChange& change);
  void close_stroke();

  Cloth cloth_;
  Solver solver_;
  StrokeCutter cutter_;
  float hand_radius_m_;
  std::optional<Eigen::Vector3f> hand_;  ///< last tracked hand position while not cutting
  std::uint32_t stroke_id_ = 0;
  std::uint64_t stroke_session_ = 0;
  std::uint32_t stroke_sensor_ = 0;     ///< source of the open stroke
  double stroke_heard_s_ = 0.0;         ///< time_s() of that source's last sample
  std::optional<TopologyChange> pending_;
  std::vector<CutReport> reports_;
  std::uint64_t steps_ = 0;
};

}  // namespace tachi::sim
