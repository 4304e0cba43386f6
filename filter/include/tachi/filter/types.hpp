// The filter's own value types: a raw hand sample from the sensor and the stroke sample it becomes.
// DDS message types never reach this library; main.cpp converts at the edge (bus_adapter).
#pragma once

#include <Eigen/Core>

#include <cstdint>

namespace tachi::filter {

/// One palm-centre measurement in the camera frame (x right, y down, z forward, metres).
struct HandSample {
  std::uint64_t frame = 0;
  std::int64_t stamp_ns = 0;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  ///< meaningful only when tracked
  bool tracked = false;
  float confidence = 0.0F;
};

/// Whether cutting is on. Matches tachi_msg_GateState.
/// Holding: a stroke is open but the hand is out of reach (exit dwell): the sample does not cut, so a
/// hand leaving the cloth never drags the cut with it; the stroke continues if the hand comes back.
/// Grabbing: the hand holds the cloth (voice "grab" until "release"; seed 000 section 2): the simulator
/// moves the particle it took with the hand; nothing is cut.
enum class GateOutput : std::uint8_t { Idle, Cutting, Holding, Grabbing };

/// What opened or closed a stroke. Matches tachi_msg_GateSource.
enum class GateSource : std::uint8_t { None, Threshold, Voice };

/// A voice command as the gate sees it.
enum class VoiceCommandKind : std::uint8_t { Start, Stop, Grab, Release };

/// One output sample: the smoothed hand in the cloth's world frame with the gate's verdict.
struct StrokeSample {
  std::uint64_t frame = 0;
  std::int64_t stamp_ns = 0;
  /// World frame, smoothed. Without a hand (tracked = false): the last position seen.
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  Eigen::Vector3f camera_position_m = Eigen::Vector3f::Zero();  ///< camera frame, smoothed
  bool tracked = false;
  /// The hand sample implied an impossible speed (stroke_outliers.hpp): published as tracked = false.
  bool outlier = false;
  GateOutput gate = GateOutput::Idle;
  std::uint32_t stroke_id = 0;  ///< grows by one each time the gate opens; 0 before the first stroke
  GateSource opened_by = GateSource::None;
  GateSource closed_by = GateSource::None;
  bool hand_outside_cloth = false;
  float distance_to_cloth_m = 0.0F;  ///< -1 without a hand
};

}  // namespace tachi::filter
