#include "tachi/common/hand_speed.hpp"

namespace tachi::common {

bool HandSpeedLimit::reachable(const std::pair<Eigen::Vector3f, std::int64_t>& from, const Eigen::Vector3f& to,
                               std::int64_t stamp_ns) const {
  const double elapsed = static_cast<double>(stamp_ns - from.second) * 1e-9;
  // Samples that carry the same (or an older) time count one nominal frame apart.
  const double dt = elapsed > 0.0 ? elapsed : nominal_dt_s_;
  return static_cast<double>((to - from.first).norm()) <= static_cast<double>(params_.max_hand_speed_mps) * dt;
}

HandSpeedLimit::Verdict HandSpeedLimit::check(const Eigen::Vector3f& world_m, std::int64_t stamp_ns) {
  if (params_.max_hand_speed_mps <= 0.0F || !accepted_ || reachable(*accepted_, world_m, stamp_ns)) {
    accepted_ = {world_m, stamp_ns};
    refused_.reset();
    run_ = 0;
    return Verdict::Accepted;
  }
  run_ = refused_ && reachable(*refused_, world_m, stamp_ns) ? run_ + 1 : 1;
  refused_ = {world_m, stamp_ns};
  if (run_ >= params_.reanchor_samples) {
    accepted_ = refused_;
    refused_.reset();
    run_ = 0;
    return Verdict::Reanchored;
  }
  ++outliers_;
  return Verdict::Outlier;
}

}  // namespace tachi::common
