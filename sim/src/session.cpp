#include "tachi/sim/session.hpp"

#include "tachi/sim/pieces.hpp"

#include <algorithm>
#include <cstdio>

namespace tachi::sim {

namespace {

BladeContactParams blade_params(const SessionOptions& options) {
  BladeContactParams p;
  p.force_n = options.blade_force_n.value_or(sharpness(options.stroke.blade).force_n());
  p.reach_m = options.blade_reach_m;
  const float spacing_x = options.cloth.width_m / static_cast<float>(std::max(options.cloth.columns - 1, 1));
  const float spacing_y = options.cloth.height_m / static_cast<float>(std::max(options.cloth.rows - 1, 1));
  p.stiffness = spring_stiffness(options.material, spacing_x, spacing_y);
  return p;
}

/// The cutter's own blade drag (a velocity kick scaled by the blade's force, blade.hpp) is off here: in a
/// session the blade's contact drags the cloth itself (BladeContact), and both would count it twice.
StrokeOptions cutter_options(const SessionOptions& options) {
  StrokeOptions s = options.stroke;
  s.drag.gain_mps_per_n = 0.0F;
  if (s.grid_hysteresis_cells <= 0.0) s.grid_hysteresis_cells = kGridHysteresisCells;
  return s;
}

ProvotParams provot_params(const SessionOptions& options) {
  ProvotParams p = options.provot;
  p.dt = options.solver.dt;
  p.gravity = options.solver.gravity;
  p.material = options.material;
  return p;
}

}  // namespace

Session::Session(const SessionOptions& options)
    : cloth_(options.cloth),
      solver_(options.solver_kind, options.solver, provot_params(options)),
      cutter_(cloth_, cutter_options(options)),
      blade_(blade_params(options)),
      object_(options.object),
      grab_reach_m_(options.grab_reach_m),
      hand_radius_m_(options.hand_radius_m) {
  // The caches are built now, after the cutter reserved the cloth's room for cuts, not in the first step: a
  // live run's first frame would otherwise stall for several frames (70-80 ms at 128 x 128).
  solver_.prepare(cloth_);
}

void Session::absorb(const TopologyChange& change) {
  if (change.empty()) return;
  if (pending_) {
    pending_->merge(change);
  } else {
    pending_ = change;
  }
}

namespace {
bool cut_something(const StrokeReport& report) { return report.particles_duplicated > 0 || report.cut_length_m > 0.0F; }
}  // namespace

std::uint64_t Session::cuts() const {
  return closed_cuts_ + (stroke_active_ && cut_something(cutter_.report()) ? 1 : 0);
}

void Session::close_stroke() {
  if (!stroke_active_) return;
  stroke_active_ = false;
  approach_.reset();
  contact_.reset();
  absorb(cutter_.end_stroke());
  if (cut_something(cutter_.report())) ++closed_cuts_;
  const Pieces pieces = find_pieces(cloth_);
  reports_.push_back(
      {stroke_id_, cutter_.report(), pieces.cloth_count(), pieces.cloth_fallen(), stroke_sensor_, blade_.max_force_n(), blade_.drag_m()});
  max_drag_m_ = std::max(max_drag_m_, blade_.drag_m());
  max_contact_force_n_ = std::max(max_contact_force_n_, blade_.max_force_n());
  blade_.end_stroke(cloth_);
}

void Session::on_grab(const HandInput& hand, bool seen) {
  hand_.reset();
  if (stroke_active_) {
    if (!grab_refused_) {
      grab_refused_ = true;
      grab_refusal_ = "grab refused: stroke " + std::to_string(stroke_id_) + " is cutting (one hand, one tool)";
    }
    return;
  }
  if (!seen) return;  // a held particle stays where the hand was last seen
  if (!grab_.held()) {
    last_grab_time_.reset();
    if (!grab_.grab(cloth_, hand.position_m, grab_reach_m_)) {
      if (!grab_refused_) {
        grab_refused_ = true;
        char why[96];
        std::snprintf(why, sizeof why, "grab refused: no cloth within %.3f m of the hand", static_cast<double>(grab_reach_m_));
        grab_refusal_ = why;
      }
      return;
    }
  }
  const float dt = last_grab_time_ ? static_cast<float>(hand.time_s - *last_grab_time_) : 0.0F;
  grab_.move(cloth_, hand.position_m, dt);
  last_grab_time_ = hand.time_s;
}

void Session::on_hand(const HandInput& hand) {
  const bool same_source = hand.sensor_id == stroke_sensor_ && hand.session_id == stroke_session_;
  if (stroke_active_) {
    if (!same_source && time_s() - stroke_heard_s_ < kSilentSource_s) return;
    if (same_source) stroke_heard_s_ = time_s();
  }
  const bool seen = hand.tracked && hand.position_m.allFinite();
  if (hand.grabbing) {
    on_grab(hand, seen);
    return;
  }
  // Any other sample lets go of what the hand held.
  grab_.release(cloth_);
  grab_refused_ = false;
  // The gate's verdict holds whether or not the hand is seen: it usually closes a stroke on samples
  // of a hand that has just been lost.
  const bool idle = !hand.cutting && !hand.holding;
  if (idle) close_stroke();
  if (!seen || hand.holding) {
    hand_.reset();  // neither cutting nor pushing the cloth
    blade_.let_go(cloth_);
    return;
  }
  if (idle) {
    hand_ = hand.position_m;
    return;
  }
  hand_.reset();
  if (stroke_active_ && (hand.stroke_id != stroke_id_ || hand.session_id != stroke_session_)) close_stroke();
  if (!stroke_active_) {
    stroke_id_ = hand.stroke_id;
    stroke_sensor_ = hand.sensor_id;
    stroke_session_ = hand.session_id;
    stroke_active_ = true;
    ++strokes_;
    absorb(cutter_.begin_stroke());
  }
  const StrokeSample sample{hand.time_s, hand.position_m};
  const bool had_cut = blade_.has_cut();
  const bool held = blade_.held().has_value();
  const BladeContact::Verdict verdict = blade_.press(cloth_, hand.position_m);
  if (verdict == BladeContact::Verdict::Away) {
    // Not touching the cloth (beyond the blade's reach): the stroke goes on as the gate says, so the cutter
    // sees where it came from (a stroke entering across an edge is clipped there); it cuts nothing here.
    absorb(cutter_.add_sample(sample, false));
    approach_.reset();
    contact_.reset();
    return;
  }
  if (verdict == BladeContact::Verdict::Pushing) {
    approach_ = sample;  // the blade drags the cloth, it does not cut
    // The blade has just met the cloth: the point it met is located now, before it drags the cloth along (the
    // press that meets a particle holds it where it is). Located later, on the dragged cloth, the approach
    // sample lies behind that point by as far as the cloth was dragged, and the cut began there: 0.36 cell
    // before the stroke's first point at the median, up to 10 (docs/cutting.md, section 8, "Tips").
    if (!held || !contact_) contact_ = cutter_.locate(hand.position_m);
    return;
  }
  // The stroke's first cut starts where the blade met the cloth (the point the blade held while it dragged
  // the cloth); later ones go on from the cut so far (the cutter joins them).
  if (!had_cut && approach_) absorb(contact_ ? cutter_.add_sample(*approach_, *contact_) : cutter_.add_sample(*approach_));
  contact_.reset();
  absorb(cutter_.add_sample(sample));
}

void Session::end_stroke() { close_stroke(); }

std::optional<std::string> Session::take_grab_refusal() {
  auto why = std::move(grab_refusal_);
  grab_refusal_.reset();
  return why;
}

void Session::set_shapes(std::vector<Sphere> spheres, std::optional<GroundPlane> ground) {
  spheres_ = std::move(spheres);
  ground_ = ground;
}

void Session::step() {
  Colliders colliders;
  colliders.spheres = spheres_;
  colliders.ground = ground_;
  if (hand_ && hand_radius_m_ > 0.0F) colliders.spheres.push_back({*hand_, hand_radius_m_});
  colliders.point_cloud = object_.get();
  solver_.step(cloth_, colliders);
  ++steps_;
  if (solver_.repairing()) ++repair_steps_;
}

std::optional<TopologyChange> Session::take_topology_change() {
  auto change = std::move(pending_);
  pending_.reset();
  return change;
}

std::vector<CutReport> Session::take_cut_reports() {
  auto reports = std::move(reports_);
  reports_.clear();
  return reports;
}

}  // namespace tachi::sim
