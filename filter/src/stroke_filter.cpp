#include "tachi/filter/stroke_filter.hpp"

namespace tachi::filter {

StrokeFilter::StrokeFilter(const FilterConfig& config)
    : config_(config), smoother_(config.smoother), gate_(config.gate) {}

void StrokeFilter::on_cloth_state(std::span<const float> xyz) {
  cloth_xyz_.assign(xyz.begin(), xyz.end());
  have_cloth_ = !cloth_xyz_.empty();
}

StrokeSample StrokeFilter::on_hand(const HandSample& hand) {
  StrokeSample out;
  out.frame = hand.frame;
  out.stamp_ns = hand.stamp_ns;
  out.tracked = hand.tracked && hand.position_m.allFinite();
  std::optional<float> distance;
  if (out.tracked) {
    last_camera_ = smoother_.filter(hand.position_m, hand.stamp_ns);
    have_last_ = true;
    out.camera_position_m = last_camera_;
    out.position_m = config_.workspace.to_world(last_camera_);
    std::optional<Proximity> near;
    if (have_cloth_) near = proximity_to_particles(out.position_m, cloth_xyz_, config_.cloth);
    if (!near) near = proximity_to_rest_cloth(out.position_m, config_.cloth);
    distance = near->distance_m;
    out.distance_to_cloth_m = near->distance_m;
    out.hand_outside_cloth = near->outside;
  } else {
    // A lost hand restarts the smoother: the next sighting may be far from the last one.
    // The position stays where the hand was last seen (tracked = false says it is stale).
    smoother_.reset();
    out.camera_position_m = have_last_ ? last_camera_ : Eigen::Vector3f::Zero();
    out.position_m = config_.workspace.to_world(out.camera_position_m);
    out.distance_to_cloth_m = -1.0F;  // unknown
  }
  const GateStatus& g = gate_.on_sample(distance);
  out.gate = g.output;
  out.stroke_id = g.stroke_id;
  out.opened_by = g.opened_by;
  out.closed_by = g.closed_by;
  return out;
}

}  // namespace tachi::filter
