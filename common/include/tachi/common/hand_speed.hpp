// Impossible hand samples: one rule for the filter (live hand samples, filter/stroke_filter.cpp) and the
// simulator (stroke CSVs: tachi-sim --stroke, sim/stroke.cpp). A hand does not move faster than ~10 m/s:
// a fast swipe is 3-5 m/s, and the fastest human arm motions (a baseball pitch's hand) reach ~20 m/s only at full throw,
// never while cutting in front of a sensor. A sample whose implied speed from the last accepted
// sample, in world metres, exceeds `max_hand_speed_mps` is an outlier: counted, never smoothed into the
// trajectory and never cut along (the filter publishes it as a sample without a hand, so the stroke
// neither jumps to it nor back). The allowed distance grows with the time since the last accepted
// sample, so a hand lost and found elsewhere is accepted once it could have got there; and
// `reanchor_samples` consecutive outliers that agree with each other (each within the speed limit of
// the one before) mean the reference was the wrong one (or the hand really is there now): the last of
// them is accepted and the smoother restarts from it.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <utility>

namespace tachi::common {

struct OutlierParams {
  float max_hand_speed_mps = 10.0F;  ///< world metres per second; 0 disables
  int reanchor_samples = 3;
};

class HandSpeedLimit {
 public:
  enum class Verdict { Accepted, Outlier, Reanchored };
  explicit HandSpeedLimit(const OutlierParams& params, double nominal_dt_s) : params_(params), nominal_dt_s_(nominal_dt_s) {}
  /// A tracked sample's world position and time.
  Verdict check(const Eigen::Vector3f& world_m, std::int64_t stamp_ns);
  std::uint64_t outliers() const noexcept { return outliers_; }

 private:
  bool reachable(const std::pair<Eigen::Vector3f, std::int64_t>& from, const Eigen::Vector3f& to, std::int64_t stamp_ns) const;

  OutlierParams params_;
  double nominal_dt_s_;
  std::optional<std::pair<Eigen::Vector3f, std::int64_t>> accepted_;  ///< last accepted sample
  std::optional<std::pair<Eigen::Vector3f, std::int64_t>> refused_;   ///< last outlier of the current run
  int run_ = 0;                                                        ///< consecutive consistent outliers
  std::uint64_t outliers_ = 0;
};

}  // namespace tachi::common
