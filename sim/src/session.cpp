#include "tachi/sim/session.hpp"

#include "tachi/sim/pieces.hpp"

namespace tachi::sim {

Session::Session(const SessionOptions& options)
    : cloth_(options.cloth), solver_(options.solver), cutter_(cloth_, options.stroke), hand_radius_m_(options.hand_radius_m) {}

void Session::absorb(const TopologyChange& change) {
  if (change.empty()) return;
  if (pending_) {
    pending_->merge(change);
  } else {
    pending_ = change;
  }
}

void Session::close_stroke() {
  if (!cutter_.stroke_open()) return;
  absorb(cutter_.end_stroke());
  const Pieces pieces = find_pieces(cloth_);
  reports_.push_back({stroke_id_, cutter_.report(), pieces.count(), pieces.fallen(), stroke_sensor_});
}

void Session::on_hand(const HandInput& hand) {
  const bool same_source = hand.sensor_id == stroke_sensor_ && hand.session_id == stroke_session_;
  if (cutter_.stroke_open()) {
    if (!same_source && time_s() - stroke_heard_s_ < kSilentSource_s) return;
    if (same_source) stroke_heard_s_ = time_s();
  }
  // The gate's verdict holds whether or not the hand is seen: it usually closes a stroke on samples
  // of a hand that has just been lost.
  const bool idle = !hand.cutting && !hand.holding;
  if (idle) close_stroke();
  const bool seen = hand.tracked && hand.position_m.allFinite();
  if (!seen || hand.holding) {
    hand_.reset();  // neither cutting nor pushing the cloth
    return;
  }
  if (idle) {
    hand_ = hand.position_m;
    return;
  }
  hand_.reset();
  if (cutter_.stroke_open() && (hand.stroke_id != stroke_id_ || !same_source)) close_stroke();
  if (!cutter_.stroke_open()) {
    stroke_id_ = hand.stroke_id;
    stroke_sensor_ = hand.sensor_id;
    stroke_session_ = hand.session_id;
    stroke_heard_s_ = time_s();
    absorb(cutter_.begin_stroke());
  }
  absorb(cutter_.add_sample({hand.time_s, hand.position_m}));
}

void Session::end_stroke() { close_stroke(); }

void Session::step() {
  Colliders colliders;
  if (hand_ && hand_radius_m_ > 0.0F) colliders.spheres.push_back({*hand_, hand_radius_m_});
  solver_.step(cloth_, colliders);
  ++steps_;
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
