// Depth frame -> 3D palm centre of the hand reaching toward the sensor.
//
// The hand is the end of the arm that reaches toward the sensor, not simply the nearest blob:
//  1. segmentation on a 160x120 grid of raw disparity: a per-cell background (the farthest
//     reading seen, so static things - furniture nearer than the hand included - are background
//     and a moving arm reveals what is behind it) gives the foreground (nearer than the background
//     by `foreground_m`); an opening removes the thin strips a swaying body leaves;
//  2. the foreground component is chosen by temporal continuity (the one under the previous hand),
//     else the one reaching nearest; its hand is the part within `hand_depth_band_m` of its
//     nearest point (the arm's far end);
//  3. at full resolution, in that region only: the hand mask (dropouts inside it filled), its
//     distance transform; the palm centre is the distance-transform maximum (the centre of the
//     largest inscribed circle, i.e. the palm), back-projected at the median depth of the palm
//     circle.
// All thresholds are raw-disparity lookups built once from metric parameters.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "tachi/sensor/depth_frame.hpp"
#include "tachi/sensor/depth_model.hpp"

namespace tachi::sensor {

/// Tuning. Metric values are converted to raw-disparity tables at construction.
struct HandFinderParams {
  double foreground_m = 0.08;       ///< nearer than the background by this = foreground (> sway, < arm)
  double hand_depth_band_m = 0.07;  ///< the hand: component pixels within this of its nearest point
  double palm_radius_m = 0.042;     ///< expected palm radius: the palm circle must fit in the image
  double min_palm_radius_m = 0.032; ///< a smaller inscribed circle is a forearm (~2.8 cm) or fingers, not a palm
  double max_palm_radius_m = 0.075; ///< a larger one is a body, not a palm
  int min_component_cells = 10;     ///< on the 160x120 grid
  int edge_margin_px = 3;           ///< the palm circle must clear the image edge by this
  int invalid_left_columns = 8;     ///< Kinect's band without readings at the left edge
  double max_jump_m = 0.2;          ///< a hand lost this many frames ago does not reappear farther away...
  int reacquire_frames = 15;        ///< ... within this many frames (0.5 s at 30 Hz)
};

struct HandObservation {
  bool tracked = false;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  ///< palm centre, camera frame
  float u = 0.0f;                   ///< palm centre pixel (640x480)
  float v = 0.0f;
  float confidence = 0.0f;          ///< 0..1; 0 when not tracked
  float palm_radius_m = 0.0f;       ///< radius of the palm's inscribed circle
};

class HandFinder {
 public:
  explicit HandFinder(const DepthModel& model, const HandFinderParams& params = {});
  ~HandFinder();
  HandFinder(HandFinder&&) noexcept;
  HandFinder& operator=(HandFinder&&) noexcept;

  /// Processes one 640x480 frame of raw disparity (kDepthPixels values). Frames must come in
  /// order: the background and the previous hand carry over. A frame of the wrong size gives an
  /// untracked observation.
  HandObservation find(std::span<const std::uint16_t> raw);
  HandObservation find(const DepthFrame& frame) { return find(frame.raw); }

  /// Forgets the background and the previous hand (e.g. after the sensor moved).
  void reset();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::sensor
