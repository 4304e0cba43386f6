#include "tachi/filter/stroke_filter.hpp"

namespace tachi::filter {

StrokeFilter::StrokeFilter(const FilterConfig& config)
    : config_(config),
      smoother_(config.smoother),
      speed_limit_(config.outliers, 1.0 / config.smoother.nominal_rate_hz),
      gate_(config.gate) {}

void StrokeFilter::on_cloth_state(std::span<const float> xyz) {
  cloth_xyz_.assign(xyz.begin(), xyz.end());
  have_cloth_ = !cloth_xyz_.empty();
}

StrokeSample StrokeFilter::apply(const HandSample& hand, const std::optional<Proximity>& given) {
  StrokeSample out;
  out.frame = hand.frame;
  out.stamp_ns = hand.stamp_ns;
  out.tracked = hand.tracked && hand.position_m.allFinite();
  if (out.tracked) {
    // An impossibly fast sample is published as one without a hand (the simulator neither cuts to it
    // nor from it) but does not restart the smoother: the hand was not lost, the sample was wrong.
    switch (speed_limit_.check(config_.workspace.to_world(hand.position_m), hand.stamp_ns)) {
      case HandSpeedLimit::Verdict::Accepted: break;
      case HandSpeedLimit::Verdict::Outlier:
        out.tracked = false;
        out.outlier = true;
        break;
      case HandSpeedLimit::Verdict::Reanchored: smoother_.reset(); break;
    }
  }
  std::optional<float> distance;
  if (out.tracked) {
    last_camera_ = smoother_.filter(hand.position_m, hand.stamp_ns);
    have_last_ = true;
    out.camera_position_m = last_camera_;
    out.position_m = config_.workspace.to_world(last_camera_);
    std::optional<Proximity> near = given;
    if (!near && have_cloth_) near = proximity_to_particles(out.position_m, cloth_xyz_, config_.cloth);
    if (!near) near = proximity_to_rest_cloth(out.position_m, config_.cloth);
    distance = near->distance_m;
    out.distance_to_cloth_m = near->distance_m;
    out.hand_outside_cloth = near->outside;
  } else {
    // A lost hand restarts the smoother: the next sighting may be far from the last one.
    // The position stays where the hand was last seen (tracked = false says it is stale).
    if (!out.outlier) smoother_.reset();
    out.camera_position_m = have_last_ ? last_camera_ : Eigen::Vector3f::Zero();
    out.position_m = config_.workspace.to_world(out.camera_position_m);
    out.distance_to_cloth_m = -1.0F;  // unknown
  }
  const GateStatus& g = gate_.on_sample(distance);
  out.gate = g.output;
  // Seed 000 sec. 5: at the start and end of a threshold cut the user moves the hand toward or away
  // from the cloth, and those samples made the cut stray (Figs. 6-8). The cloth hangs in z = 0, so
  // world z is its normal: while the hand moves along it too fast, the stroke holds instead of cutting.
  std::optional<float> normal_speed;
  if (out.tracked && previous_normal_ && hand.stamp_ns > previous_normal_->second)
    normal_speed = std::abs(out.position_m.z() - previous_normal_->first) /
                   (static_cast<float>(hand.stamp_ns - previous_normal_->second) * 1e-9F);
  previous_normal_.reset();
  if (out.tracked) previous_normal_ = std::make_pair(out.position_m.z(), hand.stamp_ns);
  const float limit = config_.gate.max_normal_speed_mps;
  if (g.phase == GatePhase::CuttingByThreshold && limit > 0.0F && normal_speed && *normal_speed > limit)
    out.gate = GateOutput::Holding;
  out.stroke_id = g.stroke_id;
  out.opened_by = g.opened_by;
  out.closed_by = g.closed_by;
  return out;
}

}  // namespace tachi::filter
