// The live simulator's logic without the bus: gated hand samples from the filter open, extend and
// close strokes on the StrokeCutter; the cloth steps at a fixed rate; topology changes accumulate
// until the caller publishes them, and each closed stroke yields a cut report.
// The same Cloth/Solver/StrokeCutter serve tachi-sim --offline; this adds only the gate handling.
#pragma once

#include "tachi/sim/blade_contact.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cloth_solver.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/grab.hpp"
#include "tachi/sim/material.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
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
  bool grabbing = false;  ///< the hand holds the cloth (GATE_GRABBING): take, move, and on the next other sample release
};

/// What one stroke did, reported when it closes.
struct CutReport {
  std::uint32_t stroke_id = 0;
  StrokeReport stroke;
  std::size_t pieces = 0;         ///< pieces of cloth after it (Pieces::cloth_count: loose particles apart)
  std::size_t fallen_pieces = 0;  ///< of them, those nothing pins
  std::uint32_t sensor_id = 0;  ///< the hand source that made the stroke
  float max_contact_force_n = 0.0F;  ///< largest blade contact force of the stroke (blade_contact.hpp)
  float drag_m = 0.0F;               ///< farthest the blade dragged the cloth before it cut (or without cutting)
};

struct SessionOptions {
  ClothConfig cloth;
  SolverParams solver;
  SolverKind solver_kind = SolverKind::Pbd;
  ProvotParams provot;  ///< used when solver_kind is Provot
  Material material;    ///< the cloth's springs for the blade's contact force (and the Provot solver)
  StrokeOptions stroke;
  /// Sharpness force of the blade, N (seed 001 Figure 4); nothing: the middle of stroke.blade's range.
  std::optional<float> blade_force_n;
  float blade_reach_m = 0.06F;  ///< the blade meets the cloth within this distance of a particle
  float grab_reach_m = 0.10F;   ///< a grab takes the nearest particle within this distance of the hand
  std::shared_ptr<const PointCloudCollider> object;  ///< an object to drape over (seed 000), or null
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
  /// A CUTTING sample cuts only once the blade is through the cloth (BladeContact): until its contact
  /// force reaches the sharpness force the blade holds and drags the particle it met. A GRABBING sample
  /// takes the nearest particle within grab reach and moves it to the hand; any other sample releases
  /// it. A grab while a stroke is open is refused (one hand, one tool): take_grab_refusal() says why.
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

  /// Why the last grab was refused, once per refused grab; nothing when none was.
  std::optional<std::string> take_grab_refusal();

  [[nodiscard]] const Cloth& cloth() const { return cloth_; }
  /// The cloth before the first step, to set its initial shape (e.g. the offline driver's jitter).
  [[nodiscard]] Cloth& cloth_for_setup() { return cloth_; }
  /// Fixed shape colliders (spheres, ground) present in every step, besides the hand and the object.
  void set_shapes(std::vector<Sphere> spheres, std::optional<GroundPlane> ground);
  [[nodiscard]] const StrokeCutter& cutter() const { return cutter_; }
  [[nodiscard]] SolverKind solver_kind() const { return solver_.kind(); }
  [[nodiscard]] const PointCloudCollider* object() const { return object_.get(); }
  /// Over every stroke so far: farthest blade drag, largest blade contact force.
  [[nodiscard]] float max_drag_m() const { return max_drag_m_; }
  [[nodiscard]] float max_contact_force_n() const { return max_contact_force_n_; }
  [[nodiscard]] const BladeContact& blade() const { return blade_; }
  /// The particle the hand holds (grab), if any.
  [[nodiscard]] std::optional<std::uint32_t> held_particle() const { return grab_.held(); }
  [[nodiscard]] std::uint64_t steps() const { return steps_; }
  /// Steps that ended with the tethers' work after a cut still going on (the cut's work and the repair,
  /// SolverParams::cut_work_per_step, repair_per_step and repair_share): how far their budgets spread it.
  [[nodiscard]] std::uint64_t repair_steps() const { return repair_steps_; }
  /// Strokes the cloth received (opened by a cutting sample), whatever their source: the hand's
  /// filter or the viewer's mouse blade.
  [[nodiscard]] std::uint64_t strokes() const { return strokes_; }
  /// Strokes that cut the cloth (split particles or cut length), the stroke still open included: a
  /// stroke whose blade never reached the cloth is no cut.
  [[nodiscard]] std::uint64_t cuts() const;
  [[nodiscard]] double time_s() const { return static_cast<double>(steps_) * solver_.dt(); }

 private:
  void absorb(const TopologyChange& change);
  void close_stroke();
  /// Applies a GRABBING sample; false when the grab was refused.
  void on_grab(const HandInput& hand, bool seen);

  Cloth cloth_;
  ClothSolver solver_;
  StrokeCutter cutter_;
  BladeContact blade_;
  Grab grab_;
  std::shared_ptr<const PointCloudCollider> object_;
  std::vector<Sphere> spheres_;
  std::optional<GroundPlane> ground_;
  float max_drag_m_ = 0.0F;
  float max_contact_force_n_ = 0.0F;
  float grab_reach_m_;
  std::optional<double> last_grab_time_;
  bool grab_refused_ = false;  ///< the current grab was refused (reported once)
  std::optional<std::string> grab_refusal_;
  bool stroke_active_ = false;  ///< a cutting stroke is open (the blade may not be through yet)
  std::optional<StrokeSample> approach_;  ///< the stroke's previous sample, for the cut to start where the blade met the cloth
  /// Where the blade met the cloth, located when it met it: the blade then drags the cloth along, and the
  /// approach sample located on the dragged cloth lies behind that point by the drag (0.36 cell at the median).
  std::optional<ClothPoint> contact_;
  float hand_radius_m_;
  std::optional<Eigen::Vector3f> hand_;  ///< last tracked hand position while not cutting
  std::uint32_t stroke_id_ = 0;
  std::uint64_t stroke_session_ = 0;
  std::uint32_t stroke_sensor_ = 0;     ///< source of the open stroke
  double stroke_heard_s_ = 0.0;         ///< time_s() of that source's last sample
  std::optional<TopologyChange> pending_;
  std::vector<CutReport> reports_;
  std::uint64_t steps_ = 0;
  std::uint64_t repair_steps_ = 0;
  std::uint64_t strokes_ = 0;
  std::uint64_t closed_cuts_ = 0;  ///< closed strokes that cut
};

}  // namespace tachi::sim
