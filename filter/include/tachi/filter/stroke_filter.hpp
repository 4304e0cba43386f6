// The filter stage: raw hand samples in, stroke samples out (one per hand sample).
// Smooths in the camera frame (so the smoother's parameters are sensor metres), maps to the cloth's
// world frame, measures the distance to the cloth and runs the gate. Pure: no DDS, no I/O.
#pragma once

#include "tachi/filter/cloth_proximity.hpp"
#include "tachi/filter/config.hpp"
#include "tachi/filter/gate.hpp"
#include "tachi/filter/smoothing.hpp"
#include "tachi/filter/stroke_outliers.hpp"
#include "tachi/filter/types.hpp"

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tachi::filter {

class StrokeFilter {
 public:
  explicit StrokeFilter(const FilterConfig& config);

  /// A voice command; it takes effect before the next hand sample. Returns why a grab was refused.
  std::optional<std::string> on_voice(VoiceCommandKind command) { return gate_.on_voice(command); }
  /// The newest cloth positions (x, y, z per particle, world frame); replaces the rest cloth.
  void on_cloth_state(std::span<const float> xyz);
  /// One hand sample in, one stroke sample out.
  StrokeSample on_hand(const HandSample& hand) { return apply(hand, std::nullopt); }
  /// The same with the hand-to-cloth proximity given instead of measured: a journal's replay, where
  /// the cloth of the time is gone (journal.hpp). Only its distance and `outside` are used.
  StrokeSample on_hand(const HandSample& hand, const Proximity& measured_then) { return apply(hand, measured_then); }

  const Gate& gate() const noexcept { return gate_; }
  /// Hand samples refused as impossibly fast (stroke_outliers.hpp), since the start.
  std::uint64_t outliers() const noexcept { return speed_limit_.outliers(); }

 private:
  StrokeSample apply(const HandSample& hand, const std::optional<Proximity>& given);

  FilterConfig config_;
  Smoother smoother_;
  HandSpeedLimit speed_limit_;
  Gate gate_;
  std::vector<float> cloth_xyz_;
  bool have_cloth_ = false;
  Eigen::Vector3f last_camera_ = Eigen::Vector3f::Zero();
  bool have_last_ = false;
  // The previous tracked sample's world z and time, for the hand's speed along the cloth's normal.
  std::optional<std::pair<float, std::int64_t>> previous_normal_;
};

}  // namespace tachi::filter
